"""FROZEN COPY of the plan interpreter the product used before the mechanism
compiler (kept only for the agreement check and the benchmarks; not part of
the product).

The compiled plan interpreter: one crank position, then a revolution.

A mechanism is compiled (``pipeline.model``) into flat arrays:

* ``codes[g]``     group code (config.G_*), in solve order;
* ``gidx[g, :]``   point indices the group reads and writes;
* ``goff[g]``      offset of the group's parameters in ``par``;
* ``fixed_idx[k]`` index of fixed point k, its coordinates at
  ``par[fixed_off[k]]``, ``par[fixed_off[k] + 1]``;
* ``par``          every dimension of the mechanism: one row per candidate.

Group layouts (gidx / par from goff):
  crank : [pivot, tip]                        / [L, phiM0]
  RRR   : [A, C, B]                           / [L_AB, L_CB, W]
  RRP   : [A, G, B, guide_a, guide_b]         / [L_AB, angle, W]
  RPR   : [A (block), C (pivot), B (guide end)] / [offset, guide_length, W]
  class3: [P2, P6, P7, P3, P4, P5]            / [L23, L34, L45, L35, L46, L57, orientation, a0, b0, phi_start]
  attach: [base, a, b, out]                   / [angle, length]
"""

import math

import numpy as np
from numba import njit

from pipeline.group_types import G_ATTACH, G_CRANK
from pipeline.group_types.class3 import G_CLASS3
from pipeline.group_types.class3.kernels import _wrap, class3, ternary_angle
from pipeline.group_types.rpr import G_RPR
from pipeline.group_types.rpr.kernels import rpr
from pipeline.group_types.rrp import G_RRP
from pipeline.group_types.rrp.kernels import rrp
from pipeline.group_types.rrr import G_RRR
from pipeline.group_types.rrr.kernels import rrr
from pipeline.kernels.config import (JIT_ALLOC as JIT, OK,
                     S_A, S_B, S_ITERS, S_MARGIN, N_STATE,
                     T_SINGULAR, T_ASSEMBLY_SLACK, T_SUBSTEP, T_CLOSE, T_MIN_STEP,
                     BRANCH_JUMP, NEWTON_MAXITER, T_STEP_CHANGE, T_FIRST_STEP, S_SLOPE_A,
                     S_SLOPE_B, S_HAS_SLOPE, S_A_OLD, S_B_OLD, S_SIGN_OLD, S_DET_SIGN)
from pipeline.kernels.geometry import angle_analogs
from pipeline.kernels.groups import attach, crank


@njit(**JIT)
def place_fixed(par, fixed_idx, fixed_off, pos, d1, d2):
    """Fixed pivots: positions from the parameter vector, zero analogs."""
    for k in range(fixed_idx.shape[0]):
        i = fixed_idx[k]
        pos[i, 0] = par[fixed_off[k]]
        pos[i, 1] = par[fixed_off[k] + 1]
        d1[i, 0] = 0.0
        d1[i, 1] = 0.0
        d2[i, 0] = 0.0
        d2[i, 1] = 0.0


@njit(**JIT)
def kinematic_work(n_points, n_groups):
    """Work arrays of one candidate's walk: (pos, d1, d2, margins, state, start_state)."""
    return (np.empty((n_points, 2)), np.empty((n_points, 2)), np.empty((n_points, 2)),
            np.empty(n_groups), np.empty((n_groups, N_STATE)), np.empty((n_groups, N_STATE)))


@njit(**JIT)
def init_state(codes, goff, par, state):
    """Start every class III group from its declared guess (a0, b0)."""
    for g in range(codes.shape[0]):
        for k in range(N_STATE):
            state[g, k] = 0.0
        if codes[g] == G_CLASS3:
            state[g, S_A] = par[goff[g] + 7]
            state[g, S_B] = par[goff[g] + 8]
            state[g, S_MARGIN] = 1.0   # not solved yet: full steps


@njit(**JIT)
def has_newton(codes):
    for g in range(codes.shape[0]):
        if codes[g] == G_CLASS3:
            return True
    return False


@njit(**JIT)
def start_angle(codes, goff, par):
    """Crank angle at which the class III guesses apply (0 if none)."""
    for g in range(codes.shape[0]):
        if codes[g] == G_CLASS3:
            return par[goff[g] + 9]
    return 0.0


