"""Kinetostatics along a crank motion (issue 29, item 1): the reactions,
slide forces, input drives and the balancing moment at every output step of
a dynamics case, with the crank's actual omega1(t) and eps1(t) in place of a
scene's constant speed.

A scene's force analysis (``pipeline.solve.reactions.scene_forces``) holds
omega1 and eps1 constant.  Along the solution of the equation of motion
(``pipeline.solve.crank_motion``) the crank speeds up and slows down within
each revolution (the non-uniformity delta), and the joints carry what the
real motion asks: that is what pins, bearings and the motor are sized with.

Two records per case, as the case itself keeps them:

* ``samples``: every recorded sample (every ``sample_dt`` over the whole
  case: the run-up included);
* ``steady``: every integration step of the last whole revolutions of the
  fine tail (the revolutions ``CaseResult.steady`` averages), for a case
  that ends in a steady rotation; a case that oscillates has none.

The balancing moment along the real motion is the moment the shaft must
deliver for that motion; with the equation of motion
J phi'' + (1/2) J' phi'^2 + b phi' = Q + M1 it equals M1 - b omega1 at
every step (a check the tests make: ``pipeline.solve.crank_motion``
integrates that equation, the kinetostatics never sees it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..kernels import config as kc
from .reactions import Reactions, joint_peaks, scene_forces
from .scene import solve_curves


@dataclass
class MotionForces:
    """The kinetostatics at the steps of one record of a dynamics case."""
    case: str
    record: str              # "samples" or "steady"
    t: np.ndarray            # s
    phi1: np.ndarray         # rad (absolute: many revolutions)
    omega1: np.ndarray       # rad/s
    eps1: np.ndarray         # rad/s²
    status: np.ndarray       # (n,) int8: the kinematics at each step
    forces: Reactions

    def peaks(self):
        """Per joint: (name, R_max [N], t at the peak [s], phi1 there [deg, mod 360],
        d_min [mm])."""
        rows = joint_peaks(np.arange(self.t.size, dtype=float), self.forces.magnitude,
                           self.forces.joint_names)
        return [(name, r, float(self.t[int(k)]), _mod360(self.phi1[int(k)]), d)
                for name, r, k, d in rows]

    def peak_M_bal(self):
        """(M_bal [N·m] of the largest magnitude, t [s], phi1 [deg, mod 360])."""
        m = self.forces.M_bal
        if not np.isfinite(m).any():
            return math.nan, math.nan, math.nan
        k = int(np.nanargmax(np.abs(m)))
        return float(m[k]), float(self.t[k]), _mod360(self.phi1[k])

    def worst_residual(self):
        r = self.forces.residual
        return float(np.nanmax(r)) if np.isfinite(r).any() else math.nan


def _mod360(phi):
    return float(np.mod(np.rad2deg(phi), 360.0))


def steady_slice(case):
    """The fine tail's steps of the last whole revolutions ``case.steady()``
    averages (a slice of the tail arrays), or None when the case does not end
    in a steady rotation."""
    s = case.steady()
    if s is None:
        return None
    phi = case.tail_phi1
    sgn = math.copysign(1.0, phi[-1] - phi[0])
    start = phi[-1] - sgn * 2.0 * math.pi * s["revolutions"]
    i = int(np.argmax((phi - start) * sgn >= 0.0))
    return slice(max(i - 1, 0), phi.size)


def along(mechanism, plan, case, record, t, phi1, omega1, eps1, tols=None) -> MotionForces:
    """The kinetostatics of ``mechanism`` at the crank angles ``phi1`` reached
    at the times ``t`` with the speeds ``omega1`` and accelerations ``eps1``
    (one each per step).  A step whose kinematics fails carries NaN and its
    status."""
    t, phi1, omega1, eps1 = (np.ascontiguousarray(a, float) for a in (t, phi1, omega1, eps1))
    curves = solve_curves(plan, phi1, kc.ACCELERATIONS, tols)
    forces = scene_forces(mechanism, plan, curves, omega1, eps1, t)
    if mechanism.friction is not None:      # with the friction at each step's omega1, eps1
        from .friction import scene_friction
        forces = scene_friction(mechanism, plan, curves, forces, None, (omega1, eps1, t))
    return MotionForces(case, record, t, phi1, omega1, eps1, curves.status, forces)


def case_forces(mechanism, plan, case, tols=None) -> dict:
    """{"samples": MotionForces, "steady": MotionForces (a steady rotation
    only)} of one dynamics case (``crank_motion.CaseResult``); empty when
    the case stopped with a failure (its samples after it are NaN)."""
    if case.status != kc.OK or not np.isfinite(case.phi1).all():
        return {}
    out = {"samples": along(mechanism, plan, case.name, "samples", case.t, case.phi1,
                            case.omega1, case.eps1, tols)}
    s = steady_slice(case)
    if s is not None:
        out["steady"] = along(mechanism, plan, case.name, "steady", case.tail_t[s],
                              case.tail_phi1[s], case.tail_omega1[s], case.tail_eps1[s], tols)
    return out


def comparison_rows(constant: Reactions, records: dict):
    """Per joint: (name, constant-speed R_max [N], its phi1 [deg], then for each
    record (samples, steady): R_max [N], t [s], phi1 [deg mod 360]), and the
    same for |M_bal| as the last row (name "M_bal", N·m)."""
    rows = []
    const = constant.peaks()
    per = {k: v.peaks() for k, v in records.items()}
    for j, (name, r, phi, _) in enumerate(const):
        row = [name, r, phi]
        for k in ("samples", "steady"):
            if k in per:
                _, rr, tt, pp, _ = per[k][j]
                row += [rr, tt, pp]
            else:
                row += [math.nan] * 3
        rows.append(tuple(row))
    m = constant.M_bal
    k0 = int(np.nanargmax(np.abs(m))) if np.isfinite(m).any() else 0
    row = ["M_bal", float(abs(m[k0])), float(np.rad2deg(constant.phi[k0]))]
    for k in ("samples", "steady"):
        if k in records:
            mb, tt, pp = records[k].peak_M_bal()
            row += [abs(mb), tt, pp]
        else:
            row += [math.nan] * 3
    rows.append(tuple(row))
    return rows
