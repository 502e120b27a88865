"""Between-sample watch: no failure hidden between two crank positions.

A walk solves a mechanism at a sequence of crank angles; a group can fail
between two of them and be whole again at both (a crank that cannot pass a
range narrower than the step, a parallelogram that passes its collinear
position and comes back as the antiparallelogram).  Every group that can fail
has a margin m (its kernel's, ``pipeline.group_types``): for instance |sin|
of the transmission angle of a two-link dyad, |cos| of the link against the
guide of a slider dyad, |det J| scaled of a class III group.  Its square
D = m^2 is a smooth function of the crank angle (for a dyad a polynomial of
the known points: the assembly discriminant, negative where the dyad cannot be
assembled); D reaches zero exactly where the group folds or passes a toggle.

The certificate of an interval uses what the walk already has: D at three
consecutive positions.  The quadratic through them bounds D between them up
to its cubic term, whose size the third divided difference of four positions
estimates (``window_score``).  Where the quadratic may come within
``tols[T_WATCH]`` of zero (or below), the walk looks closely: it re-solves the
interval at finer steps, again under the certificate, zooming in on the
suspicious part, until the interval is cleared, a position fails (then the
boundary is bisected to ``tols[T_LOCATE]``), or the minimum is resolved (at
or below ``tols[T_TOUCH]``: a toggle between positions, SINGULAR).  The
refinement is generated per mechanism (``pipeline.compiler.generate``); these
are its numbers.

A class III group's D is that of its solution, which exists only where the
group assembles: across a short range where it does not, the walk may land
on the solutions beyond it, and D at the positions on either side knows
nothing of the range.  The continuation sees it coming instead: D falls
linearly into the fold where the range begins, and no step goes more than
FOLD_SHARE of the way to where D's line reaches zero
(``pipeline.kernels.continuation.fold_limit``); the lanes hand such a window
to the careful path.
"""

import math

from numba import njit

from .config import JIT

SUB = 8                 # sub-positions of an interval looked at closely
FOLD_BACK = 1e-6        # rad: a fold's margin^2 is extrapolated from this far short of it
LOCATE_MIN_STEP = 1.0 / 64.0   # a trial's fewest halvings while a boundary is bisected
                               # (fraction of the largest step)
LOCATE_NEWTON_TOL = 1e-14      # and its closure (relative to the leads: near rounding)
RESOLVED = 1e-2         # a window is resolved when its cubic term is below this x T_TOUCH
ERR_FACTOR = 2.0        # the cubic term's bound: ERR_FACTOR |f[4 points]| (half-span)^3
                        # (the exact coefficient is 0.385 for equal steps: a 5x margin)


@njit(**JIT)
def third_difference(p0, p1, p2, p3, v0, v1, v2, v3):
    """Third divided difference f[p0, p1, p2, p3]."""
    a01 = (v1 - v0) / (p1 - p0)
    a12 = (v2 - v1) / (p2 - p1)
    a23 = (v3 - v2) / (p3 - p2)
    b012 = (a12 - a01) / (p2 - p0)
    b123 = (a23 - a12) / (p3 - p1)
    return (b123 - b012) / (p3 - p0)


@njit(**JIT)
def window_vertex(p0, p1, p2, v0, v1, v2):
    """(crank angle, value) of the smallest D between p0 and p2 by the quadratic
    through the three positions: its vertex where that lies between them, else
    the smallest of the three (the vertex of a convex quadratic is below them)."""
    a01 = (v1 - v0) / (p1 - p0)
    a12 = (v2 - v1) / (p2 - p1)
    c = (a12 - a01) / (p2 - p0)
    if c > 0.0:
        # q(s) = v1 + beta s + c s^2, s = phi - p1; its vertex between p0 and p2?
        beta = a12 - c * (p2 - p1)
        s = -beta / (2.0 * c)
        if (s - (p0 - p1)) * (s - (p2 - p1)) < 0.0:
            return p1 + s, v1 - beta * beta / (4.0 * c)
    if v0 <= v1 and v0 <= v2:
        return p0, v0
    return (p1, v1) if v1 <= v2 else (p2, v2)


@njit(**JIT)
def window_score(p0, p1, p2, v0, v1, v2, f3):
    """How far the smallest D between p0 and p2 can be from zero, by the
    quadratic through (p0, v0), (p1, v1), (p2, v2) less the bound of its cubic
    term (f3: a third divided difference near the window).  The window is safe
    when the score exceeds the watch threshold; -inf when anything is not
    finite (never safe)."""
    err = cubic_bound(p0, p2, f3)
    _, low = window_vertex(p0, p1, p2, v0, v1, v2)
    if not (math.isfinite(err) and math.isfinite(low) and math.isfinite(v0)
            and math.isfinite(v1) and math.isfinite(v2)):
        return -math.inf
    return low - err


@njit(**JIT)
def cubic_bound(p0, p2, f3):
    """The bound window_score allows for the cubic term of a window p0 .. p2."""
    h = 0.5 * abs(p2 - p0)
    return ERR_FACTOR * abs(f3) * h * h * h


@njit(**JIT)
def fold_distance(d0, d1, d2, step):
    """How far beyond the position with D = d0 the parabola through (0, d0),
    (-step, d1), (-2 step, d2) reaches zero (NaN: it does not, going on)."""
    a = (d0 - d1) / step
    c = (a - (d1 - d2) / step) / (2.0 * step)
    slope = a + c * step                  # D'(0)
    if not slope < 0.0:
        return math.nan
    disc = slope * slope - 4.0 * c * d0
    if not disc >= 0.0:
        return math.nan
    return 2.0 * d0 / (-slope + math.sqrt(disc))


@njit(**JIT)
def uniform_hit(v0, v1, v2, v3, after, floor):
    """window_score(...) <= floor for equally spaced positions, without a
    division (the lanes' form): v0, v1, v2 the window, v3 the fourth position
    (after the window if ``after``, else before it) for the cubic term."""
    d3 = (v3 - 3.0 * v2 + 3.0 * v1 - v0) if after else (v2 - 3.0 * v1 + 3.0 * v0 - v3)
    lim = floor + (ERR_FACTOR / 6.0) * abs(d3)
    b = 0.5 * (v2 - v0)
    c = 0.5 * (v2 - 2.0 * v1 + v0)
    if not (min(v0, min(v1, v2)) > lim):      # (NaN: a hit)
        return True
    return c > 0.0 and abs(b) < 2.0 * c and 4.0 * c * v1 - b * b <= 4.0 * c * lim
