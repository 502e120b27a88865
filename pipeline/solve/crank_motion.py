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
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..kernels import config as kc
from ..compiler import kernels_for
from ..kernels.continuation import MARGIN_SLOTS
from ..base.errors import StudyError

log = logging.getLogger("pipeline")

PHI_INTERVALS = 4096        # periodic spline intervals per revolution (phi tables)
T_NODE_STEPS = 2            # time tables: one node every T_NODE_STEPS integration steps
T_MAX_INTERVALS = 400_000
TAIL_SECONDS = 2.0          # fine record (every step) kept at the end of each case
STEADY_REVOLUTIONS = 5      # revolutions of the steady rotation used for delta
DOP853_TOL = 1e-12          # rtol = atol of the reference integrator
METHODS = ("rk4", "dop853")

_PERIODIC_GRID = 97         # phi samples of the periodicity / dependence checks
_T_GRID = 23
_CHECK_RTOL = 1e-9


# ----------------------------------------------------------------- drive channels
def _split_field(expr, file):
    """(file, where) for a StudyError from an expression's "file: where" field."""
    f = str(file)
    if expr.field.startswith(f + ": "):
        return f, expr.field[len(f) + 2:]
    return f, expr.field


def classify_drive(expr, t_end, file="<study>"):
    """"const", "phi" or "t": how ``expr`` enters the dynamics (see the module
    docstring).  Raises StudyError naming the field when it cannot."""
    from ..base.expressions import ExpressionError
    fname, where = _split_field(expr, file)
    if expr.is_constant:
        return "const"
    phi = np.linspace(0.0, 2.0 * math.pi, _PERIODIC_GRID, endpoint=False)
    try:
        if not expr.depends_on_time:
            f0 = expr.evaluate(phi, 0.0)
            scale = 1.0 + np.max(np.abs(f0))
            for turns in (1, -1, 7, 1000):
                f1 = expr.evaluate(phi + 2.0 * math.pi * turns, 0.0)
                if np.max(np.abs(f1 - f0)) > _CHECK_RTOL * scale:
                    raise StudyError(fname, where, (
                        f"{expr.text!r} is not 2*pi-periodic in phi (it changes by "
                        f"{np.max(np.abs(f1 - f0)):.3g} over {turns} revolution(s)); in "
                        "[dynamics] the crank makes many revolutions, so a load or M1 that "
                        "depends on phi must repeat every revolution"))
            return "phi"
        t = np.linspace(0.0, t_end, _T_GRID)
        f = expr.evaluate(phi[:, None], t[None, :])
    except ExpressionError as e:
        raise StudyError(fname, where, f"cannot be evaluated for [dynamics]: {e.reason}") from None
    scale = 1.0 + np.max(np.abs(f))
    if np.max(np.ptp(f, axis=0)) > _CHECK_RTOL * scale:
        raise StudyError(fname, where, (
            f"{expr.text!r} depends on both phi and t; [dynamics] accepts a constant, a "
            "2*pi-periodic function of phi, or a function of t alone"))
    return "t"


def check_drive(mechanism, case, file="<study>"):
    """Validate the driving moment of ``case`` and every load of ``mechanism``
    for the dynamics (called by the study parser)."""
    classify_drive(case.M1, case.t_end, file)
    for ld in mechanism.loads:
        for e in (ld.fx, ld.fy, ld.moment):
            classify_drive(e, case.t_end, file)


@dataclass(frozen=True)
class Drive:
    """Drive channels as the kernels take them (see kernels/dynamics.py)."""
    const: np.ndarray          # (n_channels,)
    tab_phi: np.ndarray        # (n_channels, n_intervals or 0, 4)
    h_phi: float
    tab_t: np.ndarray
    h_t: float

    def args(self):
        return (self.const, self.tab_phi, self.h_phi, self.tab_t, self.h_t)


