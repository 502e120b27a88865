"""Class III group (triad): ternary base link 3-4-5 with three leads.

Lead 2-3 joins the known point P2 to vertex 3; leads 4-6 and 5-7 join
vertices 4 and 5 to the known points P6 and P7.  Unknowns: the angle a of
lead 2-3 and the angle b of side 3-4.

    P3 = P2 + L23 e(a),  P4 = P3 + L34 e(b),  P5 = P3 + L35 e(b + U435)
    F1 = |P4 - P6|^2 - L46^2 = 0,   F2 = |P5 - P7|^2 - L57^2 = 0

solved by Newton with the analytic 2x2 Jacobian (damped: the step is limited),
warm-started from the previous crank position.  The first and second analogs
come from the same Jacobian applied to the differentiated closure equations.

The sliding variant (``class3_slider``) has a block at vertex 5 in place of
lead 5-7: the block slides on a guide line through the known point G = P7
with the direction th (fixed, or turning with a link), and carries P5 at the
perpendicular distance ``offset`` from it, on the side of n = e(th + 90 deg):

    F1 = (|P4 - P6|^2 - L46^2) / 2 = 0,   F2 = n . (P5 - G) - offset = 0

with the same unknowns, continuation state and checks as ``class3``.
"""

import math

import numpy as np
from numba import njit

from ...kernels.config import (JIT, OK, NEWTON_MAXITER, SINGULAR, BRANCH_JUMP,
                     BAD_GEOMETRY, S_A, S_B, S_DET_SIGN, S_MARGIN, S_ITERS, S_HANDED, S_CA,
                     S_SA, S_CB, S_SB, S_MAY_STOP,
                     T_NEWTON_TOL, T_NEWTON_MAXITER, T_NEWTON_STEP, T_SINGULAR, T_JUMP)
from ...kernels.geometry import solve2
from ...kernels.groups import guide_direction

__all__ = ("class3", "class3_slider", "ternary_angle")

# Newton outcomes
CONVERGED = 0
MAXITER = 1
SINGULAR_JACOBIAN = 2

# Newton contracts near a solution: each full step shorter than the one before
# (quadratically near a regular solution, by about half near a fold).  Where
# the group cannot be assembled it wanders instead, and ran to the iteration
# cap (50), three quarters of the careful path's work on a failing candidate.
# Two steps no shorter than the one before, each above rounding, and it stops
# (MAXITER, as at the cap), where the continuation retries a failed step at
# half the size (``continuation.may_stop``); the try that decides (the
# smallest step, a walk's straight last solve, a solve outside a walk) and the
# first solve from the declared guesses (which may be far from the solution)
# run to the cap.  Near a fold Newton may wander before it contracts: there a
# step stopped early is retried shorter, and only the cap says it failed.
# Measured on every class III solve of 450 ov7_synthesis(_law) candidates
# (170,000 converged solves, 1,134 that ran to the cap): no converged solve
# ever took two such steps (one took one); the non-converging ones stop after
# 5.5 iterations on average instead of 50.
STALL_STRIKES = 2
STALL_FLOOR = 1e-6        # rad: a longer step is no rounding noise


@njit(**JIT)
def _stalls(step, last, strikes):
    """The count of Newton steps no shorter than the one before (``last``) and
    longer than STALL_FLOOR, with ``step``."""
    if step >= last and step > STALL_FLOOR:
        return strikes + 1
    return strikes


@njit(**JIT)
def _give_up(state, g, tols):
    """How many steps that do not contract Newton takes before it stops:
    STALL_STRIKES where the continuation may retry (``continuation.may_stop``)
    after a solution (det J's sign known); else never (more than the cap)."""
    if state[g, S_MAY_STOP] != 0.0 and state[g, S_DET_SIGN] != 0.0:
        return STALL_STRIKES
    return int(tols[T_NEWTON_MAXITER]) + 1


