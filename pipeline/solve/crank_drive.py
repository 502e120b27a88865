"""The crank's driving moment and the external loads as the dynamics kernels take
them (``Drive``): each of M1 and the load components a constant, a periodic
spline of phi1 (PHI_INTERVALS intervals per revolution) or a spline of t (a
node every T_NODE_STEPS steps); anything else is refused when the study is
read, naming the field (``classify_drive``, ``check_drive``).  The equation of
motion and its integration are ``crank_motion``'s."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..base.errors import StudyError

PHI_INTERVALS = 4096        # periodic spline intervals per revolution (phi tables)
T_NODE_STEPS = 2            # time tables: one node every T_NODE_STEPS integration steps
T_MAX_INTERVALS = 400_000
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