@njit(**JIT)
def solve_position(codes, gidx, goff, par, fixed_idx, fixed_off, phi1, order, tols, state,
                   pos, d1, d2, margins):
    """Solve every group at crank angle ``phi1`` (rad), in plan order.

    Writes pos/d1/d2 (n_points, 2) and margins[g]; returns the first non-OK
    status (groups after a failed one still run and give NaN).
    """
    place_fixed(par, fixed_idx, fixed_off, pos, d1, d2)
    sing = tols[T_SINGULAR]
    slack = tols[T_ASSEMBLY_SLACK]
    status = OK
    for g in range(codes.shape[0]):
        c = codes[g]
        o = goff[g]
        ix = gidx[g]
        if c == G_CRANK:
            st, m = crank(pos, d1, d2, ix[0], ix[1], par[o], par[o + 1], phi1, order)
        elif c == G_RRR:
            st, m = rrr(pos, d1, d2, ix[0], ix[1], ix[2], par[o], par[o + 1], par[o + 2],
                        order, sing, slack)
        elif c == G_RRP:
            st, m = rrp(pos, d1, d2, ix[0], ix[1], ix[2], ix[3], ix[4], par[o], par[o + 1],
                        par[o + 2], order, sing, slack)
        elif c == G_RPR:
            st, m = rpr(pos, d1, d2, ix[0], ix[1], ix[2], par[o], par[o + 1], par[o + 2],
                        order, sing, slack)
        elif c == G_CLASS3:
            u435 = ternary_angle(par[o + 1], par[o + 2], par[o + 3], par[o + 6])
            st, m = class3(pos, d1, d2, ix[0], ix[1], ix[2], ix[3], ix[4], ix[5],
                           par[o], par[o + 1], u435, par[o + 3], par[o + 4], par[o + 5],
                           state, g, order, tols)
        else:  # G_ATTACH
            st, m = attach(pos, d1, d2, ix[0], ix[1], ix[2], ix[3], par[o], par[o + 1], order)
        margins[g] = m
        if status == OK and st != OK:
            status = st
    return status


@njit(**JIT)
def step_limit(codes, state, tols):
    """Largest crank step from the current state: tols[T_SUBSTEP], and no
    more than moves a class III angle by tols[T_STEP_CHANGE] along the secant
    slope of the last step.  Near a fold of the solution curve the slope grows
    without bound, so the walk slows down into the fold instead of stepping
    over it onto another solution.  The first step of a walk (slope unknown)
    is tols[T_FIRST_STEP] of the full step."""
    h = tols[T_SUBSTEP]
    for g in range(codes.shape[0]):
        if codes[g] == G_CLASS3:
            if state[g, S_HAS_SLOPE] == 0.0:
                h = min(h, tols[T_SUBSTEP] * tols[T_FIRST_STEP])
            else:
                s = max(abs(state[g, S_SLOPE_A]), abs(state[g, S_SLOPE_B]))
                if s > 0.0:
                    h = min(h, tols[T_STEP_CHANGE] / s)
    return h


@njit(**JIT)
def _predict(codes, state, dphi):
    """Keep the current state and move (a, b) along the secant (predictor)."""
    for g in range(codes.shape[0]):
        if codes[g] == G_CLASS3:
            state[g, S_A_OLD] = state[g, S_A]
            state[g, S_B_OLD] = state[g, S_B]
            state[g, S_SIGN_OLD] = state[g, S_DET_SIGN]
            if state[g, S_HAS_SLOPE] != 0.0:
                state[g, S_A] += state[g, S_SLOPE_A] * dphi
                state[g, S_B] += state[g, S_SLOPE_B] * dphi


@njit(**JIT)
def _restore(codes, state):
    for g in range(codes.shape[0]):
        if codes[g] == G_CLASS3:
            state[g, S_A] = state[g, S_A_OLD]
            state[g, S_B] = state[g, S_B_OLD]
            state[g, S_DET_SIGN] = state[g, S_SIGN_OLD]


@njit(**JIT)
def _accept(codes, state, dphi):
    """The step is taken: its secant slope predicts the next one."""
    if dphi == 0.0:
        return
    for g in range(codes.shape[0]):
        if codes[g] == G_CLASS3:
            state[g, S_SLOPE_A] = _wrap(state[g, S_A] - state[g, S_A_OLD]) / dphi
            state[g, S_SLOPE_B] = _wrap(state[g, S_B] - state[g, S_B_OLD]) / dphi
            state[g, S_HAS_SLOPE] = 1.0


