"""Flywheel sizing: the moment of inertia to add on the crank shaft so that a
dynamics case's steady rotation has a given coefficient of non-uniformity
delta = (omega_max - omega_min) / omega_mean.

The steady rotation is found directly, as the periodic solution of the
energy equation over one revolution (not by running the crank up and
waiting): with K = J(phi) omega^2 / 2 the equation of motion
J phi'' + (1/2) J'(phi) phi'^2 + b phi' = Q(phi) + M1(phi) reads, along the
direction of rotation s (theta = s (phi - phi0)),

    dK/dtheta = s (M1 + Q) - b |omega|,     |omega| = sqrt(2 K / (J + J_f)),

integrated by RK4 over one revolution from the exact J(phi) and Q(phi) of the
mechanism (``reduced_dynamics.reduced_terms``), and made periodic, K(2 pi) = K(0),
by Brent's method on K(0).  omega_mean is the time mean (2 pi over the period,
as ``CaseResult.steady`` measures it); omega_min and omega_max are refined
between the nodes (``_Orbit.extreme``: the largest of |omega| along an RK4
step of the same equation, over its length), so that delta and J_f do not
carry the nodes' O(h^2) error (2e-5 relative at 0.25 deg).  J_f is then found by Brent's method on
delta(J_f) = target: delta falls as J_f grows.  Needs M1 and the loads to be
constants or functions of phi (a steady rotation has no clock), and a net
positive work per revolution in the direction of rotation.  With
[mechanism.friction] the drive is less the work the joints' friction takes per
radian at constant speed (``friction_work``: the total loss over the speed),
that speed the steady rotation's own mean over the revolution (``_Orbit._friction``).

No flywheel is sized (``flywheel_of``: a ``Flywheel`` whose ``refused`` says
why, in one line naming the study file and its field) on a case whose motion
is not a result (a kinematic failure, refused for its error, past the speed
limit), nor where no steady rotation exists: with no damping the crank
speeds up forever, against too much damping or gravity it stops, and a
rotation beyond the study's speed limit is no result either.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..base import limits as lim
from ..kernels import config as kc
from ..kernels.dynamics import energy_orbit
from .crank_motion import STATUS_NAMES
from .reduced_dynamics import reduced_terms

ORBIT_STEPS = 1440          # RK4 steps over the revolution (0.25 deg)
XTOL = 1e-12                # Brent's method, relative to the bracket
BRACKET_TRIES = 200         # factors of 4 tried for a bracket (4^200: every float)


class NoSteadyRotation(ValueError):
    """The case has no steady rotation to size a flywheel for (the reason)."""


@dataclass
class Flywheel:
    case: str
    target: float               # delta asked for
    J_add: float                # kg·m² added on the crank shaft (0: none needed)
    delta: float                # of the sized system's steady rotation
    delta_without: float        # without the flywheel
    omega_min: float            # rad/s, with the flywheel (signed as the rotation)
    omega_max: float
    omega_mean: float
    J_body: str                 # the body that carries it (the crank's)
    refused: str = ""           # why none was sized: "<file>: <field>: <reason>"

    @classmethod
    def not_sized(cls, case, target, why):
        nan = math.nan
        return cls(case, target, nan, nan, nan, nan, nan, nan, "", refused=why)

    def summary(self) -> dict:
        if self.refused:
            return {f"{self.case} flywheel": f"not sized: {self.refused}"}
        if self.J_add == 0.0:
            return {f"{self.case} flywheel": (
                f"none needed: delta {self.delta_without:.4g} is already at most "
                f"{self.target:g}")}
        return {f"{self.case} flywheel": (
            f"J = {self.J_add:.4g} kg·m² added on the crank shaft brings delta from "
            f"{self.delta_without:.4g} to {self.delta:.4g} (target {self.target:g}); omega1 "
            f"{self.omega_min:.4f} to {self.omega_max:.4f} rad/s, mean {self.omega_mean:.4f}")}


def crank_inertia(plan, mech) -> int:
    """The column of plan.par holding J_S of the body that turns with the crank
    (a flywheel on the shaft adds to it: its centre is on the axis)."""
    a, b = plan.point(mech.crank.pivot), plan.point(mech.crank.tip)
    for i, name in enumerate(plan.body_names):
        if tuple(int(x) for x in plan.body_turn[i]) == (a, b):
            return plan.param(f"{name}.J_S")
    raise ValueError("a flywheel goes on the crank's shaft: declare the crank as a body "
                     f"(joints [{mech.crank.pivot!r}, {mech.crank.tip!r}])")


def with_flywheel(plan, mech, J_add):
    """The plan with ``J_add`` added to the crank body's J_S."""
    from dataclasses import replace
    par = plan.par.copy()
    par[crank_inertia(plan, mech)] += J_add
    return replace(plan, par=par)


