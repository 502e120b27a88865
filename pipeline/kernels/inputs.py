"""Driven inputs besides the crank, and the laws that move them.

A machine's cycle is one revolution of the main crank: its angle phi1 is the
cycle angle.  Every other input is moved by a law of phi1 (a cam, a gear
train or a linear actuator programmed against the main shaft), so the
mechanism keeps one degree of freedom and every analog stays a derivative
with respect to phi1:

* a rotary input turns a link about a fixed pivot to the absolute angle
  q(phi1): an oscillating rocker (harmonic, cycloidal or tabulated swing) or
  a second crank geared to the first (linear law q = phase + ratio * phi1);
* a slider input moves a block along a fixed guide to the stroke q(phi1).

Each law returns (q, dq/dphi1, d2q/dphi1^2), exact (a periodic spline for a
table: its derivatives are those of the spline, continuous to the second).

Rise-and-return laws (harmonic, cycloidal): from the cycle angle ``phase``
the input rises by ``travel`` from ``start`` over ``rise`` rad of the cycle,
then returns over the rest of the cycle (2 pi - rise), the return being the
rise played backwards.  With x the fraction of the rise:

* harmonic: f(x) = (1 - cos(pi x)) / 2 (with rise = pi, a pure cosine:
  q = start + travel (1 - cos(phi1 - phase)) / 2; with another rise the
  acceleration jumps at the turning points, as a harmonic cam's does);
* cycloidal: f(x) = x - sin(2 pi x) / (2 pi) (zero velocity and acceleration
  at both ends: no jump anywhere).
"""

import math

from numba import njit

from .config import BAD_GEOMETRY, JIT, OK
from .groups import _nan_point, polar_point

TWO_PI = 2.0 * math.pi

# law codes of the plan (``Plan.input_law``)
LAW_LINEAR = 0
LAW_HARMONIC = 1
LAW_CYCLOIDAL = 2
LAW_TABLE = 3
LAW_NAMES = {LAW_LINEAR: "linear", LAW_HARMONIC: "harmonic", LAW_CYCLOIDAL: "cycloidal",
             LAW_TABLE: "table"}

# input kinds (``Plan.input_kind``)
ROTARY = 0
SLIDER = 1


@njit(**JIT)
def linear_law(phi, ratio, phase):
    """q = phase + ratio * phi: a second crank geared to the first."""
    return phase + ratio * phi, ratio, 0.0


@njit(**JIT)
def rise_return(phi, start, travel, phase, rise, cycloidal):
    """A rise from ``start`` by ``travel`` over ``rise`` rad of the cycle from
    ``phase``, and the return over the rest: harmonic or cycloidal."""
    u = phi - phase
    u -= TWO_PI * math.floor(u / TWO_PI)       # cycle angle since the rise began, [0, 2 pi)
    if u < rise:
        x = u / rise
        s = 1.0 / rise                         # dx/dphi
    else:
        x = (TWO_PI - u) / (TWO_PI - rise)
        s = -1.0 / (TWO_PI - rise)
    if cycloidal:
        w = TWO_PI * x
        f = x - math.sin(w) / TWO_PI
        f1 = 1.0 - math.cos(w)
        f2 = TWO_PI * math.sin(w)
    else:
        w = math.pi * x
        f = 0.5 * (1.0 - math.cos(w))
        f1 = 0.5 * math.pi * math.sin(w)
        f2 = 0.5 * math.pi * math.pi * math.cos(w)
    return start + travel * f, travel * f1 * s, travel * f2 * s * s


@njit(**JIT)
def table_law(phi, phase, knots, coef):
    """The periodic cubic spline through a table: ``knots`` (n + 1) cycle
    angles from t0 to t0 + 2 pi, ``coef`` (4, n) its piecewise polynomial
    coefficients (scipy's PPoly layout: q = sum_m coef[m, k] d^(3 - m) with
    d = u - knots[k]), evaluated at u = phi - phase brought into the period."""
    n = coef.shape[1]
    t0 = knots[0]
    u = phi - phase - t0
    u = u - TWO_PI * math.floor(u / TWO_PI) + t0
    lo = 0
    hi = n                                     # knots[lo] <= u < knots[hi]
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if u >= knots[mid]:
            lo = mid
        else:
            hi = mid
    d = u - knots[lo]
    c0 = coef[0, lo]
    c1 = coef[1, lo]
    c2 = coef[2, lo]
    c3 = coef[3, lo]
    return (((c0 * d + c1) * d + c2) * d + c3, (3.0 * c0 * d + 2.0 * c1) * d + c2,
            6.0 * c0 * d + 2.0 * c1)


@njit(**JIT)
def rotary_input(pos, d1, d2, ip, io, length, q, q1, q2, order):
    """Input link turned about the fixed pivot ``ip`` to the absolute angle q:
    tip ``io`` = pivot + length e(q), analogs from q' and q''."""
    if not length > 0.0:
        _nan_point(pos, d1, d2, io)
        return BAD_GEOMETRY, 0.0
    return polar_point(pos, d1, d2, ip, io, length, q, q1, q2, order)


@njit(**JIT)
def slider_input(pos, d1, d2, ig, ib, cos_g, sin_g, q, q1, q2, order):
    """Input block moved along the fixed guide through ``ig`` with direction
    (cos_g, sin_g) to the stroke q: block ``ib`` = guide point + q u."""
    pos[ib, 0] = pos[ig, 0] + q * cos_g
    pos[ib, 1] = pos[ig, 1] + q * sin_g
    if order >= 1:
        d1[ib, 0] = d1[ig, 0] + q1 * cos_g
        d1[ib, 1] = d1[ig, 1] + q1 * sin_g
    if order >= 2:
        d2[ib, 0] = d2[ig, 0] + q2 * cos_g
        d2[ib, 1] = d2[ig, 1] + q2 * sin_g
    return OK, 1.0
