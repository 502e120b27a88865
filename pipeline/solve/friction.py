"""The kinetostatics of a scene with friction in its joints ([mechanism.friction]):
the reactions and M_bal with friction at every position (``kernels.friction``),
what each joint loses, the plain bearings' pressure p, sliding speed v and
p*v, and where a slide locks (FRICTION_LOCK, located between positions).

Definitions (``model.friction`` for the friction loads):
* loss of joint or slide e [W]: minus the power of its friction load on the
  relative motion, -F_e v_rel,e >= 0 (v_rel = relative speed analog x omega1);
* M_bal with friction - M_bal without = the total loss / omega1 (virtual power);
* mean loss: the mean of the total over the revolution's positions (uniform in
  time at the constant crank speed); efficiency: the mean power the drive
  delivers to the external loads without friction over the mean power it
  delivers with friction, P_u / (P_u + mean loss), P_u = mean(M_bal_0 omega1)
  (NaN where P_u is not positive: inertia and gravity alone do no work over a
  revolution, and the drive's mean power is then all friction);
* bearing pressure p = |R| / (d l) [MPa], sliding speed v = |omega_rel| d / 2
  [m/s] at the pin's surface, p*v [MPa*m/s].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..kernels import config as kc

REL_TOL = 1e-12     # Newton stops at a step of this fraction of the largest unknown
MAX_ITER = 50
LOCATE_TOL = 1e-10  # rad: a locking angle between positions (the failure-angle figure)


@dataclass
class FrictionForces:
    """Per position (n) and per joint (nj) or joint-then-slide element (ne)."""
    moment: np.ndarray          # (n, nj) N*m: friction moment on each joint's second body
    force: np.ndarray           # (n, ns) N: friction force on each slider along u
    speed_analog: np.ndarray    # (n, ne): rad/rad (joints), mm/rad (slides)
    loss: np.ndarray            # (n, ne) W
    M_bal_frictionless: np.ndarray   # (n,) N*m
    status: np.ndarray          # (n,) int8: OK or FRICTION_LOCK
    element: np.ndarray         # (n,) int: the locking joint (< nj) or slide, -1
    iterations: np.ndarray      # (n,) Newton's
    pressure: np.ndarray        # (n, nj) MPa
    sliding_speed: np.ndarray   # (n, nj) m/s
    omega1: object              # rad/s: the crank's constant speed, or (n, 1) along a motion
    spec: object                # model.friction.Friction
    element_names: tuple        # joints, then slides
    fail_phi: float = math.nan  # rad: the first locking angle, located between positions
    fail_element: int = -1
    # the bearings' peaks refined between the positions (``solve.peaks``, with the
    # scene's other peaks): {(quantity, joint): peaks.Peak}; None where not refined
    peaks: dict | None = None

    @property
    def pv(self):
        return self.pressure * self.sliding_speed

    @property
    def total_loss(self):
        return self.loss.sum(axis=1)

    @property
    def overall(self):
        return kc.FRICTION_LOCK if (self.status != kc.OK).any() else kc.OK

    def mean_loss(self):
        return float(np.mean(self.total_loss))

    def efficiency(self):
        useful = float(np.mean(self.M_bal_frictionless * np.ravel(self.omega1)))
        loss = self.mean_loss()
        return useful / (useful + loss) if useful > 0.0 and math.isfinite(loss) else math.nan

    def bearings(self, phi):
        """Per revolute joint: (name, peak p [MPa], phi1 there [deg], peak v [m/s],
        phi1 there, peak p*v [MPa*m/s], phi1 there, mean p*v over the positions).
        The peaks are those refined between the positions (``peaks``) where the
        scene's peaks were refined, else the largest of the positions ``phi``."""
        deg = np.rad2deg(phi)
        rows = []
        pv = self.pv
        for j, (name, _, _) in enumerate(self.spec.pins):
            row = [name]
            for q, col in (("bearing_pressure", self.pressure[:, j]),
                           ("sliding_speed", self.sliding_speed[:, j]),
                           ("bearing_pv", pv[:, j])):
                peak = (self.peaks or {}).get((q, name))
                if peak is not None:
                    row += [peak.value, peak.phi1]
                    continue
                k = int(np.nanargmax(col)) if np.isfinite(col).any() else 0
                row += [float(col[k]), float(deg[k])]
            row.append(float(np.mean(pv[:, j])))
            rows.append(tuple(row))
        return rows

    def summary(self, phi):
        """Lines for the run's summary: the mean loss and efficiency, each
        bearing's peaks against p_max and pv_max, the lock if any."""
        out = {"friction_loss": f"{self.mean_loss():.4g} W mean over the revolution"}
        eff = self.efficiency()
        out["efficiency"] = (f"{eff:.4f}" if math.isfinite(eff) else
                             "not defined (no external load does work over a revolution)")
        p_max, pv_max = self.spec.p_max, self.spec.pv_max
        for name, p, p_at, v, v_at, pv, pv_at, pv_mean in self.bearings(phi):
            line = (f"p {p:.3g} MPa at {p_at:g} deg{_against(p, p_max)}; v {v:.3g} m/s at "
                    f"{v_at:g} deg; p*v {pv:.3g} MPa·m/s at {pv_at:g} deg"
                    f"{_against(pv, pv_max)}, mean {pv_mean:.3g}")
            out[f"bearing {name}"] = line
        if self.overall != kc.OK:
            out["friction_lock"] = (f"{self.element_names[self.fail_element]} at phi1 = "
                                    f"{math.degrees(self.fail_phi):.10g} deg")
        return out


