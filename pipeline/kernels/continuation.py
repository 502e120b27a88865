"""Continuation along the revolution: the careful path's step control.

Every row of ``state`` (n_triads, N_STATE) is the continuation state of one
class III group of the mechanism (dyads are closed form and keep no state).
The generated ``advance`` of a mechanism (``pipeline.compiler``) walks from
one crank angle to the next as a predictor-corrector: a secant predictor
(``predict``), its Newton corrector (the mechanism's ``position``), steps
bounded by ``step_limit``, and a rejected step retried at half the size
(``restore``).  These helpers are the same for every mechanism.
"""

import math

import numpy as np
from numba import njit

from .config import (JIT, JIT_ALLOC, N_STATE, S_A, S_B, S_DET_SIGN, S_HAS_SLOPE, S_MARGIN, S_SLOPE_A,
                     S_MAY_STOP, S_MARGIN_OLD, S_D_RATE, S_SLOPE_B, S_A_OLD, S_B_OLD, S_SIGN_OLD,
                     T_CLOSE, T_FIRST_STEP, T_LOCATE, T_MIN_STEP, T_STEP_CHANGE, T_SUBSTEP)


MARGIN_SLOTS = 3     # after the groups' margins: failing group, angle reached, angle failed
FOLD_SHARE = 0.5     # a step goes at most this share of the way to where margin^2 reaches 0
FOLD_FLOOR = 0.03    # and no shorter than this share of the smallest retried step (1e-8 rad
                     # by default): closer, Newton's tolerance blurs where a fold is (measured:
                     # at 1e-10 rad a class III fold was located 8.5e-9 rad off)


@njit(**JIT)
def wrap(x):
    """Angle difference wrapped to (-pi, pi]."""
    return x - 2.0 * math.pi * math.floor((x + math.pi) / (2.0 * math.pi))


@njit(**JIT_ALLOC)
def work(n_points, n_groups, n_triads):
    """Work arrays of one candidate's walk: (pos, d1, d2, margins, state,
    start_state); margins has MARGIN_SLOTS slots more than groups: the index of
    the group that failed (``position``), the last crank angle a walk reached
    and the angle of its failing step (``advance``)."""
    return (np.empty((n_points, 2)), np.empty((n_points, 2)), np.empty((n_points, 2)),
            np.empty(n_groups + MARGIN_SLOTS), np.empty((n_triads, N_STATE)),
            np.empty((n_triads, N_STATE)))


@njit(**JIT)
def copy2(src, dst):
    """dst[:, :] = src by loops: a slice assignment would compile numba's
    broadcast-error path (string formatting), seconds of compile time."""
    for i in range(src.shape[0]):
        for j in range(src.shape[1]):
            dst[i, j] = src[i, j]


@njit(**JIT)
def start_triad(state, j, a0, b0):
    """Start class III group ``j`` from its declared guess (a0, b0)."""
    for k in range(N_STATE):
        state[j, k] = 0.0
    state[j, S_A] = a0
    state[j, S_B] = b0
    state[j, S_MARGIN] = 1.0   # not solved yet: full steps
    state[j, S_D_RATE] = math.nan   # the slope of margin^2: not known yet


@njit(**JIT)
def step_limit(state, tols):
    """Largest crank step from the current state: tols[T_SUBSTEP], and no
    more than moves a class III angle by tols[T_STEP_CHANGE] along the secant
    slope of the last step.  Near a fold of the solution curve the slope grows
    without bound, so the walk slows down into the fold instead of stepping
    over it onto another solution.  The first step of a walk (slope unknown)
    is tols[T_FIRST_STEP] of the full step (``accept`` takes no slope from a
    step that began at the declared guesses, so a walk from guesses away from
    its first position takes two such steps: after the second the slope of
    the margin^2 is known to ``fold_limit`` too)."""
    h = tols[T_SUBSTEP]
    for g in range(state.shape[0]):
        if state[g, S_HAS_SLOPE] == 0.0:
            h = min(h, tols[T_SUBSTEP] * tols[T_FIRST_STEP])
        else:
            s = max(abs(state[g, S_SLOPE_A]), abs(state[g, S_SLOPE_B]))
            if s > 0.0:
                h = min(h, tols[T_STEP_CHANGE] / s)
    return h