@njit(**JIT)
def ternary_angle(l34, l45, l35, orientation):
    """Angle U435 at vertex 3 between sides 3-4 and 3-5 (cosine law), signed by
    ``orientation``; NaN when the triangle cannot be built."""
    if not (l34 > 0.0 and l45 > 0.0 and l35 > 0.0):
        return math.nan
    if not (l45 < l34 + l35 and l34 < l45 + l35 and l35 < l34 + l45):
        return math.nan
    c = (l34 * l34 + l35 * l35 - l45 * l45) / (2.0 * l34 * l35)
    return orientation * math.acos(min(1.0, max(-1.0, c)))


# A variant's geometry at the current crank position, one tuple for both
# (``class3`` and ``class3_slider`` build it): the known points P2, P6 and P7
# (the sliding variant's guide point G), the guide's unit normal n (0 for the
# lead), the lengths L23, L34, L35, L46, L57 (NaN for the slider) and the
# block's offset (0 for the lead).  ``slider`` says which: LEAD or SLIDER.
LEAD = 0
SLIDER = 1


@njit(inline='always', **JIT)
def closure_unit(p2x, p2y, p6x, p6y, p7x, p7y, l23, l34, l35, l46, l57, ca, sa, cb, sb, cc, sc):
    """Residuals (F1, F2) and Jacobian d(F1, F2)/d(a, b) at the unit vectors
    e(a) = (ca, sa), e(b) = (cb, sb) and e(b + U435) = (cc, sc), and those
    cos/sin (``_place`` reuses them)."""
    p3x = p2x + l23 * ca
    p3y = p2y + l23 * sa
    r4x = p3x + l34 * cb - p6x
    r4y = p3y + l34 * sb - p6y
    r5x = p3x + l35 * cc - p7x
    r5y = p3y + l35 * sc - p7y
    f1 = r4x * r4x + r4y * r4y - l46 * l46
    f2 = r5x * r5x + r5y * r5y - l57 * l57
    # d/da of P3 (and so of P4, P5) is L23 n(a), n(x) = (-sin x, cos x)
    j11 = 2.0 * l23 * (-r4x * sa + r4y * ca)
    j12 = 2.0 * l34 * (-r4x * sb + r4y * cb)
    j21 = 2.0 * l23 * (-r5x * sa + r5y * ca)
    j22 = 2.0 * l35 * (-r5x * sc + r5y * cc)
    return f1, f2, j11, j12, j21, j22, (ca, sa, cb, sb, cc, sc)


@njit(**JIT)
def slider_closure_unit(p2x, p2y, p6x, p6y, gx, gy, nx, ny, l23, l34, l35, l46, offset, ca, sa,
                        cb, sb, cc, sc):
    """Residuals (F1, F2) of the sliding variant and their Jacobian d(F1, F2)/d(a, b)
    at the unit vectors e(a), e(b), e(b + U435): F1 = (|P4 - P6|^2 - L46^2) / 2
    (mm^2), F2 = n.(P5 - G) - offset (mm), n the guide's unit normal."""
    p3x = p2x + l23 * ca
    p3y = p2y + l23 * sa
    r4x = p3x + l34 * cb - p6x
    r4y = p3y + l34 * sb - p6y
    f1 = 0.5 * (r4x * r4x + r4y * r4y - l46 * l46)
    f2 = nx * (p3x + l35 * cc - gx) + ny * (p3y + l35 * sc - gy) - offset
    # d/da of P3, P4, P5 is L23 n(a); d/db of P4 is L34 n(b), of P5 L35 n(b + U435)
    j11 = l23 * (-r4x * sa + r4y * ca)
    j12 = l34 * (-r4x * sb + r4y * cb)
    j21 = l23 * (-nx * sa + ny * ca)
    j22 = l35 * (-nx * sc + ny * cc)
    return f1, f2, j11, j12, j21, j22, (ca, sa, cb, sb, cc, sc)


