"""Crank dynamics of a scene (DOMAIN.md section 7): the motion phi1(t) of the
crank under a driving moment, from Lagrange's equation of the second kind

    J(phi) phi'' + (1/2) dJ/dphi phi'^2 + b phi' = Q(phi) + M1.

The terms come from the exact kinematic analogs (``pipeline.kernels.dynamics``);
the integrator is a compiled fixed-step RK4 (``method = "rk4"``) or, as the
reference, scipy's ``solve_ivp(method="DOP853", rtol=1e-12, atol=1e-12)`` over
the same compiled right-hand side (``method = "dop853"``, slow).

Driving moment and external loads ("drive channels").  Expressions are
evaluated here, outside the kernels, and handed over as numbers or spline
tables.  Each of M1 and of the load components (fx, fy, moment) must be

* a constant (passed as a number, exact);
* a function of ``phi`` only that is 2 pi-periodic (checked on a grid; the
  crank makes many revolutions): a periodic cubic spline with
  ``PHI_INTERVALS`` intervals per revolution (relative error about 1e-11 for
  the smooth loads of the studies);
* a function of ``t`` only (time from the start of the case, s): a cubic
  spline over [0, t_end] with nodes every 2 dt.

Anything else (``phi`` and ``t`` together, a non-periodic function of phi)
is rejected when the study is read, with a ``StudyError`` naming the field.

Every motion carries its own error estimate (``integrate``): the case is
integrated again with half the step (RK4; DOP853 with a tolerance ten times
tighter) and the largest difference of phi1 at the common times (every
sample and every step of the fine tail) estimates the error of the result:
for RK4 (fourth order) error(dt) = 16/15 |phi1(dt) - phi1(dt/2)|.  A case
whose estimate exceeds ``ACCEPTED_ERROR_RAD`` (the README's figure for the
take-up: 8e-8 rad) is integrated again with half the step, automatically,
as long as the runs stay within ``REFINE_MAX_STEPS``; one still above it is
refused (INACCURATE: no motion kept).  A step that ends with |omega1| beyond
the study's speed limit (``base.limits.OMEGA``, 10^4 rad/s) stops the case
with TOO_FAST: the motion up to there is kept, nothing after it.
"""

from __future__ import annotations

import logging
import math
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace

import numpy as np

from ..kernels import config as kc
from ..compiler import kernels_for, plan_path
from ..kernels.continuation import MARGIN_SLOTS
from ..kernels.dynamics import OMEGA_STOP, TOO_FAST
from ..base import limits as lim
from .crank_drive import build_drive

log = logging.getLogger("pipeline")

TAIL_SECONDS = 2.0          # fine record (every step) kept at the end of each case
STEADY_REVOLUTIONS = 5      # revolutions of the steady rotation used for delta
DOP853_TOL = 1e-12          # rtol = atol of the reference integrator
METHODS = ("rk4", "dop853")

# The error a motion may carry: README's accuracy figure for the take-up's run-up (RK4 at
# dt = 1e-4 s against DOP853 over 10 s), phi1 anywhere along the case (every sample and
# every step of the fine tail).  The take-up's own estimate is 4.0e-8 rad.
ACCEPTED_ERROR_RAD = 8e-8
# a refinement halves dt as long as the run at the halved step (the companion of the
# check) makes at most this many steps and tail rows: about 4 s of the compiled RK4 on the
# take-up and 64 MB of tail; every run before it costs half as much as the next
REFINE_MAX_STEPS = 2_000_000
DOP853_CHECK_TOL = DOP853_TOL / 10    # the reference's companion run (no refinement)
# a dynamics case's outcomes beyond the kinematic statuses (kernels.config)
INACCURATE = 17             # the estimated error exceeds ACCEPTED_ERROR_RAD: refused
STATUS_NAMES = {**kc.STATUS_NAMES, TOO_FAST: "TOO_FAST", INACCURATE: "INACCURATE"}


def _kernels(plan):
    """The dynamics kernels of ``plan``: the plan path's (compiled once for every
    mechanism, the same bits) where the plan is on it, else its generated module's."""
    return plan_path.dynamics_of(plan) or kernels_for(plan)


def _plan_args(plan, tols, kern=None):
    """(par, K, tols) of the dynamics kernels ``kern`` (``_kernels``' by
    default): K the constants as an array."""
    kern = _kernels(plan) if kern is None else kern
    return (plan.par, kern.constants_array(plan.par), tols)