class _Orbit:
    """J, Q and M1 sampled at the RK4 nodes and half steps of one revolution."""

    def __init__(self, plan, mech, case, n=ORBIT_STEPS):
        self.n = n
        self.h = 2.0 * math.pi / n
        # one revolution forward from phi_start at the nodes and half steps: 2n + 1
        # samples, the last the first again; backwards they are the same, reversed
        phi = case.phi_start + self.h * 0.5 * np.arange(2 * n + 1)
        J, _, Q = reduced_terms(plan, phi, 0.0, mech)
        M1 = np.broadcast_to(case.M1.evaluate(phi, 0.0), phi.shape)
        drive = np.asarray(M1, float) + np.asarray(Q, float)
        J = np.asarray(J, float)
        if not (np.isfinite(J).all() and np.isfinite(drive).all()):
            raise NoSteadyRotation("the mechanism cannot be assembled over the whole "
                                   "revolution")
        net = float(np.mean(drive[:-1]))
        if not net != 0.0:
            raise NoSteadyRotation("M1 and the loads do no net work over a revolution; there "
                                   "is no steady rotation to size a flywheel for")
        if not case.damping > 0.0:
            raise NoSteadyRotation("with no damping nothing balances the net work of M1 and "
                                   "the loads: the crank speeds up forever, there is no "
                                   "steady rotation")
        self.s = 1.0 if net > 0.0 else -1.0
        order = slice(None) if self.s > 0 else slice(None, None, -1)
        self.phi = case.phi_start + self.s * self.h * 0.5 * np.arange(2 * n + 1)
        self.J = J[order]
        self.drive = self.s * drive[order]
        self.b = case.damping
        self.plan, self.mech, self.case = plan, mech, case
        self.friction = None
        self.friction_speed = math.nan
        if mech.friction is not None:   # less what the joints lose at constant speed
            self.friction_speed, self.friction = self._friction(plan, mech)
            self.drive = self.drive - self.friction

    def _simpson(self, y):
        """The integral over the revolution of ``y`` at the nodes and half steps."""
        h = 0.5 * self.h
        return h / 3.0 * (y[0] + y[-1] + 4.0 * y[1:-1:2].sum() + 2.0 * y[2:-1:2].sum())

    def _friction(self, plan, mech):
        """(|omega| [rad/s], the friction's work per radian at it) where |omega| is
        the steady rotation's mean speed over the revolution: b 2 pi |omega| =
        the drive's work per revolution less the friction's at |omega| (exact for
        the periodic rotation: the damping takes b |omega| per radian), by Brent's
        method between rest and the frictionless mean speed."""
        from scipy.optimize import brentq
        work = self._simpson(self.drive)
        top = work / (2.0 * math.pi * self.b)
        if not (work > 0.0 and math.isfinite(top)):
            raise NoSteadyRotation("M1 and the loads do no net work over a revolution in its "
                                   "direction; there is no steady rotation")
        cache = {}

        def lost(w):
            if w not in cache:
                cache[w] = friction_work(plan, mech, self.phi, self.s, w)
            return cache[w]

        def gap(w):
            return (work - self._simpson(lost(w))) / (2.0 * math.pi * self.b) - w

        lo = top * 1e-6
        if not gap(lo) > 0.0:
            raise NoSteadyRotation("the joints' friction takes more than M1 and the loads give "
                                   "at every speed: the crank stops")
        w = brentq(gap, lo, top, xtol=1e-12 * top, rtol=1e-13)
        return w, lost(w)

    def run(self, K0, J_add):
        """K at the nodes over one revolution from K0 (``kernels.dynamics.
        energy_orbit``); None where the crank stops on the way."""
        K = np.empty(self.n + 1)
        K[0] = K0
        ok = energy_orbit(self.J + J_add, np.ascontiguousarray(self.drive, dtype=np.float64),
                          float(self.h), float(self.b), K)
        return K if ok else None

    def periodic(self, J_add):
        """|omega| at the nodes of the periodic rotation (J_add on the shaft)."""
        from scipy.optimize import brentq
        J0 = self.J[0] + J_add

        def gap(K0):
            K = self.run(K0, J_add)
            return -K0 if K is None else K[-1] - K0

        # bracket: K0 where the revolution gains energy (gap > 0) and where it loses it;
        # K of the mean speed M / b (M the mean drive) to start from
        with np.errstate(over="ignore"):
            lo = hi = min(0.5 * J0 * (abs(np.mean(self.drive)) / self.b) ** 2, 1e300)
        lo = min(lo, 1.0)
        for _ in range(BRACKET_TRIES):
            if gap(lo) > 0.0:
                break
            lo *= 0.25
        else:
            raise NoSteadyRotation(
                f"the crank stops within a revolution from every speed: M1 and the loads "
                f"cannot carry it round against gravity and the damping b = {self.b:g} N·m·s")
        fastest = 10.0 * lim.MAX_OMEGA
        while not gap(hi) < 0.0:
            hi *= 4.0
            if not math.sqrt(2.0 * hi / J0) <= fastest:
                raise NoSteadyRotation(
                    f"the steady rotation would turn faster than {fastest:g} rad/s, beyond "
                    f"the study's limit ({lim.OMEGA.words()})")
        try:
            K0 = brentq(gap, lo, hi, xtol=1e-300, rtol=4 * np.finfo(float).eps, maxiter=500)
        except RuntimeError:
            raise NoSteadyRotation("the energy of the steady rotation could not be found (no "
                                   "convergence)") from None
        K = self.run(K0, J_add)
        return np.sqrt(2.0 * K / (self.J[::2] + J_add))

    def delta(self, J_add, refined=True):
        """(delta, omega_min, omega_max, omega_mean) of the periodic rotation; its
        extremes refined between the nodes (``extreme``), or the nodes' own."""
        w = self.periodic(J_add)
        inv = 1.0 / w                          # time = integral of dtheta / |omega|: Simpson
        period = self.h / 3.0 * (inv[0] + inv[-1] + 4.0 * inv[1:-1:2].sum()
                                 + 2.0 * inv[2:-1:2].sum()) if self.n % 2 == 0 else \
            self.h * (inv.sum() - 0.5 * (inv[0] + inv[-1]))
        mean = 2.0 * math.pi / period
        lo, hi = float(w.min()), float(w.max())
        if refined:
            K = 0.5 * w * w * (self.J[::2] + J_add)
            lo = self.extreme(K, J_add, int(np.argmin(w)), -1.0)
            hi = self.extreme(K, J_add, int(np.argmax(w)), 1.0)
        return (float((hi - lo) / mean), self.s * lo, self.s * hi, self.s * float(mean))

    def extreme(self, K, J_add, i, sign):
        """|omega|'s largest (sign 1) or smallest (-1) value between the nodes i - 1
        and i + 1 of the periodic rotation (K at the nodes): the largest of |omega|
        along one RK4 step of the same equation from node i - 1 (its drive and J
        at the step's own angles, ``_terms``), over the step's length, by Brent's
        bounded method.  The nodes' value where that is larger."""
        from scipy.optimize import minimize_scalar
        j = max(i - 1, 0)
        span = self.h * (min(i + 1, self.n) - j)
        J0, d0 = self.J[2 * j] + J_add, self.drive[2 * j]
        theta = self.h * j
        b = self.b

        def speed(tau):
            if tau <= 0.0:
                return math.sqrt(2.0 * K[j] / J0)
            J, d = self._terms(theta + np.array([0.5 * tau, tau]))
            J = J + J_add

            def f(dk, Jk, k):
                return dk - b * math.sqrt(max(2.0 * k / Jk, 0.0))
            k1 = f(d0, J0, K[j])
            k2 = f(d[0], J[0], K[j] + 0.5 * tau * k1)
            k3 = f(d[0], J[0], K[j] + 0.5 * tau * k2)
            k4 = f(d[1], J[1], K[j] + tau * k3)
            k = K[j] + tau / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            return math.sqrt(max(2.0 * k / J[1], 0.0))

        r = minimize_scalar(lambda tau: -sign * speed(tau), bounds=(0.0, span),
                            method="bounded", options={"xatol": 1e-10 * span})
        best = speed(float(r.x))
        nodes = math.sqrt(2.0 * K[i] / (self.J[2 * i] + J_add))
        return max(best, nodes) if sign > 0 else min(best, nodes)

    def _terms(self, theta):
        """(J [kg·m²], the drive in the direction of rotation less the friction's
        work [N·m]) at the angles ``theta`` along the rotation from phi_start."""
        phi = self.case.phi_start + self.s * np.asarray(theta, float)
        J, _, Q = reduced_terms(self.plan, phi, 0.0, self.mech)
        M1 = np.broadcast_to(self.case.M1.evaluate(phi, 0.0), phi.shape)
        d = self.s * (np.asarray(M1, float) + np.asarray(Q, float))
        if self.friction is not None:
            d = d - friction_work(self.plan, self.mech, phi, self.s, self.friction_speed)
        return np.asarray(J, float), d