@njit(inline='always', **JIT)
def _closure(slider, geo, ca, sa, cb, sb, cc, sc):
    """The variant's closure (``closure_unit``, ``slider_closure_unit``) at the unit
    vectors: (F1, F2, J, trig, the larger residual as a distance, mm).  The
    distances: how far P4 is off its circle (|F1| / 2 L46, the slider's halved
    F1 / L46) and P5 off its circle (|F2| / 2 L57) or its guide line (|F2|)."""
    p2x, p2y, p6x, p6y, p7x, p7y, nx, ny, l23, l34, l35, l46, l57, offset = geo
    if slider:
        f1, f2, j11, j12, j21, j22, trig = slider_closure_unit(p2x, p2y, p6x, p6y, p7x, p7y, nx,
                                                               ny, l23, l34, l35, l46, offset,
                                                               ca, sa, cb, sb, cc, sc)
        return f1, f2, j11, j12, j21, j22, trig, max(abs(f1) / l46, abs(f2))
    f1, f2, j11, j12, j21, j22, trig = closure_unit(p2x, p2y, p6x, p6y, p7x, p7y, l23, l34, l35,
                                                    l46, l57, ca, sa, cb, sb, cc, sc)
    return f1, f2, j11, j12, j21, j22, trig, max(abs(f1) / (2.0 * l46), abs(f2) / (2.0 * l57))


@njit(inline='always', **JIT)
def _longer_lead(slider, geo):
    """The length Newton's relative tolerance is taken of: the longer lead (L46 or
    L57; with a slider L23 or L46)."""
    if slider:
        return max(geo[8], geo[11])
    return max(geo[11], geo[12])


@njit(**JIT)
def newton(slider, geo, u435, a, b, tol, maxiter, max_step, strikes_max):
    """Damped Newton on the closure equations of either variant from (a, b).

    Returns (outcome, a, b, iterations, det J, trig): outcome CONVERGED, MAXITER or
    SINGULAR_JACOBIAN; trig the cos/sin of a, b and b + U435 where it converged
    (the last residual's: ``_place`` does not compute them again).  Converged means
    both closure residuals, as distances (``_closure``, mm), are at most ``tol``
    times the longer lead (a relative tolerance: the same digits at 1e-3 mm and
    at 1e4 mm).  Gives up (MAXITER, with the iterations taken) before ``maxiter``
    after ``strikes_max`` steps that did not contract (``_stalls``).
    """
    det = math.nan
    trig = (math.nan, math.nan, math.nan, math.nan, math.nan, math.nan)
    last = math.inf       # the last full Newton step (rad)
    strikes = np.int64(0)   # (not the literal 0: one compiled _stalls)
    tol_mm = tol * _longer_lead(slider, geo)
    for it in range(maxiter + 1):
        f1, f2, j11, j12, j21, j22, trig, res = _closure(slider, geo, math.cos(a), math.sin(a),
                                                         math.cos(b), math.sin(b),
                                                         math.cos(b + u435), math.sin(b + u435))
        det = j11 * j22 - j12 * j21
        if res <= tol_mm:
            return CONVERGED, a, b, it, det, trig
        if it == maxiter:
            break
        if not (det != 0.0 and math.isfinite(det)):
            return SINGULAR_JACOBIAN, a, b, it, det, trig
        da, db = solve2(j11, j12, j21, j22, f1, f2)
        step = max(abs(da), abs(db))
        if not math.isfinite(step):
            return SINGULAR_JACOBIAN, a, b, it, det, trig
        strikes = _stalls(step, last, strikes)
        if strikes >= strikes_max:
            return MAXITER, a, b, it, det, trig
        last = step
        if step > max_step:
            da *= max_step / step
            db *= max_step / step
        a -= da
        b -= db
    return MAXITER, a, b, maxiter, det, trig