def _against(value, limit):
    if limit is None:
        return ""
    return f" ({'over' if value > limit else 'within'} the limit {limit:g})"


def _arrays(plan):
    return (plan.body_com, plan.body_turn, plan.body_mass_off, plan.joint_point,
            plan.joint_bodies, plan.slide_bodies, plan.slide_dir, plan.slide_angle,
            int(plan.crank_body), plan.load_body, plan.load_point)


def solve_positions(plan, spec, pos, d1, d2, omega1, eps1, loads):
    """The friction kernel at every position: (R, slide, M_bal, body_loads,
    friction loads (n, ne), speed analogs (n, ne), found (n, 4)); ``omega1``
    and ``eps1``: the crank's, constant or one per position."""
    from ..kernels.friction import friction_forces
    n = pos.shape[0]
    nb, nj, ns = len(plan.body_names), len(plan.joint_names), len(plan.slide_names)
    m = 3 * nb
    radius = np.asarray(spec.diameters(), float) * 0.5e-3
    block = np.asarray(spec.block_lengths(), float).reshape(ns)
    a0, jac = np.empty((m, m)), np.empty((m, m))
    b0, res, x = np.empty(m), np.empty(m), np.empty(m)
    sense = np.empty(nj + ns)
    R = np.empty((n, nj, 2))
    S = np.empty((n, ns, 2))
    body_loads = np.empty((n, nb, 3))
    fric = np.empty((n, nj + ns))
    speed = np.empty((n, nj + ns))
    found = np.empty((n, 4))
    (com, turn, mass_off, jp, jb, sb, sd, sa, crank_body, lb, lp) = _arrays(plan)
    omega1 = np.broadcast_to(np.asarray(omega1, float), (n,))
    eps1 = np.broadcast_to(np.asarray(eps1, float), (n,))
    for k in range(n):
        friction_forces(pos[k], d1[k], d2[k], float(omega1[k]), float(eps1[k]), plan.gravity,
                        plan.par,
                        com, turn, mass_off, jp, jb, sb, sd, sa, crank_body, lb, lp, loads[k],
                        float(spec.revolute), radius, float(spec.slide), block, REL_TOL,
                        MAX_ITER, a0, b0, jac, res, x, sense, body_loads[k], R[k], S[k],
                        fric[k], speed[k], found[k], False)
    return R, S, found[:, 1].copy(), body_loads, fric, speed, found


def scene_forces_with_friction(mechanism, plan, curves, kinematics):
    """``solve.reactions.scene_forces`` at the crank's constant speed, with the
    mechanism's friction where it has [mechanism.friction] (``scene_friction``);
    ``kinematics(phis)``: the plan's curves with second analogs at the crank
    angles ``phis``, by continuation (``solve.scene.solve_curves``: where a
    lock is located between positions)."""
    from .reactions import scene_forces
    out = scene_forces(mechanism, plan, curves)
    if mechanism.friction is None:
        return out
    return scene_friction(mechanism, plan, curves, out, kinematics)


