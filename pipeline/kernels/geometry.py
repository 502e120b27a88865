"""Planar geometry primitives: rotation, circle intersection, angle analogs."""

import math

from numba import njit

from .config import JIT


@njit(**JIT)
def rot(x, y, alpha, length):
    """The vector (x, y) rotated by alpha about +Z and rescaled to ``length``."""
    n = math.hypot(x, y)
    c = math.cos(alpha)
    s = math.sin(alpha)
    return length * (c * x - s * y) / n, length * (s * x + c * y) / n


@njit(**JIT)
def circle_intersection(ax, ay, cx, cy, l_ab, l_cb, w, slack):
    """Point B at distance l_ab from A and l_cb from C (DOMAIN.md section 2).

    r = A - C, U = arccos((|r|^2 + l_cb^2 - l_ab^2) / (2 |r| l_cb)),
    C->B = rot(r, -w U, l_cb).  Returns (ok, bx, by, toggle): ok is False when
    the cosine-law argument leaves [-1 - slack, 1 + slack]; toggle is True when
    it had to be clamped (the two circles touch).
    """
    rx = ax - cx
    ry = ay - cy
    r2 = rx * rx + ry * ry
    r = math.sqrt(r2)
    if not (r > 0.0):
        return False, math.nan, math.nan, False
    arg = (r2 + l_cb * l_cb - l_ab * l_ab) / (2.0 * r * l_cb)
    toggle = False
    if arg > 1.0:
        if arg > 1.0 + slack:
            return False, math.nan, math.nan, False
        arg = 1.0
        toggle = True
    elif arg < -1.0:
        if arg < -1.0 - slack:
            return False, math.nan, math.nan, False
        arg = -1.0
        toggle = True
    u = math.acos(arg)
    bx, by = rot(rx, ry, -w * u, l_cb)
    return True, cx + bx, cy + by, toggle


@njit(**JIT)
def angle_analogs(dx, dy, d1x, d1y, d2x, d2y):
    """Angle of the vector d and its exact first and second analogs.

    theta = atan2(dy, dx); theta' = (d x d') / |d|^2;
    theta'' = (d x d'') / |d|^2 - 2 (d . d') (d x d') / |d|^4.
    """
    r2 = dx * dx + dy * dy
    c1 = dx * d1y - dy * d1x
    c2 = dx * d2y - dy * d2x
    th1 = c1 / r2
    th2 = c2 / r2 - 2.0 * (dx * d1x + dy * d1y) * c1 / (r2 * r2)
    return math.atan2(dy, dx), th1, th2


@njit(**JIT)
def solve2(a11, a12, a21, a22, b1, b2):
    """Cramer's rule for a 2x2 system; inf/nan when singular (numpy error model)."""
    det = a11 * a22 - a12 * a21
    return (b1 * a22 - a12 * b2) / det, (a11 * b2 - b1 * a21) / det


@njit(**JIT)
def link_angles(pos, d1, d2, ia, ib, order, out):
    """Angle of every link ia[j] -> ib[j] and its analogs, for every position.

    pos/d1/d2: (n_phi, n_points, 2); out: (n_phi, n_links, 3) = (phi, phi', phi'').
    """
    for k in range(pos.shape[0]):
        for j in range(ia.shape[0]):
            a = ia[j]
            b = ib[j]
            dx = pos[k, b, 0] - pos[k, a, 0]
            dy = pos[k, b, 1] - pos[k, a, 1]
            if order >= 1:
                e2x = d2[k, b, 0] - d2[k, a, 0] if order >= 2 else 0.0
                e2y = d2[k, b, 1] - d2[k, a, 1] if order >= 2 else 0.0
                th, th1, th2 = angle_analogs(dx, dy, d1[k, b, 0] - d1[k, a, 0],
                                      d1[k, b, 1] - d1[k, a, 1], e2x, e2y)
                out[k, j, 0] = th
                out[k, j, 1] = th1
                out[k, j, 2] = th2 if order >= 2 else math.nan
            else:
                out[k, j, 0] = math.atan2(dy, dx)
                out[k, j, 1] = math.nan
                out[k, j, 2] = math.nan



# below this share of the square of a running peak, a length cannot reach the peak
_REACH = 1.0 - 1e-9


@njit(inline='always', **JIT)
def may_reach(x, y, peak):
    """False only where |(x, y)| is certainly below ``peak`` (>= 0): a running
    maximum then needs no ``math.hypot`` (a library call) for this vector.
    hypot is within an ulp of the exact length and x^2 + y^2 within a few of
    its square, so below (1 - 1e-9) peak^2 the hypot is below the peak and the
    maximum is the same to the bit; NaN, inf and a negative peak (none yet)
    give True, so they reach the caller's own test."""
    return not (peak >= 0.0 and x * x + y * y < _REACH * peak * peak)
