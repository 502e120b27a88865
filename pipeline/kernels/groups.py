"""The kernels of the mechanism's own elements (the crank, a point attached to a
link: ``attach``, ``polar_point``) and the pieces the group types' kernels share
(a guide's direction, two guide lines' meet); each structural group's kernels
are in its folder of ``pipeline.group_types``.

Every kernel reads already-solved points from ``pos``/``d1``/``d2`` (shape
(n_points, 2): position, first and second analogs with respect to phi1) and
writes the point(s) it solves.  ``order`` says how far to go: 0 positions,
1 with first analogs, 2 with second analogs.  Each returns (status, margin):
margin is the normalised distance from a toggle, used for SINGULAR detection
and reported metrics.  Analogs come from differentiating the closure
equations, never from finite differences.
"""

import math

from numba import njit

from .config import JIT, OK, SINGULAR
from .geometry import angle_analogs, solve2


@njit(**JIT)
def _nan_point(pos, d1, d2, i):
    for k in range(2):
        pos[i, k] = math.nan
        d1[i, k] = math.nan
        d2[i, k] = math.nan


@njit(**JIT)
def polar_point(pos, d1, d2, ibase, io, length, th, th1, th2, order):
    """Point ``io`` = base + length e(th), its analogs from th' and th'' (an
    attached point, an input's tip)."""
    c = math.cos(th)
    s = math.sin(th)
    pos[io, 0] = pos[ibase, 0] + length * c
    pos[io, 1] = pos[ibase, 1] + length * s
    if order >= 1:
        d1[io, 0] = d1[ibase, 0] - length * th1 * s
        d1[io, 1] = d1[ibase, 1] + length * th1 * c
    if order >= 2:
        d2[io, 0] = d2[ibase, 0] - length * (th2 * s + th1 * th1 * c)
        d2[io, 1] = d2[ibase, 1] + length * (th2 * c - th1 * th1 * s)
    return OK, 1.0


@njit(**JIT)
def crank(pos, d1, d2, ip, io, length, phi_m0, phi1, order):
    """Crank tip: P = pivot + L (cos(phi1 + phiM0), sin(phi1 + phiM0))."""
    ang = phi1 + phi_m0
    c = math.cos(ang)
    s = math.sin(ang)
    pos[io, 0] = pos[ip, 0] + length * c
    pos[io, 1] = pos[ip, 1] + length * s
    if order >= 1:
        d1[io, 0] = d1[ip, 0] - length * s
        d1[io, 1] = d1[ip, 1] + length * c
    if order >= 2:
        d2[io, 0] = d2[ip, 0] - length * c
        d2[io, 1] = d2[ip, 1] - length * s
    return OK, 1.0


@njit(**JIT)
def guide_direction(pos, d1, d2, ga, gb, angle, order):
    """Direction angle of a guide and its analogs: fixed (ga < 0) or the angle
    of the link ga->gb plus ``angle``."""
    if ga < 0:
        return angle, 0.0, 0.0
    dx = pos[gb, 0] - pos[ga, 0]
    dy = pos[gb, 1] - pos[ga, 1]
    if not (dx * dx + dy * dy > 0.0):
        return math.nan, math.nan, math.nan
    if order >= 1:
        th, th1, th2 = angle_analogs(dx, dy, d1[gb, 0] - d1[ga, 0], d1[gb, 1] - d1[ga, 1],
                                     d2[gb, 0] - d2[ga, 0], d2[gb, 1] - d2[ga, 1])
        if order < 2:
            th2 = math.nan
    else:
        th, th1, th2 = math.atan2(dy, dx), math.nan, math.nan
    return th + angle, th1, th2