@njit(**JIT)
def fold_limit(state, tols, direction):
    """Largest crank step in ``direction`` (+1.0 or -1.0) towards a fold: where
    a group's margin^2 falls that way (its slope over the last step),
    FOLD_SHARE of the way to where its line reaches zero (and no less than
    FOLD_FLOOR of the smallest retried step, nor tols[T_LOCATE]); inf where
    none falls.  margin^2 falls linearly into a fold, and a class III group
    whose range ends there may resume a little further on; a step over that
    gap would land on the solutions beyond it (the same sign of det J, a small
    correction: nothing to see), so the walk slows down into the fold, below
    the smallest retried step if need be, until a step lands in the gap
    (``pipeline.kernels.watch``: the margin^2 of a class III group is known
    only where it assembles, so the watch cannot see such a gap)."""
    h = math.inf
    for g in range(state.shape[0]):
        rate = state[g, S_D_RATE] * direction     # (NaN: not known yet)
        if rate < 0.0:
            h = min(h, FOLD_SHARE * state[g, S_MARGIN] * state[g, S_MARGIN] / -rate)
    return max(h, tols[T_LOCATE], FOLD_FLOOR * tols[T_SUBSTEP] * tols[T_MIN_STEP])


@njit(**JIT)
def predict(state, dphi):
    """Keep the current state and move (a, b) along the secant (predictor)."""
    for g in range(state.shape[0]):
        state[g, S_A_OLD] = state[g, S_A]
        state[g, S_B_OLD] = state[g, S_B]
        state[g, S_SIGN_OLD] = state[g, S_DET_SIGN]
        state[g, S_MARGIN_OLD] = state[g, S_MARGIN]
        if state[g, S_HAS_SLOPE] != 0.0:
            state[g, S_A] += state[g, S_SLOPE_A] * dphi
            state[g, S_B] += state[g, S_SLOPE_B] * dphi


@njit(**JIT)
def may_stop(state, flag):
    """Whether the next solve's Newton may stop where its steps do not contract
    (the class III kernel's ``_give_up``): 1.0 where the continuation retries a failure at half
    the step; 0.0 (the default) where this try decides: Newton runs to its cap."""
    for g in range(state.shape[0]):
        state[g, S_MAY_STOP] = flag


@njit(**JIT)
def restore(state):
    """Back to the state before the step that was tried."""
    for g in range(state.shape[0]):
        state[g, S_A] = state[g, S_A_OLD]
        state[g, S_B] = state[g, S_B_OLD]
        state[g, S_DET_SIGN] = state[g, S_SIGN_OLD]
        state[g, S_MARGIN] = state[g, S_MARGIN_OLD]


@njit(**JIT)
def accept(state, dphi):
    """The step is taken: its secant slope predicts the next one, and the slope
    of margin^2 bounds it (``fold_limit``); both only from a step that began
    at a solution (not at the declared guesses: their error over a step is no
    slope)."""
    if dphi == 0.0:
        return
    for g in range(state.shape[0]):
        if state[g, S_SIGN_OLD] == 0.0:      # (det J's sign is known after a solve)
            continue
        m0 = state[g, S_MARGIN_OLD]
        m1 = state[g, S_MARGIN]
        if math.isfinite(m0) and math.isfinite(m1):
            state[g, S_D_RATE] = (m1 * m1 - m0 * m0) / dphi
        state[g, S_SLOPE_A] = wrap(state[g, S_A] - state[g, S_A_OLD]) / dphi
        state[g, S_SLOPE_B] = wrap(state[g, S_B] - state[g, S_B_OLD]) / dphi
        state[g, S_HAS_SLOPE] = 1.0


@njit(**JIT)
def closes(state, start_state, tols):
    """True when every class III group is back on its starting (a, b)."""
    for g in range(state.shape[0]):
        if (abs(wrap(state[g, S_A] - start_state[g, S_A])) > tols[T_CLOSE]
                or abs(wrap(state[g, S_B] - start_state[g, S_B])) > tols[T_CLOSE]):
            return False
    return True