# ----------------------------------------------------------------- results
def _round(x, digits=6):
    return float(f"{x:.{digits}g}") if math.isfinite(x) else None


# the units of CaseResult.summary's figures (dimensionless ones: none)
SUMMARY_UNITS = {"omega_mean": " rad/s", "rpm": " 1/min", "delta": "", "omega_min": " rad/s",
                 "omega_max": " rad/s", "omega_mean_change": " rad/s", "phi1_end_deg": " deg",
                 "omega1_end": " rad/s", "phi_mid_deg": " deg", "amplitude_deg": " deg",
                 "period_s": " s", "dt": " s", "error_phi1": " rad", "error_omega1": " rad/s"}


@dataclass
class CaseResult:
    """The motion of one case: samples every sample_dt and a fine tail."""
    name: str
    t: np.ndarray            # s
    phi1: np.ndarray         # rad
    omega1: np.ndarray       # rad/s
    eps1: np.ndarray         # rad/s²
    status: int
    method: str
    case: object             # study.DynamicsCase
    tail_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tail_phi1: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tail_omega1: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tail_eps1: np.ndarray = field(default_factory=lambda: np.zeros(0))
    seconds: float = math.nan    # wall time of the integration (compile excluded if warm)
    dt: float = math.nan         # s, the step of this motion (the study's, or refined)
    error_phi1: float = math.nan     # rad, its estimated error (largest along the case)
    error_omega1: float = math.nan   # rad/s, the same for omega1
    note: str = ""               # why it was re-run with a smaller step, refused or stopped
    t_cross: float = math.nan    # s, where |omega1| first passed the speed limit (TOO_FAST)

    def steady(self, revolutions=STEADY_REVOLUTIONS):
        """Statistics of the last whole revolutions of the fine tail (at most
        ``revolutions``), or None if the crank does not rotate there:
        omega_mean = (revolutions * 2 pi) / time taken (the time mean, not
        (omega_max + omega_min) / 2), the coefficient of non-uniformity
        delta = (omega_max - omega_min) / omega_mean, and omega_mean_change, the
        change of omega_mean from the revolutions before (0 once steady)."""
        phi, om, t = self.tail_phi1, self.tail_omega1, self.tail_t
        if phi.size < 3 or not np.isfinite(phi).all():
            return None
        sgn = math.copysign(1.0, phi[-1] - phi[0])
        if np.any(om * sgn <= 0.0):
            return None                      # not a steady rotation (it stops or reverses)
        n = min(revolutions, int(abs(phi[-1] - phi[0]) / (2.0 * math.pi)))
        if n < 1:
            return None

        def time_at(angle):
            # the crank passes ``angle`` between two steps: interpolate the time there
            i = int(np.argmax((phi - angle) * sgn >= 0.0))
            if i == 0:
                return t[0], 0
            return float(np.interp(angle * sgn, phi[i - 1:i + 1] * sgn, t[i - 1:i + 1])), i

        span = sgn * 2.0 * math.pi * n
        t0, i = time_at(phi[-1] - span)
        w = om[i:] * sgn
        mean = 2.0 * math.pi * n / (t[-1] - t0)
        out = {"revolutions": n, "omega_mean": sgn * mean, "omega_max": sgn * float(w.max()),
               "omega_min": sgn * float(w.min()), "delta": float((w.max() - w.min()) / mean),
               "rpm": sgn * mean * 30.0 / math.pi, "omega_mean_change": math.nan}
        if abs(phi[-1] - phi[0]) >= 2.0 * abs(span):
            # the n revolutions before: a non-zero change says the run-up is not over
            tb, _ = time_at(phi[-1] - 2.0 * span)
            out["omega_mean_change"] = sgn * (mean - 2.0 * math.pi * n / (t0 - tb))
        return out

    def oscillation(self):
        """Settled angle, amplitude and period of an oscillation in the fine
        tail (None if the crank rotates or the tail has no turning points)."""
        phi, om, t = self.tail_phi1, self.tail_omega1, self.tail_t
        if phi.size < 3 or not np.isfinite(phi).all():
            return None
        # turning points: omega changes sign from + to - (maxima of phi)
        k = np.nonzero((om[:-1] > 0.0) & (om[1:] <= 0.0))[0]
        tp = t[k] + (t[k + 1] - t[k]) * om[k] / (om[k] - om[k + 1])
        out = {"phi_mid_deg": math.degrees(0.5 * (phi.max() + phi.min())),
               "amplitude_deg": math.degrees(0.5 * (phi.max() - phi.min()))}
        if np.ptp(phi) >= 2.0 * math.pi:
            return None
        out["period_s"] = float(np.mean(np.diff(tp))) if tp.size >= 2 else math.nan
        return out

    def summary_lines(self) -> dict:
        """The summary with the unit of every figure, one entry per figure."""
        out = {k: (f"{v:g}{SUMMARY_UNITS.get(k, '')}" if isinstance(v, float) else str(v))
               for k, v in self.summary().items()}
        if "error_phi1" in out:
            how = ("dt against dt/2" if self.method == "rk4"
                   else "against a tolerance ten times tighter")
            out["error_phi1"] += f" estimated (accepted: {ACCEPTED_ERROR_RAD:g} rad; {how})"
        return out

    def summary(self):
        out = {"status": STATUS_NAMES[self.status], "method": self.method}
        if self.note:
            out["note"] = self.note
        if self.method == "rk4" and math.isfinite(self.dt):
            out["dt"] = self.dt
        for key in ("error_phi1", "error_omega1"):
            if math.isfinite(getattr(self, key)):
                out[key] = _round(getattr(self, key), 2)
        # a refused or stopped case has no steady rotation nor oscillation to report
        s = self.steady() if self.status == kc.OK else None
        if s is not None:
            out.update(omega_mean=_round(s["omega_mean"]), rpm=_round(s["rpm"], 5),
                       delta=_round(s["delta"], 5),
                       omega_min=_round(s["omega_min"]), omega_max=_round(s["omega_max"]),
                       omega_mean_change=_round(s["omega_mean_change"], 3))
        elif self.status == kc.OK:
            o = self.oscillation()
            if o is not None:
                out.update({k: _round(v) for k, v in o.items()})
        out["phi1_end_deg"] = _round(math.degrees(self.phi1[-1]))
        out["omega1_end"] = _round(float(self.omega1[-1]))
        return out


