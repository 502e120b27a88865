"""The RPR dyad's kernel (the coulisse).

Conventions of ``pipeline.kernels.groups``: points read from and written to
``pos``/``d1``/``d2`` to ``order``; returns (status, margin)."""

import math

from numba import njit

from ...kernels.config import JIT, BAD_GEOMETRY, NO_ASSEMBLY, OK, SINGULAR
from ...kernels.groups import _nan_point as nan_point

__all__ = ("rpr",)


@njit(**JIT)
def rpr(pos, d1, d2, ia, ic, ib, offset, guide_length, w, order, sing_tol, slack):
    """RPR dyad (coulisse): a block pinned at known A slides on a guide that
    turns about C; the guide line runs at perpendicular distance ``offset``
    from C.  Solves the guide angle th and writes the guide's end point
    B = C + guide_length (cos th, sin th).

    A - C = s u + e n in the guide frame, s = w sqrt(|A-C|^2 - e^2),
    th = atan2(A - C) - atan2(e, s).  Returns margin = |s| / guide_length
    (0 when the block sits on the pivot: the guide angle is undefined).
    """
    dx = pos[ia, 0] - pos[ic, 0]
    dy = pos[ia, 1] - pos[ic, 1]
    rho2 = dx * dx + dy * dy
    q2 = rho2 - offset * offset
    toggle = False
    if not q2 >= 0.0:
        if not q2 >= -slack * offset * offset:
            nan_point(pos, d1, d2, ib)
            return NO_ASSEMBLY, 0.0
        q2 = 0.0          # rounding at the toggle: the block at the foot of the perpendicular
        toggle = True
    if not guide_length > 0.0:
        nan_point(pos, d1, d2, ib)
        return BAD_GEOMETRY, 0.0
    s = w * math.sqrt(q2)
    th = math.atan2(dy, dx) - math.atan2(offset, s)
    ux = math.cos(th)
    uy = math.sin(th)
    nx = -uy
    ny = ux
    pos[ib, 0] = pos[ic, 0] + guide_length * ux
    pos[ib, 1] = pos[ic, 1] + guide_length * uy
    margin = abs(s) / guide_length
    status = OK
    if toggle or not margin >= sing_tol:
        status = SINGULAR
    if order >= 1:
        if status == SINGULAR:
            for k in range(2):
                d1[ib, k] = math.nan
                d2[ib, k] = math.nan
            return status, margin
        e1x = d1[ia, 0] - d1[ic, 0]
        e1y = d1[ia, 1] - d1[ic, 1]
        th1 = (e1x * nx + e1y * ny) / s
        d1[ib, 0] = d1[ic, 0] + guide_length * th1 * nx
        d1[ib, 1] = d1[ic, 1] + guide_length * th1 * ny
        if order >= 2:
            e2x = d2[ia, 0] - d2[ic, 0]
            e2y = d2[ia, 1] - d2[ic, 1]
            th2 = ((e2x * nx + e2y * ny) - 2.0 * th1 * (e1x * ux + e1y * uy)
                   - th1 * th1 * offset) / s
            d2[ib, 0] = d2[ic, 0] + guide_length * (th2 * nx - th1 * th1 * ux)
            d2[ib, 1] = d2[ic, 1] + guide_length * (th2 * ny - th1 * th1 * uy)
    return status, margin