@njit(**JIT)
def advance(codes, gidx, goff, par, fixed_idx, fixed_off, phi_from, phi_to, order, tols,
            state, newton, pos, d1, d2, margins):
    """Continuation from ``phi_from`` to ``phi_to``, then the solve at
    ``phi_to`` to ``order``.

    Dyad-only plans are closed form: one solve.  With class III groups the
    walk is a predictor-corrector: secant predictor, Newton corrector, steps
    bounded by ``step_limit``; a step whose Newton fails or jumps branch (det J
    changes sign, or the correction exceeds tols[T_JUMP]) is retried at half
    the size, down to tols[T_MIN_STEP] of the full step, and only then
    reported.  Returns the first non-OK status met on the way.
    """
    if not newton:
        return solve_position(codes, gidx, goff, par, fixed_idx, fixed_off, phi_to, order, tols,
                              state, pos, d1, d2, margins)
    status = OK
    direction = 1.0 if phi_to >= phi_from else -1.0
    h_min = tols[T_SUBSTEP] * tols[T_MIN_STEP]
    h_cap = tols[T_SUBSTEP]
    phi = phi_from
    while True:
        h = max(min(step_limit(codes, state, tols), h_cap), h_min)
        final = abs(phi_to - phi) <= h
        target = phi_to if final else phi + direction * h
        dphi = target - phi
        _predict(codes, state, dphi)
        st = solve_position(codes, gidx, goff, par, fixed_idx, fixed_off, target,
                            order if final else 0, tols, state, pos, d1, d2, margins)
        # retry decisions use the intended step h, never the rounded dphi
        # (phi + h - phi can exceed h_min by an ulp forever)
        if (st == NEWTON_MAXITER or st == BRANCH_JUMP) and min(h, abs(dphi)) > h_min:
            _restore(codes, state)
            h_cap = 0.5 * min(h, abs(dphi))
            continue
        if st == OK:
            _accept(codes, state, dphi)
            h_cap = min(2.0 * h_cap, tols[T_SUBSTEP])
            phi = target
            if final:
                return status
            continue
        # a failure at the smallest step is a fact about the candidate: record
        # it, and go straight to phi_to from the last good solution (so that a
        # scene still shows what can be shown) instead of crawling on
        if status == OK:
            status = st
        if st == NEWTON_MAXITER:
            _restore(codes, state)
        if final:
            return status
        st = solve_position(codes, gidx, goff, par, fixed_idx, fixed_off, phi_to, order, tols,
                            state, pos, d1, d2, margins)
        return status


@njit(**JIT)
def closes(codes, state, start_state, tols):
    """True when every class III group is back on its starting (a, b)."""
    for g in range(codes.shape[0]):
        if codes[g] == G_CLASS3:
            if (abs(_wrap(state[g, S_A] - start_state[g, S_A])) > tols[T_CLOSE]
                    or abs(_wrap(state[g, S_B] - start_state[g, S_B])) > tols[T_CLOSE]):
                return False
    return True


@njit(**JIT)
def solve_revolution(codes, gidx, goff, par, fixed_idx, fixed_off, phis, phi_close, order,
                     tols, pos_out, d1_out, d2_out, status_out, margin_out, iters_out):
    """Solve the mechanism at the crank angles ``phis`` (rad) by continuation.

    Outputs per position: pos_out/d1_out/d2_out (n_phi, n_points, 2),
    status_out (n_phi) int8, margin_out (n_phi, n_groups), iters_out (n_phi)
    Newton iterations summed over class III groups.  If ``phi_close`` is
    finite, the continuation goes on to it and the revolution must close on
    the state at phis[0]; otherwise it returns BRANCH_JUMP.
    Returns the overall status: the first non-OK position status, or
    BRANCH_JUMP if the revolution does not close.
    """
    n_groups = codes.shape[0]
    pos, d1, d2, margins, state, start_state = kinematic_work(pos_out.shape[1], n_groups)
    init_state(codes, goff, par, state)
    newton = has_newton(codes)
    phi_prev = start_angle(codes, goff, par) if newton else phis[0]
    overall = OK
    for k in range(phis.shape[0]):
        st = advance(codes, gidx, goff, par, fixed_idx, fixed_off, phi_prev, phis[k], order,
                     tols, state, newton, pos, d1, d2, margins)
        phi_prev = phis[k]
        if k == 0:
            start_state[:, :] = state
        status_out[k] = st
        it = 0.0
        for g in range(n_groups):
            margin_out[k, g] = margins[g]
            if codes[g] == G_CLASS3:
                it += state[g, S_ITERS]
        iters_out[k] = it
        pos_out[k] = pos
        if order >= 1:
            d1_out[k] = d1
        if order >= 2:
            d2_out[k] = d2
        if overall == OK and st != OK:
            overall = st
    if newton and math.isfinite(phi_close):
        st = advance(codes, gidx, goff, par, fixed_idx, fixed_off, phi_prev, phi_close, 0,
                     tols, state, newton, pos, d1, d2, margins)
        if overall == OK and (st != OK or not closes(codes, state, start_state, tols)):
            overall = BRANCH_JUMP if st == OK else st
    return overall


from pipeline.kernels.geometry import link_angles  # noqa: E402,F401  (the product's own)
