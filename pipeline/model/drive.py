"""How the crank's driving moment M1 and each component of the external loads
enter the dynamics: a constant, a 2*pi-periodic function of phi1, or a function
of t alone (``classify_drive``); anything else is refused when the study is read,
naming the field (``check_drive``, called by the study's [dynamics] reader).  The
drive channels the kernels take are ``solve.crank_drive``'s."""

from __future__ import annotations

import math

import numpy as np

from ..base.errors import StudyError

_PERIODIC_GRID = 97         # phi samples of the periodicity / dependence checks
_T_GRID = 23
_CHECK_RTOL = 1e-9


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