# ----------------------------------------------------------------- integration
def _grid(case):
    """(steps per sample, number of samples, number of tail steps)."""
    n_sub = int(round(case.sample_dt / case.dt))
    n_samples = int(round(case.t_end / case.sample_dt)) + 1
    n_steps = (n_samples - 1) * n_sub
    n_tail = min(n_steps, int(round(TAIL_SECONDS / case.dt))) + 1
    return n_sub, n_samples, n_tail


def integrate(plan, mechanism, case, method="rk4", tols=None, file="<study>",
              checked=True) -> CaseResult:
    """Integrate one dynamics case (study.DynamicsCase) of the compiled ``plan``
    with its error estimate: re-run with smaller steps, or refused, where the
    estimate exceeds ACCEPTED_ERROR_RAD (the module docstring).

    ``checked=False``: one integration at the case's own step (or tolerance),
    no estimate, no refinement: what the integrator alone does at that step
    (the accuracy benchmark's error against the step; never a study's result)."""
    if method not in METHODS:
        raise ValueError(f"unknown integration method {method!r}; known: {', '.join(METHODS)}")
    tols = kc.default_tolerances() if tols is None else tols
    t0 = time.perf_counter()

    def run(dt, tol=DOP853_TOL):
        return _run_once(plan, mechanism, case, method, tols, file, dt, tol)

    if not checked:
        res = run(case.dt)
    elif method == "dop853":       # tolerance-proportional: error(tol) = 10/9 |y(tol) - y(tol/10)|
        a = run(case.dt)
        res = _judged(a, _check(a, run(case.dt, DOP853_CHECK_TOL), 10.0 / 9.0), "", False)
    else:                        # fourth order: error(dt) = 16/15 |y(dt) - y(dt/2)|
        a, b = _at_once(run, (case.dt, case.dt / 2.0))
        halvings, first = 0, None
        while True:
            check = _check(a, b, 16.0 / 15.0)
            first = first or check
            if not check.problem or not _refinable(check.b, case):
                break
            a, halvings = check.b, halvings + 1
            b = run(a.dt / 2.0)
        why = "" if not halvings else (
            f"re-run with dt = {a.dt:g} s, the study's {case.dt:g} s halved {halvings} times "
            f"(at {case.dt:g} s {first.problem})")
        res = _judged(a, check, why, True)
    res.seconds = time.perf_counter() - t0
    return res


