"""The [dynamics] section of a study: its cases (start, driving moment, damping,
step, duration, sampling), the integration method and the flywheel to size."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..base import limits as lim
from ..model.drive import check_drive
from ..model.mechanism import Mechanism
from .section import Section


@dataclass(frozen=True)
class DynamicsCase:
    name: str
    phi_start: float        # rad
    omega_start: float      # rad/s
    M1: object              # Expression
    damping: float          # b, N·m·s
    t_end: float
    dt: float
    sample_dt: float


@dataclass(frozen=True)
class DynamicsSpec:
    cases: tuple
    method: str = "rk4"
    flywheel: tuple | None = None   # (case name, target delta): [dynamics.flywheel]


def parse_dynamics(sec: Section, mech: Mechanism) -> DynamicsSpec:
    from ..base.expressions import parse_expression
    if not mech.bodies:
        raise sec.error("", "crank dynamics needs mass data: declare [[mechanism.bodies]]")
    method = sec.string("method", "rk4", choices=("rk4", "dop853"))
    if method == "dop853" and mech.friction is not None:
        raise sec.error("method", "the reference integrator (dop853) is frictionless; with "
                                  "[mechanism.friction] the crank's motion is integrated by "
                                  "rk4 (its friction implicit in each step's omega1 and eps1)")
    cases = []
    names = set()
    sections = {}
    for c in sec.tables("cases"):
        name = c.name("name")
        if name in names or not name.replace("_", "").isalnum():
            raise c.error("name", f"case name {name!r} must be unique and made of letters, "
                                  "digits and _")
        names.add(name)
        sections[name] = c
        t_end = c.number("t_end", 10.0, positive=True, within=lim.DURATION)
        # RK4 step: 1e-4 s keeps phi1 within 1e-7 rad of DOP853 over 10 s at ~125 rad/s
        dt = c.number("dt", 1e-4, positive=True, within=lim.DURATION)
        sample = c.number("sample_dt", 0.01, positive=True, within=lim.DURATION)
        if dt > sample:
            raise c.error("dt", f"the integration step {dt:g} s exceeds the sampling step {sample:g} s")
        if abs(sample / dt - round(sample / dt)) > 1e-9 * (sample / dt):
            raise c.error("dt", f"the sampling step {sample:g} s must be a whole number of "
                                f"integration steps (dt = {dt:g} s)")
        if abs(t_end / sample - round(t_end / sample)) > 1e-9 * (t_end / sample):
            raise c.error("t_end", f"t_end = {t_end:g} s must be a whole number of sampling "
                                   f"steps (sample_dt = {sample:g} s)")
        if t_end / dt > lim.MAX_DYNAMICS_STEPS:
            raise c.error("t_end", f"t_end / dt = {t_end / dt:,.0f} integration steps; at most "
                                   f"{lim.MAX_DYNAMICS_STEPS:,} ({lim.DYNAMICS_STEPS_WHY})")
        if t_end / sample > lim.MAX_DYNAMICS_SAMPLES:
            raise c.error("t_end", f"t_end / sample_dt = {t_end / sample:,.0f} samples; at most "
                                   f"{lim.MAX_DYNAMICS_SAMPLES:,} ({lim.DYNAMICS_SAMPLES_WHY})")
        cases.append(DynamicsCase(
            name=name, phi_start=math.radians(c.number("phi_start", within=lim.ANGLE)),
            omega_start=c.number("omega_start", 0.0, within=lim.OMEGA),
            M1=parse_expression(c.raw("M1", 0.0), f"{c.file}: {c.path('M1')}"),
            damping=c.number("damping", 0.0), t_end=t_end, dt=dt, sample_dt=sample))
        if cases[-1].damping < 0:
            raise c.error("damping", "must not be negative")
        c.check_range("damping", cases[-1].damping, lim.DAMPING)
        c.done()
        # M1 and the loads must be constant, 2*pi-periodic in phi, or functions of t alone
        check_drive(mech, cases[-1], c.file)
    flywheel = None
    if sec.has("flywheel"):      # size a flywheel for a case's steady rotation
        fw = sec.table("flywheel")
        case = fw.name("case", cases[0].name if cases else "")
        if case not in names:
            raise fw.error("case", f"no dynamics case {case!r}; known: {', '.join(sorted(names))}")
        delta = fw.number("delta", positive=True)
        if not delta < 1.0:
            raise fw.error("delta", f"the coefficient of non-uniformity (omega_max - omega_min) "
                                    f"/ omega_mean is below 1 for a flywheel to reach; got "
                                    f"{delta:g}")
        timed = [e.text for ld in mech.loads for e in (ld.fx, ld.fy, ld.moment)
                 if e.depends_on_time]
        if timed:
            raise fw.error("case", f"a load depends on time ({timed[0]!r}): a steady rotation "
                                   "(for a flywheel) needs the loads constant or functions of phi")
        for c in cases:
            if c.name == case and c.M1.depends_on_time:
                raise fw.error("case", f"case {case!r} has a driving moment that depends on "
                                       "time: a steady rotation (for a flywheel) needs M1 "
                                       "constant or a function of phi")
            if c.name == case and c.damping == 0.0:
                raise sections[case].error("damping", (
                    "0 in the case [dynamics.flywheel] sizes a flywheel for: with no damping "
                    "nothing balances the work of M1 and the loads, the crank speeds up "
                    "forever and there is no steady rotation"))
        fw.done()
        flywheel = (case, delta)
    sec.done()
    return DynamicsSpec(cases=tuple(cases), method=method, flywheel=flywheel)
