"""Force analysis of a scene: loads sampled on the crank-angle grid, the
kinetostatics kernel, peaks over the revolution and pin sizing."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..kernels.forces import equilibrium_residual, shaking
from ..kernels.inputs import ROTARY


PIN_LENGTH_MM = 10.0       # DOMAIN.md section 5: pin of length 10 mm in bending
PIN_SIGMA_MPA = 200.0      # allowed bending stress


def pin_diameter(r_max, length=PIN_LENGTH_MM, sigma=PIN_SIGMA_MPA):
    """d_min = (32 R_max l / (pi sigma))^(1/3) [mm] for R in N, l in mm, sigma in MPa."""
    return np.cbrt(32.0 * np.asarray(r_max, float) * length / (math.pi * sigma))


def joint_peaks(phi_deg, magnitude, joint_names):
    """Per joint: (name, R_max [N], phi1 at the peak [deg], d_min [mm]) from the
    reaction magnitudes (n_positions, n_joints)."""
    rows = []
    for j, name in enumerate(joint_names):
        col = magnitude[:, j]
        k = int(np.nanargmax(col)) if np.isfinite(col).any() else 0
        rows.append((name, float(col[k]), float(phi_deg[k]), float(pin_diameter(col[k]))))
    return rows


def slide_action(slide):
    """Where the normal force of each prismatic pair acts: e = 1000 C / N [mm],
    its distance from the slider's centre of mass along the slide's direction
    (the guide's N n at S plus the couple C is the one force N n at S + e u,
    u the slide's direction, n = u turned +90 deg).  ``slide`` (..., 2) holds
    (N [N], C [N·m]); NaN where N = 0 (a pure couple has no line of action).

    A slider that bears on its guide at two ends l [mm] apart, centred on S,
    takes N/2 - 1000 C/l and N/2 + 1000 C/l [N] there: both press on the same
    side of the guide while |e| < l/2; beyond that the slider is wedged
    between the guide's two faces (edge loads larger than N, and jamming
    with friction).  The larger end load sizes the slide."""
    slide = np.asarray(slide, float)
    n, c = slide[..., 0], slide[..., 1]
    e = 1000.0 * c / np.where(n != 0.0, n, 1.0) + 0.0     # (+ 0.0: no -0 in tables)
    return np.where(n != 0.0, e, np.nan)


def slide_label(name):
    """The slider's name in a slide's name: slide[block] -> block."""
    return name[6:-1] if name.startswith("slide[") and name.endswith("]") else name


def load_time(phi, crank):
    """Time at crank angle phi on a uniform run from phi0 (the kinetostatic crank)."""
    return (np.asarray(phi, float) - crank.phi0) / crank.omega1


def sample_loads(mechanism, phi, t=None):
    """External loads at the crank angles ``phi`` (rad): array (n, n_loads, 3)
    of (fx [N], fy [N], moment [N·m]); at the times ``t`` (s) where given (a
    crank motion), else at the times of a uniform run (``load_time``)."""
    phi = np.asarray(phi, float)
    t = load_time(phi, mechanism.crank) if t is None else np.asarray(t, float)
    out = np.zeros((phi.shape[0], len(mechanism.loads), 3))
    for k, ld in enumerate(mechanism.loads):
        for c, e in enumerate((ld.fx, ld.fy, ld.moment)):
            out[:, k, c] = np.broadcast_to(e.evaluate(phi, t), phi.shape)
    return out


def joint_where(plan) -> list[str]:
    """Per reported joint, the bodies it joins and its point: 'crank 1-2 / lead
    2-3 at P2' (the pictures' legend, the export's column headers)."""
    out = []
    for ip, (b0, b1) in zip(plan.joint_point, plan.joint_bodies):
        what = " / ".join("ground" if b < 0 else plan.body_names[b] for b in (b0, b1))
        out.append(f"{what} at {plan.point_names[int(ip)]}")
    return out


