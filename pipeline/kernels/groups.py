"""Structural groups: the crank, class II dyads (RRR, RRP, RPR, PRP, RPP), attached points.

Every group reads already-solved points from ``pos``/``d1``/``d2`` (shape
(n_points, 2): position, first and second analogs with respect to phi1) and
writes the point(s) it solves.  ``order`` says how far to go: 0 positions,
1 with first analogs, 2 with second analogs.  Each returns (status, margin):
margin is the normalised distance from a toggle (|sin| of the transmission
angle for RRR, and so on), used for SINGULAR detection and reported metrics.
Analogs come from differentiating each group's closure equations, never from
finite differences.
"""

import math

from numba import njit

from .config import BAD_GEOMETRY, JIT, NO_ASSEMBLY, OK, SINGULAR
from .geometry import angle_analogs, circle_intersection, solve2


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
def rrr(pos, d1, d2, ia, ic, ib, l_ab, l_cb, w, order, sing_tol, slack):
    """RRR dyad: B joined to known A by link A-B and to known C by link C-B."""
    if not (l_ab > 0.0 and l_cb > 0.0):
        _nan_point(pos, d1, d2, ib)
        return BAD_GEOMETRY, 0.0
    ok, bx, by, toggle = circle_intersection(pos[ia, 0], pos[ia, 1], pos[ic, 0], pos[ic, 1],
                                             l_ab, l_cb, w, slack)
    if not ok:
        _nan_point(pos, d1, d2, ib)
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


@njit(**JIT)
def _direction(pos, d1, d2, ga, gb, angle, order):
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
def rrp(pos, d1, d2, ia, ig, ib, ga, gb, l_ab, angle, w, order, sing_tol, slack):
    """RRP dyad: slider B on a guide line through G, joined to known A by link A-B.

    The guide direction is fixed (ga < 0, absolute ``angle``) or turns with the
    link ga->gb (``angle`` relative to it).  B = G + s u with
    s = u.(A - G) + w sqrt(L^2 - h^2), h the distance of A from the guide.
    """
    if not l_ab > 0.0:
        _nan_point(pos, d1, d2, ib)
        return BAD_GEOMETRY, 0.0
    th, th1, th2 = _direction(pos, d1, d2, ga, gb, angle, order)
    if not math.isfinite(th):   # the guide link has no length: no direction
        _nan_point(pos, d1, d2, ib)
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
            _nan_point(pos, d1, d2, ib)
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
            _nan_point(pos, d1, d2, ib)
            return NO_ASSEMBLY, 0.0
        q2 = 0.0          # rounding at the toggle: the block at the foot of the perpendicular
        toggle = True
    if not guide_length > 0.0:
        _nan_point(pos, d1, d2, ib)
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


@njit(**JIT)
def _line_meet(pos, d1, d2, ib, g1, th1, t11, t12, e1, g2, th2, t21, t22, e2, order, sing_tol):
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
def prp(pos, d1, d2, ig1, ga1, gb1, ig2, ga2, gb2, ib, angle1, offset1, angle2, offset2,
        order, sing_tol):
    """PRP dyad: two blocks joined by the revolute B, each sliding on a known
    guide.  Guide i runs through the known point G_i with a fixed direction
    (ga_i < 0: the absolute ``angle_i``) or one that turns with the link
    ga_i->gb_i (``angle_i`` relative to it); block i carries B at the
    perpendicular distance ``offset_i`` from its guide (on the +90 deg side).
    B is where the two lines of B meet (``_line_meet``); the margin |sin| of
    the angle between the guides is 0 where they are parallel (SINGULAR)."""
    th1, t11, t12 = _direction(pos, d1, d2, ga1, gb1, angle1, order)
    th2, t21, t22 = _direction(pos, d1, d2, ga2, gb2, angle2, order)
    if not (math.isfinite(th1) and math.isfinite(th2)):   # a guide link of no length
        _nan_point(pos, d1, d2, ib)
        return SINGULAR, 0.0
    return _line_meet(pos, d1, d2, ib, ig1, th1, t11, t12, offset1, ig2, th2, t21, t22,
                      offset2, order, sing_tol)


@njit(**JIT)
def rpp(pos, d1, d2, ia, ig, ga, gb, ib, guide_angle, guide_offset, slot_angle, slot_offset,
        order, sing_tol):
    """RPP dyad (Scotch yoke): a block pinned at the known point A slides in a
    slot of the yoke, and the yoke slides on a guide.  The guide runs through
    the known point G with a fixed direction (ga < 0: absolute
    ``guide_angle``) or one that turns with the link ga->gb (``guide_angle``
    relative to it); the yoke's reference point B travels on the line at the
    perpendicular distance ``guide_offset`` from it.  The slot is fixed in the
    yoke at ``slot_angle`` from the guide, and A runs on it at the distance
    ``slot_offset`` from the slot's line through B.  So B is where the yoke's
    line and the slot's line through A (shifted back by the offset) meet:

        (B - G) . n_g = guide_offset,  (B - A) . n_s = -slot_offset,

    n = the direction turned +90 deg.  The margin |sin slot_angle| does not
    change with the crank (0: the slot runs along the guide, SINGULAR)."""
    th, t1, t2 = _direction(pos, d1, d2, ga, gb, guide_angle, order)
    if not math.isfinite(th):
        _nan_point(pos, d1, d2, ib)
        return SINGULAR, 0.0
    return _line_meet(pos, d1, d2, ib, ig, th, t1, t2, guide_offset, ia, th + slot_angle,
                      t1, t2, -slot_offset, order, sing_tol)


@njit(**JIT)
def attach(pos, d1, d2, ibase, ia, ib, io, angle, length, order):
    """Point rigidly attached to a link: P = base + rot(Pa->Pb, angle, length).

    With ia < 0 the direction is fixed: P = base + length (cos angle, sin angle)
    (a point of a translating body).
    """
    th, th1, th2 = _direction(pos, d1, d2, ia, ib, angle, order)
    if ia >= 0:
        dx = pos[ib, 0] - pos[ia, 0]
        dy = pos[ib, 1] - pos[ia, 1]
        if not (dx * dx + dy * dy > 0.0):
            _nan_point(pos, d1, d2, io)
            return SINGULAR, 0.0
    return polar_point(pos, d1, d2, ibase, io, length, th, th1, th2, order)