def build_drive(mechanism, M1, t_end=1.0, dt=1e-3, file="<study>") -> Drive:
    """Sample M1 and the mechanism's loads into drive channels."""
    from scipy.interpolate import CubicSpline
    exprs = [M1] + [e for ld in mechanism.loads for e in (ld.fx, ld.fy, ld.moment)]
    kinds = [classify_drive(e, t_end, file) for e in exprs]
    n = len(exprs)
    const = np.zeros(n)
    h_phi = 2.0 * math.pi / PHI_INTERVALS
    n_t = int(min(T_MAX_INTERVALS, max(16, math.ceil(t_end / (T_NODE_STEPS * dt)))))
    h_t = t_end / n_t
    tab_phi = np.zeros((n, PHI_INTERVALS if "phi" in kinds else 0, 4))
    tab_t = np.zeros((n, n_t if "t" in kinds else 0, 4))
    for c, (e, kind) in enumerate(zip(exprs, kinds)):
        if kind == "const":
            const[c] = float(e.evaluate(0.0, 0.0))
        elif kind == "phi":
            x = np.arange(PHI_INTERVALS + 1) * h_phi
            y = e.evaluate(x, 0.0)
            y[-1] = y[0]
            tab_phi[c] = CubicSpline(x, y, bc_type="periodic").c.T
        else:
            x = np.arange(n_t + 1) * h_t
            tab_t[c] = CubicSpline(x, e.evaluate(0.0, x)).c.T
    return Drive(const, tab_phi, h_phi, tab_t, h_t)


def _plan_args(plan, tols):
    """(par, K, tols) of the dynamics kernels: K the constants as an array."""
    return (plan.par, kernels_for(plan).constants_array(plan.par), tols)


# ----------------------------------------------------------------- helpers for tests
def _zero_drive(n_loads):
    """No driving moment and no loads (the channel count must match the plan)."""
    empty = np.zeros((1 + 3 * n_loads, 0, 4))
    return Drive(np.zeros(1 + 3 * n_loads), empty, 1.0, empty, 1.0)


def _curve(plan, phi, t=0.0, mechanism=None, loads=True, tols=None):
    if len(plan.body_names) == 0:
        raise ValueError("crank dynamics needs mass data (bodies)")
    n_loads = len(plan.load_body)
    if loads and n_loads and mechanism is None:
        raise ValueError("the plan has external loads: pass the mechanism that declares them")
    tols = kc.default_tolerances() if tols is None else tols
    phis = np.atleast_1d(np.asarray(phi, dtype=np.float64)).ravel().copy()
    ts = np.broadcast_to(np.asarray(t, dtype=np.float64), np.shape(phi)).ravel().copy()
    if loads and n_loads:
        from ..base.expressions import parse_expression
        t_max = max(1e-3, float(np.max(ts))) if ts.size else 1e-3
        drive = build_drive(mechanism, parse_expression(0.0, "M1"), t_end=t_max,
                            dt=t_max / 2000)
    else:
        drive = _zero_drive(n_loads)
    out = [np.full(phis.shape, np.nan) for _ in range(5)]
    status = np.zeros(phis.shape, np.int8)
    kernels_for(plan).terms_curve(*_plan_args(plan, tols), *drive.args(), phis, ts, *out, status)
    return out, status


def reduced_terms(plan, phi, t=0.0, mechanism=None):
    """(J [kg m^2], (1/2) dJ/dphi [kg m^2], Q without M1 [N m]) at crank
    angle(s) ``phi`` (rad).  ``mechanism`` supplies the load expressions when
    the plan has loads (evaluated at ``t``).  Scalars in, scalars out."""
    (J, half, Q, _m1, _V), _ = _curve(plan, phi, t, mechanism)
    if np.ndim(phi) == 0:
        return float(J[0]), float(half[0]), float(Q[0])
    shape = np.shape(phi)
    return J.reshape(shape), half.reshape(shape), Q.reshape(shape)