def scene_friction(mechanism, plan, curves, frictionless, kinematics, motion=None):
    """The scene's reactions with friction (``solve.reactions.Reactions`` with
    ``friction``: a ``FrictionForces``) from the frictionless ones; at the
    crank's constant speed, or along a crank motion (``motion`` = (omega1,
    eps1, t), one each per position: ``solve.motion_forces``; no lock is
    located between its steps, ``kinematics`` None)."""
    from .reactions import sample_loads
    spec = mechanism.friction
    crank = mechanism.crank
    omega1, eps1, t = (crank.omega1, crank.eps1, None) if motion is None else motion
    loads = sample_loads(mechanism, curves.phi, t)
    R, S, M, body_loads, fric, speed, found = solve_positions(
        plan, spec, curves.pos, curves.d1, curves.d2, omega1, eps1, loads)
    # the crank's speed, constant or (n, 1) along a motion (broadcast with (n, ne))
    w = float(omega1) if motion is None else np.asarray(omega1, float).reshape(-1, 1)
    nj = len(plan.joint_names)
    status = found[:, 0].astype(np.int8)
    element = found[:, 2].astype(np.int64)
    unit = np.r_[np.ones(nj), np.full(fric.shape[1] - nj, 1e-3)]   # mm/rad -> m/rad
    loss = -fric * speed * unit * w + 0.0
    d = np.asarray(spec.diameters(), float)
    length = np.asarray(spec.lengths(), float)
    mag = np.hypot(R[..., 0], R[..., 1])
    ff = FrictionForces(
        moment=fric[:, :nj], force=fric[:, nj:], speed_analog=speed, loss=loss,
        M_bal_frictionless=frictionless.M_bal, status=status, element=element,
        iterations=found[:, 3].astype(np.int64), pressure=mag / (d * length),
        sliding_speed=np.abs(speed[:, :nj] * w) * d * 0.5e-3,
        omega1=w, spec=spec,
        element_names=tuple(plan.joint_names) + tuple(plan.slide_names))
    locked = np.flatnonzero(status != kc.OK)
    if locked.size and kinematics is not None:
        ff.fail_phi, ff.fail_element = locate_lock(mechanism, plan, curves, int(locked[0]),
                                                   int(element[locked[0]]), kinematics)
    from dataclasses import replace
    return replace(frictionless, R=R, slide=S, M_bal=M, body_loads=body_loads,
                   residual=friction_residual(plan, curves, M, body_loads, loss, w),
                   friction=ff)


def friction_residual(plan, curves, M, body_loads, loss, omega1):
    """The relative virtual-power residual with friction: |M_bal + sum over
    bodies (F . S' + M phi') - total loss / omega1| over the largest term
    (``kernels.forces.equilibrium_residual`` with the friction's power)."""
    com = np.asarray(plan.body_com, np.int64)
    sd = curves.d1[:, com]                                  # (n, nb, 2) mm/rad
    pf = (body_loads[..., 0] * sd[..., 0] + body_loads[..., 1] * sd[..., 1]) * 1e-3
    w = np.zeros(pf.shape)
    for i, (a, b) in enumerate(np.asarray(plan.body_turn)):
        if a >= 0:
            r = curves.pos[:, b] - curves.pos[:, a]
            v = curves.d1[:, b] - curves.d1[:, a]
            w[:, i] = (r[:, 0] * v[:, 1] - r[:, 1] * v[:, 0]) / (r[:, 0] ** 2 + r[:, 1] ** 2)
    pm = body_loads[..., 2] * w
    w = np.broadcast_to(np.asarray(omega1, float), (loss.shape[0], 1)) if np.ndim(omega1) \
        else np.full((loss.shape[0], 1), float(omega1))
    with np.errstate(invalid="ignore", divide="ignore"):
        fl = np.where(w != 0.0, -loss / np.where(w != 0.0, w, 1.0), 0.0)
    total = M + pf.sum(axis=1) + pm.sum(axis=1) + fl.sum(axis=1)
    scale = np.maximum.reduce([np.abs(M), np.abs(pf).max(axis=1), np.abs(pm).max(axis=1),
                               np.abs(fl).max(axis=1) if fl.shape[1] else np.zeros_like(M)])
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(scale > 0.0, np.abs(total) / np.where(scale > 0.0, scale, 1.0), 0.0)


def locate_lock(mechanism, plan, curves, k, element, kinematics):
    """(crank angle [rad], element) of the first lock between positions k - 1
    (free) and k (locked), by bisection to LOCATE_TOL on the kinematics solved
    by continuation along the revolution's positions (``kinematics``); position
    k's own angle where k is the first position."""
    from .reactions import sample_loads
    if k == 0:
        return float(curves.phi[0]), element
    crank = mechanism.crank
    prefix = np.asarray(curves.phi[:k], float)

    def state(mid):
        c = kinematics(np.append(prefix, mid))
        if c.status[-1] != kc.OK:    # the kinematics fails first: not a lock here
            return False, -1
        found = solve_positions(plan, mechanism.friction, c.pos[-1:], c.d1[-1:], c.d2[-1:],
                                crank.omega1, crank.eps1,
                                sample_loads(mechanism, np.array([mid])))[-1]
        return found[0, 0] == kc.OK, int(found[0, 2])
    return bisect_lock(float(curves.phi[k - 1]), float(curves.phi[k]), element, state)


def bisect_lock(good, bad, element, state):
    """(crank angle [rad], element) of a lock between ``good`` (free) and
    ``bad`` (locked), by bisection to LOCATE_TOL; ``state(phi)``: (free,
    the locking element) there (a position whose kinematics fails counts
    as not free, its element -1 keeping the last one found)."""
    for _ in range(200):
        if not abs(bad - good) > LOCATE_TOL:
            break
        mid = 0.5 * (good + bad)
        free, e = state(mid)
        if free:
            good = mid
        else:
            bad = mid
            if e >= 0:
                element = e
    return bad, element