def load_integrators(plan, mechanism, method="rk4"):
    """The RK4 kernels of ``plan`` compiled (or loaded from numba's cache) now, on
    this thread: a scene loads them before it starts the thread that runs them
    (each kernel's caller loads it too, under numba's lock: ``compile_for``)."""
    if method != "rk4":
        return
    from ..kernels.dynamics import compile_integrator
    from ..kernels.dynamics_friction import compile_friction_integrator
    _kernels(plan)
    compile_integrator()
    if mechanism.friction is not None:
        compile_friction_integrator()


def _at_once(fn, args, threads=True):
    """[fn(a) for a in args], each on a thread of its own (``threads``): the
    compiled integrators release the GIL, so independent runs (a case's step and
    its half, the cases) share the cores; each run's numbers are its own,
    whatever runs beside it."""
    if not threads or len(args) < 2:
        return [fn(a) for a in args]
    with ThreadPoolExecutor(len(args) - 1) as pool:
        ahead = [pool.submit(fn, a) for a in args[1:]]
        return [fn(args[0])] + [f.result() for f in ahead]


def _run_once(plan, mechanism, case, method, tols, file, dt, tol) -> CaseResult:
    """One integration of ``case`` at the step ``dt`` (RK4) or the tolerance
    ``tol`` (DOP853), unchecked; the speed limit ends it (TOO_FAST)."""
    drive = build_drive(mechanism, case.M1, case.t_end, dt, file)
    stepped = replace(case, dt=dt)
    n_sub, n_samples, n_tail = _grid(stepped)
    out = [np.full(n_samples, np.nan) for _ in range(4)]
    tail = [np.full(n_tail, np.nan) for _ in range(4)]
    n_steps = (n_samples - 1) * n_sub      # the times of every record, as rk4 writes them
    out[0][:] = np.arange(n_samples) * n_sub * dt
    tail[0][:] = np.arange(n_steps - n_tail + 1, n_steps + 1) * dt
    if method == "rk4" and mechanism.friction is not None:
        status, crossing = _rk4_friction(plan, mechanism, tols, drive.args(), case, dt, n_sub,
                                         out, tail)
        t_cross = crossing * dt if crossing >= 0 else math.nan
    elif method == "rk4":
        kern = _kernels(plan)
        status, crossing = kern.rk4(
            *_plan_args(plan, tols, kern), *drive.args(), float(case.damping),
            float(case.phi_start),
            float(case.omega_start), float(dt), n_sub, float(lim.MAX_OMEGA), *out, *tail)
        t_cross = crossing * dt if crossing >= 0 else math.nan
    else:
        status, t_cross = _dop853(plan, drive, stepped, tols, out, tail, tol)
    res = CaseResult(case.name, *out, int(status), method, case, *tail, dt=dt)
    res.t_cross = t_cross
    return res


def _rk4_friction(plan, mechanism, tols, drive_args, case, dt, n_sub, out, tail):
    """RK4 with the mechanism's friction (``kernels.dynamics_friction``): on the
    generated module's continuation, as its ``rk4``."""
    from ..kernels import dynamics_friction as df
    mod = _kernels(plan)
    par, K, tols = _plan_args(plan, tols, mod)
    df.compile_friction_integrator()
    return df.rk4_friction(mod.advance_first_class, mod.start_first_class, K, mod.SIZES,
                           mod.MASSES, par, tols, *drive_args, float(case.damping),
                           float(case.phi_start), float(case.omega_start), float(dt), n_sub,
                           float(lim.MAX_OMEGA), *out, *tail,
                           df.friction_args(plan, mechanism.friction))


@dataclass
class _Check:
    """A run ``a`` checked against its companion ``b`` (half the step, or a
    tighter tolerance)."""
    a: CaseResult
    b: CaseResult
    error_phi1: float        # rad, estimated error of a's phi1 (largest at the common times)
    error_omega1: float      # rad/s
    problem: str             # why a is not accepted ("" where it is)


