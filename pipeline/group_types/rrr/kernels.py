"""The RRR dyad's kernel: B from two known points and two link lengths.

Conventions of ``pipeline.kernels.groups``: points read from and written to
``pos``/``d1``/``d2`` to ``order``; returns (status, margin)."""

import math

from numba import njit

from ...kernels.config import JIT, BAD_GEOMETRY, NO_ASSEMBLY, OK, SINGULAR
from ...kernels.geometry import circle_intersection, solve2
from ...kernels.groups import _nan_point as nan_point

__all__ = ("rrr",)


@njit(**JIT)
def rrr(pos, d1, d2, ia, ic, ib, l_ab, l_cb, w, order, sing_tol, slack):
    """RRR dyad: B joined to known A by link A-B and to known C by link C-B."""
    if not (l_ab > 0.0 and l_cb > 0.0):
        nan_point(pos, d1, d2, ib)
        return BAD_GEOMETRY, 0.0
    ok, bx, by, toggle = circle_intersection(pos[ia, 0], pos[ia, 1], pos[ic, 0], pos[ic, 1],
                                             l_ab, l_cb, w, slack)
    if not ok:
        nan_point(pos, d1, d2, ib)
        return NO_ASSEMBLY, 0.0
    pos[ib, 0] = bx
    pos[ib, 1] = by
    # closure: (B-A).(B-A) = l_ab^2, (B-C).(B-C) = l_cb^2
    pax = bx - pos[ia, 0]
    pay = by - pos[ia, 1]
    pcx = bx - pos[ic, 0]
    pcy = by - pos[ic, 1]
    margin = abs(pax * pcy - pay * pcx) / (l_ab * l_cb)  # |sin| of the angle at B
    status = OK
    if toggle or not margin >= sing_tol:     # (NaN-safe: a NaN margin is singular)
        status = SINGULAR
    if order >= 1:
        if status == SINGULAR:
            for k in range(2):
                d1[ib, k] = math.nan
                d2[ib, k] = math.nan
            return status, margin
        r1 = pax * d1[ia, 0] + pay * d1[ia, 1]
        r2 = pcx * d1[ic, 0] + pcy * d1[ic, 1]
        vx, vy = solve2(pax, pay, pcx, pcy, r1, r2)
        d1[ib, 0] = vx
        d1[ib, 1] = vy
        if order >= 2:
            ux = vx - d1[ia, 0]
            uy = vy - d1[ia, 1]
            wx = vx - d1[ic, 0]
            wy = vy - d1[ic, 1]
            r1 = pax * d2[ia, 0] + pay * d2[ia, 1] - (ux * ux + uy * uy)
            r2 = pcx * d2[ic, 0] + pcy * d2[ic, 1] - (wx * wx + wy * wy)
            ax, ay = solve2(pax, pay, pcx, pcy, r1, r2)
            d2[ib, 0] = ax
            d2[ib, 1] = ay
    return status, margin