@njit(**JIT)
def _handed_unit(state, g, u_cos, u_sin):
    """The unit vectors e(a), e(b) handed over in state row ``g`` and e(b + U435)
    from them (u_cos, u_sin: cos and sin of U435); clears the hand-over flag."""
    state[g, S_HANDED] = 0.0
    ca = state[g, S_CA]
    sa = state[g, S_SA]
    cb = state[g, S_CB]
    sb = state[g, S_SB]
    return ca, sa, cb, sb, cb * u_cos - sb * u_sin, sb * u_cos + cb * u_sin


@njit(**JIT)
def _handed_angles(state, g):
    """The angles (a, b) of the unit vectors handed over in state row ``g``
    (where they are not taken: Newton's start)."""
    return math.atan2(state[g, S_SA], state[g, S_CA]), math.atan2(state[g, S_SB], state[g, S_CB])


@njit(**JIT)
def handed(slider, geo, u_cos, u_sin, state, g, tol):
    """The solution handed over in state row ``g`` as unit vectors e(a), e(b)
    (the lane path's, ``S_CA`` .. ``S_SB``): (taken, det J, the cos/sin of
    a, b and b + U435).  Taken where its closure residuals are within Newton's
    tolerance (the test Newton's first iteration makes, without its cos and
    sin: the unit vectors are the solution); else the caller runs Newton
    from its angles.  Clears the hand-over flag."""
    ca, sa, cb, sb, cc, sc = _handed_unit(state, g, u_cos, u_sin)
    f1, f2, j11, j12, j21, j22, trig, res = _closure(slider, geo, ca, sa, cb, sb, cc, sc)
    return res <= tol * _longer_lead(slider, geo), j11 * j22 - j12 * j21, trig


@njit(**JIT)
def _wrap(x):
    """Angle difference wrapped to (-pi, pi]."""
    return x - 2.0 * math.pi * math.floor((x + math.pi) / (2.0 * math.pi))


@njit(**JIT)
def _accept(state, g, a, b, a0, b0, det, margin, tols, moved=True):
    """Status of a converged solve (a, b) from (a0, b0): BRANCH_JUMP where det J
    changed sign or (``moved``: a solve from a prediction, not a solution
    handed over) an angle moved more than tols[T_JUMP], SINGULAR below
    tols[T_SINGULAR]; the continuation state row g takes the new solution."""
    status = OK
    sign = 1.0 if det > 0.0 else -1.0
    if state[g, S_DET_SIGN] != 0.0:
        if sign != state[g, S_DET_SIGN]:
            status = BRANCH_JUMP
        elif moved and (abs(_wrap(a - a0)) > tols[T_JUMP] or abs(_wrap(b - b0)) > tols[T_JUMP]):
            status = BRANCH_JUMP
    state[g, S_A] = a
    state[g, S_B] = b
    state[g, S_DET_SIGN] = sign
    if status == OK and margin < tols[T_SINGULAR]:
        status = SINGULAR
    return status


@njit(**JIT)
def _place(pos, i2, i3, i4, i5, l23, l34, l35, trig):
    """Vertices 3, 4, 5 at the angles (a, b) whose cos/sin (and those of
    b + U435) are ``trig`` (Newton's last residual computed them); returns
    them for the analogs."""
    ca, sa, cb, sb, cc, sc = trig
    pos[i3, 0] = pos[i2, 0] + l23 * ca
    pos[i3, 1] = pos[i2, 1] + l23 * sa
    pos[i4, 0] = pos[i3, 0] + l34 * cb
    pos[i4, 1] = pos[i3, 1] + l34 * sb
    pos[i5, 0] = pos[i3, 0] + l35 * cc
    pos[i5, 1] = pos[i3, 1] + l35 * sc
    return ca, sa, cb, sb, cc, sc