@njit(**JIT)
def line_meet(pos, d1, d2, ib, g1, th1, t11, t12, e1, g2, th2, t21, t22, e2, order, sing_tol):
    """B where two guide lines meet: line i runs through the known point g_i
    (its analogs in d1/d2) with direction u_i = e(th_i) (analogs t_i1, t_i2) at
    the perpendicular offset e_i along n_i = e(th_i + 90 deg), i.e.
    (B - G_i) . n_i = e_i.  The two conditions are linear in B:

        B = G1 + e1 n1 + s1 u1,  s1 = (e2 - e1 n1.n2 - (G1 - G2).n2) / (u1.n2);

    differentiated, n_i . B' = n_i . G_i' + t_i1 s_i and
    n_i . B'' = n_i . G_i'' + 2 t_i1 (B' - G_i') . u_i + t_i2 s_i + t_i1^2 e_i,
    s_i = (B - G_i) . u_i: two 2x2 systems with the matrix rows n1, n2.
    Returns (status, margin), margin = |sin| of the angle between the lines
    (|u1 x u2|, 0 where they are parallel: no meet, or no unique one)."""
    u1x = math.cos(th1)
    u1y = math.sin(th1)
    u2x = math.cos(th2)
    u2y = math.sin(th2)
    n1x = -u1y
    n1y = u1x
    n2x = -u2y
    n2y = u2x
    den = u1x * n2x + u1y * n2y            # u1 . n2 = -(u1 x u2)
    margin = abs(den)
    if not (margin >= sing_tol):           # parallel guides (NaN-safe)
        _nan_point(pos, d1, d2, ib)
        return SINGULAR, margin
    gx = pos[g1, 0] - pos[g2, 0]
    gy = pos[g1, 1] - pos[g2, 1]
    s1 = (e2 - e1 * (n1x * n2x + n1y * n2y) - (gx * n2x + gy * n2y)) / den
    bx = pos[g1, 0] + e1 * n1x + s1 * u1x
    by = pos[g1, 1] + e1 * n1y + s1 * u1y
    pos[ib, 0] = bx
    pos[ib, 1] = by
    if order >= 1:
        s2 = (bx - pos[g2, 0]) * u2x + (by - pos[g2, 1]) * u2y
        r1 = n1x * d1[g1, 0] + n1y * d1[g1, 1] + t11 * s1
        r2 = n2x * d1[g2, 0] + n2y * d1[g2, 1] + t21 * s2
        vx, vy = solve2(n1x, n1y, n2x, n2y, r1, r2)
        d1[ib, 0] = vx
        d1[ib, 1] = vy
        if order >= 2:
            r1 = (n1x * d2[g1, 0] + n1y * d2[g1, 1]
                  + 2.0 * t11 * ((vx - d1[g1, 0]) * u1x + (vy - d1[g1, 1]) * u1y)
                  + t12 * s1 + t11 * t11 * e1)
            r2 = (n2x * d2[g2, 0] + n2y * d2[g2, 1]
                  + 2.0 * t21 * ((vx - d1[g2, 0]) * u2x + (vy - d1[g2, 1]) * u2y)
                  + t22 * s2 + t21 * t21 * e2)
            ax, ay = solve2(n1x, n1y, n2x, n2y, r1, r2)
            d2[ib, 0] = ax
            d2[ib, 1] = ay
    return OK, margin


@njit(**JIT)
def attach(pos, d1, d2, ibase, ia, ib, io, angle, length, order):
    """Point rigidly attached to a link: P = base + rot(Pa->Pb, angle, length).

    With ia < 0 the direction is fixed: P = base + length (cos angle, sin angle)
    (a point of a translating body).
    """
    th, th1, th2 = guide_direction(pos, d1, d2, ia, ib, angle, order)
    if ia >= 0:
        dx = pos[ib, 0] - pos[ia, 0]
        dy = pos[ib, 1] - pos[ia, 1]
        if not (dx * dx + dy * dy > 0.0):
            _nan_point(pos, d1, d2, io)
            return SINGULAR, 0.0
    return polar_point(pos, d1, d2, ibase, io, length, th, th1, th2, order)
