"""The RRP dyad's kernel: a slider on a guide joined by a link to a known point.

Conventions of ``pipeline.kernels.groups``: points read from and written to
``pos``/``d1``/``d2`` to ``order``; returns (status, margin)."""

import math

from numba import njit

from ...kernels.config import JIT, BAD_GEOMETRY, NO_ASSEMBLY, OK, SINGULAR
from ...kernels.groups import _nan_point as nan_point, guide_direction

__all__ = ("rrp",)


@njit(**JIT)
def rrp(pos, d1, d2, ia, ig, ib, ga, gb, l_ab, angle, w, order, sing_tol, slack):
    """RRP dyad: slider B on a guide line through G, joined to known A by link A-B.

    The guide direction is fixed (ga < 0, absolute ``angle``) or turns with the
    link ga->gb (``angle`` relative to it).  B = G + s u with
    s = u.(A - G) + w sqrt(L^2 - h^2), h the distance of A from the guide.
    """
    if not l_ab > 0.0:
        nan_point(pos, d1, d2, ib)
        return BAD_GEOMETRY, 0.0
    th, th1, th2 = guide_direction(pos, d1, d2, ga, gb, angle, order)
    if not math.isfinite(th):   # the guide link has no length: no direction
        nan_point(pos, d1, d2, ib)
        return SINGULAR, 0.0
    ux = math.cos(th)
    uy = math.sin(th)
    nx = -uy
    ny = ux
    dx = pos[ia, 0] - pos[ig, 0]
    dy = pos[ia, 1] - pos[ig, 1]
    p = ux * dx + uy * dy
    h = nx * dx + ny * dy
    q2 = l_ab * l_ab - h * h
    toggle = False
    if q2 < 0.0:
        if q2 < -slack * l_ab * l_ab:
            nan_point(pos, d1, d2, ib)
            return NO_ASSEMBLY, 0.0
        q2 = 0.0
        toggle = True
    q = math.sqrt(q2)
    s = p + w * q
    pos[ib, 0] = pos[ig, 0] + s * ux
    pos[ib, 1] = pos[ig, 1] + s * uy
    margin = q / l_ab  # |cos| of the angle between link A-B and the guide
    status = OK
    if toggle or not margin >= sing_tol:
        status = SINGULAR
    if order >= 1:
        if status == SINGULAR:
            for k in range(2):
                d1[ib, k] = math.nan
                d2[ib, k] = math.nan
            return status, margin
        rx = pos[ib, 0] - pos[ia, 0]
        ry = pos[ib, 1] - pos[ia, 1]
        ru = rx * ux + ry * uy
        # B' = G' + s' u + s th' n ; r.(B' - A') = 0
        tx = d1[ig, 0] + s * th1 * nx - d1[ia, 0]
        ty = d1[ig, 1] + s * th1 * ny - d1[ia, 1]
        s1 = -(rx * tx + ry * ty) / ru
        vx = d1[ig, 0] + s1 * ux + s * th1 * nx
        vy = d1[ig, 1] + s1 * uy + s * th1 * ny
        d1[ib, 0] = vx
        d1[ib, 1] = vy
        if order >= 2:
            # B'' = G'' + s'' u + 2 s' th' n + s (th'' n - th'^2 u)
            # r.(B'' - A'') + |B' - A'|^2 = 0
            ex = d2[ig, 0] + 2.0 * s1 * th1 * nx + s * (th2 * nx - th1 * th1 * ux) - d2[ia, 0]
            ey = d2[ig, 1] + 2.0 * s1 * th1 * ny + s * (th2 * ny - th1 * th1 * uy) - d2[ia, 1]
            wx = vx - d1[ia, 0]
            wy = vy - d1[ia, 1]
            s2 = -((wx * wx + wy * wy) + rx * ex + ry * ey) / ru
            d2[ib, 0] = ex + d2[ia, 0] + s2 * ux
            d2[ib, 1] = ey + d2[ia, 1] + s2 * uy
    return status, margin