def energy(plan, phi, omega):
    """(T, V) [J]: kinetic energy J(phi) omega^2 / 2 and gravitational
    potential sum m g y_S at the states (phi [rad], omega [rad/s])."""
    (J, _h, _Q, _m1, V), _ = _curve(plan, phi, loads=False)
    shape = np.shape(phi)
    T = 0.5 * J * np.broadcast_to(np.asarray(omega, float), J.shape) ** 2
    if len(shape) == 0:
        return float(T[0]), float(V[0])
    return T.reshape(shape), V.reshape(shape)


# ----------------------------------------------------------------- results
def _round(x, digits=6):
    return float(f"{x:.{digits}g}") if math.isfinite(x) else None


# the units of CaseResult.summary's figures (dimensionless ones: none)
SUMMARY_UNITS = {"omega_mean": " rad/s", "rpm": " 1/min", "delta": "", "omega_min": " rad/s",
                 "omega_max": " rad/s", "omega_mean_change": " rad/s", "phi1_end_deg": " deg",
                 "omega1_end": " rad/s", "phi_mid_deg": " deg", "amplitude_deg": " deg",
                 "period_s": " s"}


@dataclass
class CaseResult:
    """The motion of one case: samples every sample_dt and a fine tail."""
    name: str
    t: np.ndarray            # s
    phi1: np.ndarray         # rad
    omega1: np.ndarray       # rad/s
    eps1: np.ndarray         # rad/s^2
    status: int
    method: str
    case: object             # study.DynamicsCase
    tail_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tail_phi1: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tail_omega1: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tail_eps1: np.ndarray = field(default_factory=lambda: np.zeros(0))
    seconds: float = math.nan    # wall time of the integration (compile excluded if warm)

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
        return {k: (f"{v:g}{SUMMARY_UNITS.get(k, '')}" if isinstance(v, float) else str(v))
                for k, v in self.summary().items()}

    def summary(self):
        out = {"status": kc.STATUS_NAMES[self.status], "method": self.method}
        s = self.steady()
        if s is not None:
            out.update(omega_mean=_round(s["omega_mean"]), rpm=_round(s["rpm"], 5),
                       delta=_round(s["delta"], 5),
                       omega_min=_round(s["omega_min"]), omega_max=_round(s["omega_max"]),
                       omega_mean_change=_round(s["omega_mean_change"], 3))
        else:
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


def integrate(plan, mechanism, case, method="rk4", tols=None, file="<study>") -> CaseResult:
    """Integrate one dynamics case (study.DynamicsCase) of the compiled ``plan``."""
    if method not in METHODS:
        raise ValueError(f"unknown integration method {method!r}; known: {', '.join(METHODS)}")
    tols = kc.default_tolerances() if tols is None else tols
    drive = build_drive(mechanism, case.M1, case.t_end, case.dt, file)
    n_sub, n_samples, n_tail = _grid(case)
    out = [np.full(n_samples, np.nan) for _ in range(4)]
    tail = [np.full(n_tail, np.nan) for _ in range(4)]
    t0 = time.perf_counter()
    if method == "rk4":
        status, _ = kernels_for(plan).rk4(*_plan_args(plan, tols), *drive.args(),
                                          float(case.damping), float(case.phi_start), float(case.omega_start),
                        float(case.dt), n_sub, *out, *tail)
    else:
        status = _dop853(plan, drive, case, tols, out, tail)
    seconds = time.perf_counter() - t0
    return CaseResult(case.name, *out, int(status), method, case, *tail, seconds=seconds)


class _Stop(Exception):
    def __init__(self, status):
        self.status = status