def _check(a, b, factor) -> _Check:
    """``a``'s error estimate: ``factor`` times the largest difference from ``b``
    at the common times (every sample, every step of a's fine tail), and
    whether it is accepted: both runs end the same way, a crossing of the
    speed limit is confirmed by the state past it, and the estimate is at
    most ACCEPTED_ERROR_RAD."""
    stride = (b.tail_t.size - 1) // max(a.tail_t.size - 1, 1) if a.tail_t.size > 1 else 1
    d_phi = d_omega = 0.0
    for pa, pb, wa, wb in ((a.phi1, b.phi1, a.omega1, b.omega1),
                           (a.tail_phi1, b.tail_phi1[::stride][-a.tail_t.size:],
                            a.tail_omega1, b.tail_omega1[::stride][-a.tail_t.size:])):
        both = np.isfinite(pa) & np.isfinite(pb) & np.isfinite(wa) & np.isfinite(wb)
        if both.any():
            d_phi = max(d_phi, float(np.max(np.abs(pa[both] - pb[both]))))
            d_omega = max(d_omega, float(np.max(np.abs(wa[both] - wb[both]))))
    check = _Check(a, b, factor * d_phi, factor * d_omega, "")
    other = "half that step" if a.method == "rk4" else "a tighter tolerance"
    if a.status != b.status:
        check.problem = (f"the outcome depended on the step: {STATUS_NAMES[a.status]}, "
                         f"{STATUS_NAMES[b.status]} with {other}")
    elif math.isfinite(a.t_cross) and not _crossing_confirmed(a, b):
        check.problem = (f"|omega1| passed the limit of {lim.MAX_OMEGA:g} rad/s at t = "
                         f"{a.t_cross:.6g} s, with {other} at {b.t_cross:.6g} s: the step "
                         "does not resolve the motion there")
    if check.problem:        # the runs part ways: their differences up to there are no estimate
        check.error_phi1 = check.error_omega1 = math.nan
    elif check.error_phi1 > ACCEPTED_ERROR_RAD:
        check.problem = (f"the estimated error of phi1 was {check.error_phi1:.2g} rad, above "
                         f"the accepted {ACCEPTED_ERROR_RAD:g} rad")
    return check


def _crossing_confirmed(a, b):
    """Whether ``a``'s crossing of the speed limit is confirmed by ``b``: both
    recorded the first sample past it (the state there compared) and ``b``
    crossed too by then."""
    if not math.isfinite(b.t_cross):
        return False
    k = int(math.ceil(a.t_cross / a.case.sample_dt - 1e-9))
    return (k < a.t.size and bool(np.isfinite(a.phi1[k]) and np.isfinite(b.phi1[k]))
            and b.t_cross <= a.t[k])


def _steps_run(res):
    """Integration steps ``res`` made (up to where it ended)."""
    done = np.flatnonzero(np.isfinite(res.phi1))
    t_stop = res.case.t_end if res.status == kc.OK or done.size == 0 \
        else min(res.case.t_end, res.t[done[-1]] + res.case.sample_dt)
    return int(round(t_stop / res.dt))


def _refinable(b, case):
    """Whether the run at half ``b``'s step stays within REFINE_MAX_STEPS
    (twice b's steps; its tail rows)."""
    _, _, n_tail = _grid(replace(case, dt=b.dt / 2.0))
    return max(2 * _steps_run(b), n_tail) <= REFINE_MAX_STEPS


def _judged(a, check, why, halvable) -> CaseResult:
    """``a`` with the error estimate of ``check``; refused (INACCURATE, no motion
    kept) where it is not accepted; cut where |omega1| passes the limit."""
    a.error_phi1, a.error_omega1, a.note = check.error_phi1, check.error_omega1, why
    if check.problem:
        step = f"dt = {a.dt:g} s" if a.method == "rk4" else f"tolerance {DOP853_TOL:g}"
        if a.dt != a.case.dt:
            step += f" (the study's {a.case.dt:g} s halved)"
        more = (f"; a smaller step would take more than {REFINE_MAX_STEPS:,} steps"
                if halvable else "")
        a.status = INACCURATE
        a.note = f"refused: at {step} {check.problem}{more}"
        if math.isfinite(a.t_cross) and "passed the limit" not in check.problem:
            a.note += (f" (|omega1| passed the limit of {lim.MAX_OMEGA:g} rad/s at t = "
                       f"{a.t_cross:.6g} s)")
        for arr in (a.phi1, a.omega1, a.eps1, a.tail_phi1, a.tail_omega1, a.tail_eps1):
            arr[:] = np.nan
    elif math.isfinite(a.t_cross):
        a.status = TOO_FAST
        for t, arrays in ((a.t, (a.phi1, a.omega1, a.eps1)),
                          (a.tail_t, (a.tail_phi1, a.tail_omega1, a.tail_eps1))):
            for arr in arrays:
                arr[~(t < a.t_cross)] = np.nan
        a.note = ((why + "; ") if why else "") + (
            f"|omega1| passed {lim.MAX_OMEGA:g} rad/s at t = {a.t_cross:.6g} s, the study's "
            f"limit ({lim.OMEGA.words()}): no motion kept from there on")
    return a


