"""``advance`` of a mechanism with class III groups: continuation by predictor
and Newton corrector, the step halved on a failure.

The text below the marker line is pasted into the generated module
(``pipeline.compiler.generate``); the imports above it declare, for linters and
readers, the names the generated module gives it."""

from .header import (njit, JIT_INNER, OK, BRANCH_JUMP, NEWTON_MAXITER, T_SUBSTEP, T_MIN_STEP,
                     T_GO_ON, accept, fold_limit, may_stop, predict, restore, step_limit)
from ._mechanism import (N_GROUPS, position)

# ---- the skeleton: from here on, pasted into the generated module ----
@njit(**JIT_INNER)
def advance(K, phi_from, phi_to, order, tols, state, pos, d1, d2, margins, with_com):
    """Continuation from ``phi_from`` to ``phi_to``, then the solve at
    ``phi_to`` to ``order``: secant predictor, Newton corrector, steps bounded
    by ``step_limit`` and, towards a fold, ``fold_limit``; a step whose Newton
    fails or jumps branch (det J changes sign, or the correction exceeds
    tols[T_JUMP]) is retried at half the size, down to tols[T_MIN_STEP] of the
    full step, and only then reported (a step that ``fold_limit`` makes shorter
    still is not retried: a failure there is the fold's); then, where
    tols[T_GO_ON], phi_to is solved straight from the last solution.  Returns the first
    non-OK status met on the way (margins[N_GROUPS]: its group;
    margins[N_GROUPS + 1]: the last angle reached, margins[N_GROUPS + 2]: the
    angle of the failing step).  (One call site of ``position``: numba inlines
    per call site, and compile time grows with every copy.)"""
    status = OK
    group = -1.0
    margins[N_GROUPS + 1] = phi_from
    margins[N_GROUPS + 2] = phi_to
    direction = 1.0 if phi_to >= phi_from else -1.0
    h_min = tols[T_SUBSTEP] * tols[T_MIN_STEP]
    h_cap = tols[T_SUBSTEP]
    phi = phi_from
    straight = False
    while True:
        if straight:
            # after a failure at the smallest step: straight to phi_to from the
            # last good solution (a scene still shows what can be shown)
            final = True
            target = phi_to
            h = 0.0
        else:
            # (towards a fold below the smallest retried step if need be)
            h = min(max(min(step_limit(state, tols), h_cap), h_min),
                    fold_limit(state, tols, direction))
            final = abs(phi_to - phi) <= h
            target = phi_to if final else phi + direction * h
            predict(state, target - phi)
        dphi = target - phi
        # a Newton whose steps do not contract may stop early where a failure is
        # retried at half the step; the try that decides runs to the cap
        may_stop(state, 1.0 if (not straight and min(h, abs(dphi)) > h_min) else 0.0)
        st = position(K, target, order if final else 0, tols, state, pos, d1, d2, margins,
                      with_com and final)
        may_stop(state, 0.0)
        if straight:
            margins[N_GROUPS] = group      # the group of the failure reported
            return status
        # retry decisions use the intended step h, never the rounded dphi
        # (phi + h - phi can exceed h_min by an ulp forever)
        if (st == NEWTON_MAXITER or st == BRANCH_JUMP) and min(h, abs(dphi)) > h_min:
            restore(state)
            h_cap = 0.5 * min(h, abs(dphi))
            continue
        if st == OK:
            accept(state, dphi)
            h_cap = min(2.0 * h_cap, tols[T_SUBSTEP])
            phi = target
            margins[N_GROUPS + 1] = phi
            if final:
                return status
            continue
        # a failure at the smallest step is a fact about the candidate
        if status == OK:
            status = st
            group = margins[N_GROUPS]
            margins[N_GROUPS + 2] = target
        if st == NEWTON_MAXITER:
            restore(state)
        if final or tols[T_GO_ON] == 0.0:
            return status       # (a sweep's careful path, a location: no further)
        straight = True