@dataclass
class Reactions:
    phi: np.ndarray          # rad
    R: np.ndarray            # (n, n_joints, 2) N: force of the first body on the second
    slide: np.ndarray        # (n, n_slides, 2): normal force N, couple N·m
    M_bal: np.ndarray        # (n,) N·m, delivered by the main shaft (the crank's moment
                             # plus every input's share)
    body_loads: np.ndarray   # (n, n_bodies, 3): applied + inertia loads at S (N, N·m)
    joint_names: tuple
    slide_names: tuple
    body_names: tuple
    # inputs besides the crank: (n, n_inputs, 2) = drive on the input (N·m for a
    # rotary input, N along the guide for a slider input), its share of M_bal
    drive: np.ndarray = None
    input_names: tuple = ()
    drive_units: tuple = ()  # per input: "N·m" (rotary) or "N" (slider)
    # per position: the relative virtual-power residual (kernels.forces.equilibrium_residual)
    residual: np.ndarray = None
    # per position: the shaking force and moment on the frame, (n, 3) = (Fx [N], Fy [N],
    # M [N·m] about the point ``shaking_about``, the crank's pivot): kernels.forces.shaking
    shaking: np.ndarray = None
    shaking_about: str = ""
    # with [mechanism.friction] at the constant crank speed: solve.friction.FrictionForces
    # (R, slide, M_bal, body_loads and residual are then the friction-inclusive ones)
    friction: object = None

    @property
    def magnitude(self):
        return np.hypot(self.R[..., 0], self.R[..., 1])

    @property
    def shaking_magnitude(self):
        """|shaking force| [N] per position."""
        return np.hypot(self.shaking[:, 0], self.shaking[:, 1])

    def peaks(self):
        """Per joint: (name, R_max, phi1 at the peak [deg], d_min [mm])."""
        return joint_peaks(np.rad2deg(self.phi), self.magnitude, self.joint_names)

    def summary(self):
        peaks = self.peaks()
        j = max(range(len(peaks)), key=lambda i: peaks[i][1]) if peaks else None
        out = {}
        if j is not None:
            out["peak_reaction"] = f"{peaks[j][1]:.1f} N at {peaks[j][0]}, phi1 = {peaks[j][2]:g} deg"
        k = int(np.nanargmax(np.abs(self.M_bal)))
        out["peak_M_bal"] = f"{self.M_bal[k]:.3f} N·m at phi1 = {np.rad2deg(self.phi[k]):g} deg"
        return out


def scene_forces(mechanism, plan, curves, omega1=None, eps1=None, t=None) -> Reactions:
    """Reactions at every position of ``curves`` (which must carry second
    analogs), at the crank's constant omega1 and eps1, or along a crank
    motion: ``omega1``, ``eps1`` (rad/s, rad/s²) and ``t`` (s, for the
    loads) one per position (``pipeline.solve.motion_forces``).  Without
    friction: ``pipeline.solve.friction.scene_forces_with_friction`` adds the
    mechanism's [mechanism.friction] at the constant crank speed."""
    crank = mechanism.crank
    n = curves.phi.shape[0]
    along = omega1 is not None
    omega = np.broadcast_to(np.asarray(crank.omega1 if not along else omega1, float), (n,))
    eps = np.broadcast_to(np.asarray(crank.eps1 if not along else eps1, float), (n,))
    loads = sample_loads(mechanism, curves.phi, t)
    nb, nj, ns = len(plan.body_names), len(plan.joint_names), len(plan.slide_names)
    body_loads = np.zeros((n, nb, 3))
    R = np.zeros((n, nj, 2))
    S = np.zeros((n, ns + plan.n_inputs, 2))
    M = np.zeros(n)
    from ..compiler import await_beside, kernels_for, plan_path
    # the plan path (its tape of the generated forces_at: the same bits) where it has
    # the plan's; else the generated module's, compiled in a process beside meanwhile
    forces_curve = plan_path.forces_curve_of(plan)
    if forces_curve is None:
        kern = kernels_for(plan)
        await_beside(kern, "forces_curve")    # compiled beside: loaded, not compiled
        forces_curve = kern.forces_curve
    if not along:
        forces_curve(plan.par, curves.pos, curves.d1, curves.d2, crank.omega1, crank.eps1,
                     loads, body_loads, R, S, M)
    else:
        for k in range(n):  # the same kernel, one position at a time with its own speed
            s = slice(k, k + 1)
            forces_curve(plan.par, curves.pos[s], curves.d1[s], curves.d2[s], float(omega[k]),
                         float(eps[k]), loads[s], body_loads[s], R[s], S[s], M[s])
    residual = np.empty(n)
    shake = np.empty((n, 3))
    for k in range(n):      # the sweep's force stage calls the same two kernels
        residual[k] = equilibrium_residual(curves.pos[k], curves.d1[k], curves.d2[k], M[k],
                                           body_loads[k], plan.body_com, plan.body_turn)
        shake[k] = shaking(curves.pos[k], curves.d1[k], curves.d2[k], float(omega[k]),
                           float(eps[k]), plan.par, plan.body_com, plan.body_turn,
                           plan.body_mass_off, plan.crank_pivot)
    return Reactions(curves.phi, R, S[:, :ns], M, body_loads, plan.joint_names,
                     plan.slide_names, plan.body_names, drive=S[:, ns:],
                     input_names=plan.input_names,
                     drive_units=tuple("N·m" if k == ROTARY else "N" for k in plan.input_kind),
                     residual=residual, shaking=shake,
                     shaking_about=plan.point_names[plan.crank_pivot])