class _Stop(Exception):
    def __init__(self, status):
        self.status = status


def _dop853(plan, drive, case, tols, out, tail, tol=DOP853_TOL):
    """The reference: scipy's DOP853 at rtol = atol = ``tol`` over the compiled
    right-hand side; samples from its dense output, eps1 re-evaluated there.
    A kinematic failure stops it with that status and leaves every sample NaN.
    Returns (status, the time |omega1| first passes the speed limit or NaN):
    past it, TOO_FAST, and the run ends with the first sample after it (or at
    once where |omega1| exceeds OMEGA_STOP times the limit)."""
    from scipy.integrate import solve_ivp
    n = plan.n_points
    kern = kernels_for(plan)
    work = dict(state=np.zeros((kern.N_TRIADS, kc.N_STATE)), last=np.zeros(1),
                pos=np.zeros((n, 2)), d1=np.zeros((n, 2)), d2=np.zeros((n, 2)),
                margins=np.zeros(plan.n_groups + MARGIN_SLOTS), loads_k=np.zeros((len(plan.load_body), 3)))
    pa, da = _plan_args(plan, tols, kern), drive.args()
    b = float(case.damping)

    def restart():
        kern.begin(pa[1], float(case.phi_start), work["state"], work["last"])

    def eps(t, phi, omega):
        st, e = kern.acceleration(*pa, *da, b, float(t), float(phi), float(omega),
                             work["state"], work["last"], work["pos"], work["d1"], work["d2"],
                             work["margins"], work["loads_k"])
        if st != kc.OK:
            raise _Stop(st)
        return e

    def rhs(t, y):
        return np.array([y[1], eps(t, y[0], y[1])])

    n_sub, n_samples, n_tail = _grid(case)
    ts = np.arange(n_samples) * case.sample_dt
    n_steps = (n_samples - 1) * n_sub
    tt = np.arange(n_steps - n_tail + 1, n_steps + 1) * case.dt

    def crossing(t, y):
        return abs(y[1]) - lim.MAX_OMEGA

    def runaway(t, y):
        return abs(y[1]) - OMEGA_STOP * lim.MAX_OMEGA

    runaway.terminal = True
    try:
        restart()
        sol = solve_ivp(rhs, (0.0, ts[-1]), [case.phi_start, case.omega_start],
                        method="DOP853", rtol=tol, atol=tol, dense_output=True,
                        events=(crossing, runaway))
        if not sol.success:
            log.warning("dynamics %s: DOP853 failed: %s", case.name, sol.message)
            return kc.SINGULAR, math.nan
        up = sol.t_events[0][sol.t_events[0] > 0.0]
        if abs(case.omega_start) > lim.MAX_OMEGA:
            up = np.array([0.0])
        t_cross = float(up[0]) if up.size else math.nan
        t_last = sol.t[-1]
        if up.size:           # the first sample after the crossing is the last
            past = ts[ts >= t_cross]
            t_last = min(t_last, past[0]) if past.size else t_last
        restart()
        for times, dest in ((ts, out), (tt, tail)):
            dest[0][:] = times
            times = times[times <= t_last]
            y = sol.sol(times)
            dest[1][:times.size] = y[0]
            dest[2][:times.size] = y[1]
            dest[3][:times.size] = [eps(t, p, w) for t, p, w in zip(times, y[0], y[1])]
    except _Stop as s:
        return s.status, math.nan
    return (TOO_FAST if up.size or sol.status == 1 else kc.OK), t_cross


def run_dynamics(study, plan, method=None) -> list[CaseResult]:
    """Every case of the study's [dynamics] section, with its method (or ``method``)."""
    spec = study.dynamics
    method = method or spec.method
    # (DOP853 steps in Python: on threads the cases would only take turns)
    results = _at_once(lambda case: integrate(plan, study.mechanism, case, method,
                                              file=study.path), spec.cases,
                       threads=method == "rk4")
    for case, res in zip(spec.cases, results):
        log.info("dynamics %s (%s): %s, %.2f s, estimated error %.2g rad%s", case.name, method,
                 STATUS_NAMES[res.status], res.seconds, res.error_phi1,
                 f" ({res.note})" if res.note else "")
    return results


def with_changes(case, **changes):
    """A copy of a DynamicsCase with some fields changed (e.g. damping=0)."""
    if "M1" in changes and not hasattr(changes["M1"], "evaluate"):
        from ..base.expressions import parse_expression
        changes["M1"] = parse_expression(changes["M1"], "M1")
    return replace(case, **changes)