@njit(**JIT)
def _place_analogs(d, i2, i3, i4, i5, l23, l34, l35, a_k, b_k, a1, b1, ca, sa, cb, sb, cc, sc):
    """First (a1 = b1 = 0) or second analogs ``d`` of vertices 3, 4, 5 from the
    analogs (a_k, b_k) of the angles a, b and the first ones (a1, b1):
    P3^(k) = P2^(k) + L23 (a_k n(a) - a1^2 e(a)), P4^(k) = P3^(k) + L34 (b_k n(b)
    - b1^2 e(b)), P5^(k) = P3^(k) + L35 (b_k n(c) - b1^2 e(c)), c = b + U435."""
    d[i3, 0] = d[i2, 0] - l23 * a1 * a1 * ca - l23 * a_k * sa
    d[i3, 1] = d[i2, 1] - l23 * a1 * a1 * sa + l23 * a_k * ca
    d[i4, 0] = d[i3, 0] - l34 * (b_k * sb + b1 * b1 * cb)
    d[i4, 1] = d[i3, 1] + l34 * (b_k * cb - b1 * b1 * sb)
    d[i5, 0] = d[i3, 0] - l35 * (b_k * sc + b1 * b1 * cc)
    d[i5, 1] = d[i3, 1] + l35 * (b_k * cc - b1 * b1 * sc)


@njit(**JIT)
def _nan_joints(pos, d1, d2, i3, i4, i5, order_from):
    """NaN the three vertices from ``order_from`` on (0: positions and analogs,
    1: the analogs only)."""
    for i in (i3, i4, i5):
        for k in range(2):
            if order_from == 0:
                pos[i, k] = math.nan
            d1[i, k] = math.nan
            d2[i, k] = math.nan


@njit(inline='always', **JIT)
def _fail(pos, d1, d2, i3, i4, i5, state, g, status):
    """No solution: vertices 3, 4, 5 and their analogs NaN, no margin, no
    hand-over left; returns (status, 0.0)."""
    state[g, S_HANDED] = 0.0
    _nan_joints(pos, d1, d2, i3, i4, i5, np.int64(0))
    state[g, S_MARGIN] = 0.0
    return status, 0.0