def friction_work(plan, mech, phi, s, speed):
    """The work the joints' friction takes per radian of the crank [N·m] at the
    crank angles ``phi``, at the constant speed s ``speed`` (in the direction
    of rotation s; eps1 = 0): the total loss [W] over the speed
    (``solve.friction``'s kinetostatics)."""
    from .friction import solve_positions
    from .reactions import sample_loads
    from .scene import solve_curves
    omega = s * abs(speed)
    c = solve_curves(plan, phi, kc.ACCELERATIONS)
    if c.overall != kc.OK:
        raise NoSteadyRotation("the mechanism cannot be assembled over the whole revolution")
    _, _, _, _, fric, speed, found = solve_positions(plan, mech.friction, c.pos, c.d1, c.d2,
                                                     omega, 0.0, sample_loads(mech, phi))
    if (found[:, 0] != kc.OK).any():
        k = int(np.flatnonzero(found[:, 0] != kc.OK)[0])
        raise NoSteadyRotation(f"the friction locks at phi1 = {math.degrees(phi[k]):.6g} deg "
                               "at constant speed")
    nj = len(plan.joint_names)
    unit = np.r_[np.ones(nj), np.full(fric.shape[1] - nj, 1e-3)]     # mm/rad -> m/rad
    return (-fric * speed * unit).sum(axis=1) * math.copysign(1.0, omega)


