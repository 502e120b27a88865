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
                     S_SLOPE_B, S_A_OLD, S_B_OLD, S_SIGN_OLD, T_CLOSE, T_FIRST_STEP,
                     T_STEP_CHANGE, T_SUBSTEP)


MARGIN_SLOTS = 3     # after the groups' margins: failing group, angle reached, angle failed


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


@njit(**JIT)
def step_limit(state, tols):
    """Largest crank step from the current state: tols[T_SUBSTEP], and no
    more than moves a class III angle by tols[T_STEP_CHANGE] along the secant
    slope of the last step.  Near a fold of the solution curve the slope grows
    without bound, so the walk slows down into the fold instead of stepping
    over it onto another solution.  The first step of a walk (slope unknown)
    is tols[T_FIRST_STEP] of the full step."""
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
def predict(state, dphi):
    """Keep the current state and move (a, b) along the secant (predictor)."""
    for g in range(state.shape[0]):
        state[g, S_A_OLD] = state[g, S_A]
        state[g, S_B_OLD] = state[g, S_B]
        state[g, S_SIGN_OLD] = state[g, S_DET_SIGN]
        if state[g, S_HAS_SLOPE] != 0.0:
            state[g, S_A] += state[g, S_SLOPE_A] * dphi
            state[g, S_B] += state[g, S_SLOPE_B] * dphi


@njit(**JIT)
def restore(state):
    """Back to the state before the step that was tried."""
    for g in range(state.shape[0]):
        state[g, S_A] = state[g, S_A_OLD]
        state[g, S_B] = state[g, S_B_OLD]
        state[g, S_DET_SIGN] = state[g, S_SIGN_OLD]


@njit(**JIT)
def accept(state, dphi):
    """The step is taken: its secant slope predicts the next one."""
    if dphi == 0.0:
        return
    for g in range(state.shape[0]):
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