@njit(**JIT)
def _solve(slider, geo, u435, th1, th2, pos, d1, d2, i2, i6, i7, i3, i4, i5, state, g, order,
           tols, u_cos, u_sin):
    """Either variant at the current crank position (``class3``, ``class3_slider``
    check the lengths and build ``geo``): the solution handed over or Newton's,
    accepted (``_accept``) and placed, then the first and second analogs to
    ``order``.  th1, th2: the slider's guide direction's first and second
    analogs (0 for the lead).  Returns (status, margin)."""
    p2x, p2y, p6x, p6y, p7x, p7y, nx, ny, l23, l34, l35, l46, l57, offset = geo
    a0 = state[g, S_A]
    b0 = state[g, S_B]
    taken = False
    if state[g, S_HANDED] != 0.0:   # (a hand-over holds for one solve only)
        if not (u_cos == u_cos and u_sin == u_sin):
            u_cos = math.cos(u435)
            u_sin = math.sin(u435)
        taken, det, trig = handed(slider, geo, u_cos, u_sin, state, g, tols[T_NEWTON_TOL])
        if taken:   # the angles are not needed: the next position is handed over too
            outcome, a, b, iters = CONVERGED, math.nan, math.nan, 0
        else:       # Newton from the handed angles, its move checked like any other
            a0, b0 = _handed_angles(state, g)
    if not taken:   # (one call site of newton: compile time)
        outcome, a, b, iters, det, trig = newton(slider, geo, u435, a0, b0, tols[T_NEWTON_TOL],
                                                 int(tols[T_NEWTON_MAXITER]),
                                                 tols[T_NEWTON_STEP], _give_up(state, g, tols))
    state[g, S_ITERS] = iters
    if outcome != CONVERGED:
        # Where the group cannot be assembled Newton does not converge either;
        # the solver's own outcome is what is reported.
        return _fail(pos, d1, d2, i3, i4, i5, state, g,
                     SINGULAR if outcome == SINGULAR_JACOBIAN else NEWTON_MAXITER)
    if slider:
        margin = abs(det) / (l23 * l46 * max(l34, l35))
    else:
        margin = abs(det) / (4.0 * l23 * l46 * l57 * max(l34, l35))
    state[g, S_MARGIN] = margin
    status = _accept(state, g, a, b, a0, b0, det, margin, tols, not taken)
    ca, sa, cb, sb, cc, sc = _place(pos, i2, i3, i4, i5, l23, l34, l35, trig)
    if order < 1:
        return status, margin
    if status == SINGULAR:
        _nan_joints(pos, d1, d2, i3, i4, i5, np.int64(1))
        return status, margin

    r4x = pos[i4, 0] - p6x
    r4y = pos[i4, 1] - p6y
    w5x = pos[i5, 0] - p7x     # P5 - P7 (the slider's P5 - G)
    w5y = pos[i5, 1] - p7y
    ux = ny                    # the guide's direction u, n = e(th + 90 deg)
    uy = -nx
    # Jacobian of the half closure: row 1 (r4.r4 - L46^2)/2, row 2 (w5.w5 - L57^2)/2
    # along v = w5, or the slider's n.(P5 - G) - offset along v = n
    if slider:
        vx = nx
        vy = ny
    else:
        vx = w5x
        vy = w5y
    j11 = l23 * (-r4x * sa + r4y * ca)
    j12 = l34 * (-r4x * sb + r4y * cb)
    j21 = l23 * (-vx * sa + vy * ca)
    j22 = l35 * (-vx * sc + vy * cc)
    # first analogs: r4.(P4' - P6') = 0, v.(P5' - P7') = 0 and, the slider's with
    # n' = -th' u, n.(P5' - G') - th' u.(P5 - G) = 0
    rhs1 = -(r4x * (d1[i2, 0] - d1[i6, 0]) + r4y * (d1[i2, 1] - d1[i6, 1]))
    rhs2 = -(vx * (d1[i2, 0] - d1[i7, 0]) + vy * (d1[i2, 1] - d1[i7, 1]))
    if slider:
        rhs2 = rhs2 + th1 * (ux * w5x + uy * w5y)
    a1, b1 = solve2(j11, j12, j21, j22, rhs1, rhs2)
    _place_analogs(d1, i2, i3, i4, i5, l23, l34, l35, a1, b1, 0.0, 0.0, ca, sa, cb, sb, cc, sc)
    if order < 2:
        return status, margin
    # second analogs: r4.(P4'' - P6'') + |P4' - P6'|^2 = 0 (and for 5, 7), with
    # P4'' = P2'' + L23 (a'' n(a) - a'^2 e(a)) + L34 (b'' n(b) - b'^2 e(b)); the
    # slider's n.(P5'' - G'') - 2 th' u.(P5' - G') - th'' u.(P5 - G) - th'^2 offset = 0,
    # with P5'' = P2'' + L23 (a'' n(a) - a'^2 e(a)) + L35 (b'' n(c) - b'^2 e(c))
    q4x = d1[i4, 0] - d1[i6, 0]
    q4y = d1[i4, 1] - d1[i6, 1]
    q5x = d1[i5, 0] - d1[i7, 0]
    q5y = d1[i5, 1] - d1[i7, 1]
    k3x = d2[i2, 0] - l23 * a1 * a1 * ca
    k3y = d2[i2, 1] - l23 * a1 * a1 * sa
    k4x = k3x - l34 * b1 * b1 * cb - d2[i6, 0]
    k4y = k3y - l34 * b1 * b1 * sb - d2[i6, 1]
    k5x = k3x - l35 * b1 * b1 * cc - d2[i7, 0]
    k5y = k3y - l35 * b1 * b1 * sc - d2[i7, 1]
    rhs1 = -(q4x * q4x + q4y * q4y) - (r4x * k4x + r4y * k4y)
    if slider:
        rhs2 = (-(nx * k5x + ny * k5y) + 2.0 * th1 * (ux * q5x + uy * q5y)
                + th2 * (ux * w5x + uy * w5y) + th1 * th1 * offset)
    else:
        rhs2 = -(q5x * q5x + q5y * q5y) - (w5x * k5x + w5y * k5y)
    a2, b2 = solve2(j11, j12, j21, j22, rhs1, rhs2)
    _place_analogs(d2, i2, i3, i4, i5, l23, l34, l35, a2, b2, a1, b1, ca, sa, cb, sb, cc, sc)
    return status, margin