def size_flywheel(plan, mech, case, target, steps=ORBIT_STEPS) -> Flywheel:
    """The flywheel (kg·m² on the crank shaft) that brings the steady rotation
    of dynamics case ``case`` to the non-uniformity ``target`` (its extremes
    refined between the ``steps`` RK4 nodes of the revolution)."""
    from scipy.optimize import brentq
    body = plan.body_names[[plan.param(f"{n}.J_S") for n in plan.body_names]
                           .index(crank_inertia(plan, mech))]
    orbit = _Orbit(plan, mech, case, steps)
    d0 = orbit.delta(0.0)
    fastest = max(abs(d0[1]), abs(d0[2]))
    if not fastest <= lim.MAX_OMEGA:
        raise NoSteadyRotation(f"the steady rotation reaches |omega1| = {fastest:.4g} rad/s, "
                               f"beyond the study's limit ({lim.OMEGA.words()})")
    if d0[0] <= target:
        return Flywheel(case.name, target, 0.0, d0[0], d0[0], *d0[1:], body)
    hi = max(float(np.mean(orbit.J)), 1e-12)
    for _ in range(BRACKET_TRIES):
        if not orbit.delta(hi)[0] > target:
            break
        hi *= 4.0
    else:
        raise NoSteadyRotation(f"no flywheel up to {hi:.3g} kg·m² brings delta to {target:g}")
    J_add = brentq(lambda j: orbit.delta(j)[0] - target, 0.0, hi, xtol=XTOL * hi, rtol=1e-12)
    d = orbit.delta(J_add)
    return Flywheel(case.name, target, float(J_add), d[0], d0[0], *d[1:], body)


def flywheel_of(study, plan, cases, sizing=None) -> Flywheel:
    """The flywheel [dynamics.flywheel] of ``study`` asks for, on its case's
    integrated motion (``cases``: crank_motion.CaseResult); not sized (its
    ``refused`` saying why, naming the file and the field) on a motion that
    is not a result or where no steady rotation exists.  ``sizing``: the
    sizing already under way (``size_study_flywheel`` in a Future), else done
    here."""
    name, target = study.dynamics.flywheel
    run = next(c for c in cases if c.name == name)
    where = f"{study.path}: dynamics.flywheel"
    if run.status != kc.OK:
        return Flywheel.not_sized(name, target, (
            f"{where}: case {name!r} ended {STATUS_NAMES[run.status]} (its note says why): "
            "no flywheel is sized on a motion that is not a result"))
    try:
        return sizing.result() if sizing is not None else size_study_flywheel(study, plan)
    except NoSteadyRotation as e:
        return Flywheel.not_sized(name, target, f"{where}: case {name!r}: {e}")


def size_study_flywheel(study, plan) -> Flywheel:
    """``size_flywheel`` on the flywheel's case as the study declares it: its
    drive, damping and start, which are all the sizing reads of a case (not its
    step, nor the integrated motion, which only says whether the flywheel is
    sized at all: ``flywheel_of``).  So a scene sizes it while the motion is
    integrated, with the same numbers."""
    name, target = study.dynamics.flywheel
    case = next(c for c in study.dynamics.cases if c.name == name)
    return size_flywheel(plan, study.mechanism, case, target)