def _dop853(plan, drive, case, tols, out, tail):
    """The reference: scipy's DOP853 at rtol = atol = 1e-12 over the compiled
    right-hand side; samples from its dense output, eps1 re-evaluated there.
    A kinematic failure stops it with that status and leaves every sample NaN."""
    from scipy.integrate import solve_ivp
    n = plan.n_points
    kern = kernels_for(plan)
    work = dict(state=np.zeros((kern.N_TRIADS, kc.N_STATE)), last=np.zeros(1),
                pos=np.zeros((n, 2)), d1=np.zeros((n, 2)), d2=np.zeros((n, 2)),
                margins=np.zeros(plan.n_groups + MARGIN_SLOTS), loads_k=np.zeros((len(plan.load_body), 3)))
    pa, da = _plan_args(plan, tols), drive.args()
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
    try:
        restart()
        sol = solve_ivp(rhs, (0.0, ts[-1]), [case.phi_start, case.omega_start],
                        method="DOP853", rtol=DOP853_TOL, atol=DOP853_TOL, dense_output=True)
        if not sol.success:
            log.warning("dynamics %s: DOP853 failed: %s", case.name, sol.message)
            return kc.SINGULAR
        restart()
        for times, dest in ((ts, out), (tt, tail)):
            y = sol.sol(times)
            dest[0][:] = times
            dest[1][:] = y[0]
            dest[2][:] = y[1]
            dest[3][:] = [eps(t, p, w) for t, p, w in zip(times, y[0], y[1])]
    except _Stop as s:
        return s.status
    return kc.OK


def run_dynamics(study, plan, method=None) -> list[CaseResult]:
    """Every case of the study's [dynamics] section, with its method (or ``method``)."""
    spec = study.dynamics
    method = method or spec.method
    results = []
    for case in spec.cases:
        res = integrate(plan, study.mechanism, case, method, file=study.path)
        log.info("dynamics %s (%s): %s, %.2f s", case.name, method,
                 kc.STATUS_NAMES[res.status], res.seconds)
        results.append(res)
    return results


# ----------------------------------------------------------------- reduced dynamics
@dataclass
class Reduced:
    """The crank's reduced dynamics over one revolution (loads at t = 0):
    J(phi), (1/2) dJ/dphi and the generalised force Q(phi) without M1, and
    the equilibria (Q = 0) with their stability."""
    phi: np.ndarray             # rad, absolute crank angle, increasing over [0, 2 pi)
    J: np.ndarray               # kg m^2
    half_dJ: np.ndarray         # kg m^2
    Q: np.ndarray               # N m
    equilibria: list            # (phi deg, stable) where Q = 0

    def summary(self) -> dict:
        if not self.equilibria:
            return {"equilibria": "none (Q does not change sign over the revolution)"}
        return {"equilibria": ", ".join(f"{p:.4f} deg ({'stable' if st else 'unstable'})"
                                        for p, st in self.equilibria)}


def reduced_dynamics(study, plan, n=None) -> Reduced:
    """J, (1/2) J' and Q over the revolution and the equilibria: Q = 0 found
    by Brent's method between samples where Q changes sign; stable where Q
    falls through zero as phi grows (a restoring force)."""
    from scipy.optimize import brentq
    n = n or study.output.dense_positions
    phis = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    J, half, Q = reduced_terms(plan, phis, 0.0, study.mechanism)

    def q(phi):
        return reduced_terms(plan, float(phi), 0.0, study.mechanism)[2]

    eq = []
    for k in range(n):
        a, b = phis[k], phis[k + 1] if k + 1 < n else 2.0 * math.pi
        qa, qb = Q[k], Q[(k + 1) % n]
        if not (np.isfinite(qa) and np.isfinite(qb)) or qa * qb > 0.0 or qa == qb == 0.0:
            continue
        if qb == 0.0 and k + 1 < n:
            continue                  # the root is the next sample's left end
        root = a if qa == 0.0 else brentq(q, a, b, xtol=1e-13)
        eq.append((math.degrees(root) % 360.0, bool(qa > qb)))
    return Reduced(phis, J, half, Q, eq)


def with_changes(case, **changes):
    """A copy of a DynamicsCase with some fields changed (e.g. damping=0)."""
    if "M1" in changes and not hasattr(changes["M1"], "evaluate"):
        from ..base.expressions import parse_expression
        changes["M1"] = parse_expression(changes["M1"], "M1")
    return replace(case, **changes)