@njit(**JIT)
def class3(pos, d1, d2, i2, i6, i7, i3, i4, i5, l23, l34, u435, l35, l46, l57,
           state, g, order, tols, u_cos=math.nan, u_sin=math.nan):
    """Solve the class III group whose continuation state is row ``g`` of
    ``state``, at the current crank position.

    ``u435`` is the ternary link's angle at vertex 3 (``ternary_angle``, NaN
    when the triangle cannot be built), computed once per candidate by the
    caller (``u_cos``, ``u_sin``: its cos and sin, computed here if NaN).
    ``state[g]`` carries the continuation: the last (a, b), the sign of det J
    there (0 before the first solve), and receives the singularity margin and
    the Newton iterations; or, flagged ``S_HANDED``, the solution at this
    position as unit vectors (``handed``).  The margin is |det J| / (4 L23 L46
    L57 max(L34, L35)).  Returns (status, margin).
    """
    if not (math.isfinite(u435) and l23 > 0.0 and l46 > 0.0 and l57 > 0.0):
        return _fail(pos, d1, d2, i3, i4, i5, state, g, BAD_GEOMETRY)
    geo = (pos[i2, 0], pos[i2, 1], pos[i6, 0], pos[i6, 1], pos[i7, 0], pos[i7, 1], 0.0, 0.0,
           l23, l34, l35, l46, l57, 0.0)
    return _solve(np.int64(LEAD), geo, u435, 0.0, 0.0, pos, d1, d2, i2, i6, i7, i3, i4, i5,
                  state, g, order, tols, u_cos, u_sin)


@njit(**JIT)
def class3_slider(pos, d1, d2, i2, i6, i7, i3, i4, i5, ga, gb, l23, l34, u435, l35, l46,
                  guide_angle, offset, state, g, order, tols, u_cos=math.nan, u_sin=math.nan):
    """Solve the sliding class III group whose continuation state is row ``g``
    of ``state``, at the current crank position (see ``class3``).

    The guide runs through the known point i7 with the absolute direction
    ``guide_angle`` (ga < 0) or that of the link ga->gb plus ``guide_angle``
    (``kernels.groups.guide_direction``).  The margin is |det J| / (L23 L46 max(L34, L35)),
    J the Jacobian of (F1, F2) above: scale-free, 0 at a singular position.
    Flagged ``S_HANDED``, the solution at this position as unit vectors
    (``handed``; u_cos, u_sin: cos and sin of U435, computed here if NaN), as
    ``class3``.  Returns (status, margin).
    """
    if not (math.isfinite(u435) and l23 > 0.0 and l46 > 0.0):
        return _fail(pos, d1, d2, i3, i4, i5, state, g, BAD_GEOMETRY)
    th, th1, th2 = guide_direction(pos, d1, d2, ga, gb, guide_angle, order)
    if not math.isfinite(th):   # the guide link has no length: no direction
        return _fail(pos, d1, d2, i3, i4, i5, state, g, SINGULAR)
    geo = (pos[i2, 0], pos[i2, 1], pos[i6, 0], pos[i6, 1], pos[i7, 0], pos[i7, 1],
           -math.sin(th), math.cos(th), l23, l34, l35, l46, math.nan, offset)
    return _solve(np.int64(SLIDER), geo, u435, th1, th2, pos, d1, d2, i2, i6, i7, i3, i4, i5,
                  state, g, order, tols, u_cos, u_sin)
