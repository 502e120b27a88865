"""The careful walk over crank angles and its between-sample watch: the groups'
margins between two computed positions, where a failure begins (``locate``,
``refine``), the walk's check at every step (``watch``) and the scene's
revolution (``revolution``).

Each function takes the mechanism's ``advance`` (its continuation: one step
of the crank, pipeline.compiler's generated module) and ``start`` as
arguments, its constants ``K`` and the groups it watches (``watch_g``), so the
same code serves every mechanism:

* the text between the marker lines is pasted into every generated module,
  whose careful stages and batch call it with the module's own ``advance``
  (numba compiles it with the module, as today: the sweep's careful path keeps
  the mechanism's code inline and its constants in registers);
* imported as it is, ``revolution`` (below the end marker) is the scene's:
  compiled once per installation (numba's cache) for ``advance`` and ``start``
  as first-class functions (numba's FunctionType: called through their
  address, not compiled into it) and the constants as an array, so a scene of
  a new mechanism compiles its groups' code only.
"""

import math

import numpy as np
from numba import njit, types
from numba.core.types.function_type import CompileResultWAP
from numba.extending import typeof_impl

from .config import (JIT, JIT_ALLOC, JIT_INNER, OK, BRANCH_JUMP, SINGULAR, S_ITERS, N_STATE,
                     N_TOLS, T_MIN_STEP, T_NEWTON_TOL, T_WATCH, T_TOUCH, T_LOCATE, T_GO_ON,
                     compile_for)
from .continuation import MARGIN_SLOTS, closes, copy2, restore, work
from .watch import (FOLD_BACK, LOCATE_MIN_STEP, LOCATE_NEWTON_TOL, RESOLVED, SUB, cubic_bound,
                    fold_distance, third_difference, uniform_hit, window_score, window_vertex)

# ---- the skeleton: from here on, pasted into the generated module ----
@njit(**JIT_ALLOC)
def watch_work(n_watch, n_triads):
    """Work arrays of the between-sample watch (pipeline.kernels.watch):
    (hist_phi (4), hist_val (n_watch, 4), hist_state (4, n_triads, N_STATE): the
    last four positions of a walk; sub_phi (SUB + 1), sub_val (n_watch, SUB + 1),
    sub_state (SUB + 1, n_triads, N_STATE): an interval looked at closely; keep
    (n_triads, N_STATE); found (3): status, crank angle, group of a failure;
    ltols (N_TOLS): the tolerances of ``locate``)."""
    return (np.empty(4), np.empty((n_watch, 4)), np.empty((4, n_triads, N_STATE)),
            np.empty(SUB + 1), np.empty((n_watch, SUB + 1)),
            np.empty((SUB + 1, n_triads, N_STATE)), np.empty((n_triads, N_STATE)),
            np.empty(3), np.empty(N_TOLS))


@njit(**JIT_INNER)
def watched_values(watch_g, margins, vals, col):
    """vals[w, col] = margin^2 of every watched group (D of pipeline.kernels.watch)."""
    for w in range(watch_g.shape[0]):
        m = margins[watch_g[w]]
        vals[w, col] = m * m


@njit(**JIT_INNER)
def watched_min(watch_g, margins):
    """The smallest margin^2 of the watched groups."""
    v = math.inf
    for w in range(watch_g.shape[0]):
        v = min(v, margins[watch_g[w]] * margins[watch_g[w]])
    return v


@njit(**JIT_INNER)
def worst_window(phis, vals, j0, j1, n):
    """The smallest window_score of the windows centred at j0 .. j1 - 1 of the n
    positions (phis[j], vals[:, j]), the cubic term from four positions; and
    (its centre, its group, its third divided difference)."""
    best = math.inf
    best_j = -1
    best_w = -1
    best_f3 = math.nan
    for j in range(j0, j1):
        q = j - 2 if j >= 2 else j - 1          # four positions around the window
        if q + 3 >= n:
            q = n - 4
        for w in range(vals.shape[0]):
            f3 = third_difference(phis[q], phis[q + 1], phis[q + 2], phis[q + 3],
                                  vals[w, q], vals[w, q + 1], vals[w, q + 2],
                                  vals[w, q + 3])
            sc = window_score(phis[j - 1], phis[j], phis[j + 1], vals[w, j - 1],
                              vals[w, j], vals[w, j + 1], f3)
            if not (sc >= best):
                best = sc
                best_j = j
                best_w = w
                best_f3 = f3
    return best, best_j, best_w, best_f3


@njit(inline='always', **JIT)
def near_rounding(tols, ww):
    """``tols`` with Newton's closure at near rounding (LOCATE_NEWTON_TOL), in the
    watch's work array ww[8]: a located boundary's, and a spliced lane's window
    (the walk's own tolerance leaves a short step's solution within it, not at it)."""
    ltols = ww[8]
    for q in range(N_TOLS):
        ltols[q] = tols[q]
    ltols[T_NEWTON_TOL] = min(tols[T_NEWTON_TOL], LOCATE_NEWTON_TOL)
    ltols[T_GO_ON] = 0.0     # (a trial that fails is put back: nothing past it is read)
    return ltols


@njit(**JIT_INNER)
def locate(advance, K, watch_g, good, bad, st_bad, g_bad, good_state, tols, state, pos, d1, d2,
           margins, ww):
    """Bisect between ``good`` (assembled: ``good_state`` is its solution) and
    ``bad`` (the walk from good to bad failed with st_bad at group g_bad) down to
    tols[T_LOCATE]; found = (status, crank angle of the first failing position,
    group).  Returns the status; ``state`` is the solution at the good end.
    Called right after the walk from good to bad failed (``state`` as it left
    it): its last accepted angle and the angle of its failing step
    (margins[fail_g + 1], margins[fail_g + 2]) narrow the bracket, the state
    before the failing step (``restore``) the solution there.
    Where a watched group's margin^2 on the good side has come down to
    tols[T_WATCH] or less the group folds there: a dead position the crank
    cannot pass, reported SINGULAR whatever the solver met beyond it."""
    fail_g = margins.shape[0] - MARGIN_SLOTS     # margins: the groups', then 3 slots
    reached = margins[fail_g + 1]
    tried = margins[fail_g + 2]
    keep = ww[6]
    found = ww[7]
    # closure to near rounding: Newton's tolerance blurs where a fold is; each
    # trial a short walk from the good side with few halvings (a trial beyond
    # the boundary fails fast; the bracket shrinks anyway)
    ltols = near_rounding(tols, ww)
    ltols[T_MIN_STEP] = max(tols[T_MIN_STEP], LOCATE_MIN_STEP)
    if (tried - good) * (bad - tried) > 0.0:
        bad = tried
    d_good = math.inf        # the smallest watched margin^2 at the good end
    restore(state)
    if (reached - good) * (bad - reached) > 0.0:
        # the walk's last angle, solved again to the trials' closure: beyond a
        # fold by Newton's tolerance it is the bad end instead
        if advance(K, reached, reached, np.int64(0), ltols, state, pos, d1, d2, margins,
                   np.bool_(False)) == OK:
            good = reached
            d_good = watched_min(watch_g, margins)
        else:
            bad = reached
            copy2(good_state, state)
    else:
        copy2(good_state, state)
    copy2(state, keep)
    mid = 0.5 * (good + bad)
    for it in range(200):
        if not abs(bad - good) > tols[T_LOCATE]:
            break
        if d_good <= tols[T_WATCH] and not abs(bad - good) > 2.0 * FOLD_BACK:
            break     # a fold, close enough: extrapolated below
        st = advance(K, good, mid, np.int64(0), ltols, state, pos, d1, d2, margins,
                      np.bool_(False))
        if st == OK:
            good = mid
            copy2(state, keep)
            d_good = watched_min(watch_g, margins)
        else:
            bad = mid
            st_bad = st
            g_bad = margins[fail_g]
            copy2(keep, state)
        mid = 0.5 * (good + bad)
    at = bad
    if d_good <= tols[T_WATCH]:
        st_bad = SINGULAR
        # a fold: margin^2 goes to zero with the crank angle, linearly (and a
        # narrow lock's other edge adds a square).  Newton converges a little
        # past the fold (within its tolerance of closure), so the bracket's
        # edge is blurred there; the parabola through margin^2 at the good end
        # and FOLD_BACK, 2 FOLD_BACK short of it has its zero at the fold
        back = -FOLD_BACK if bad > good else FOLD_BACK
        copy2(keep, state)
        st1 = advance(K, good, good + back, np.int64(0), ltols, state, pos, d1, d2, margins,
                      np.bool_(False))
        v1 = watched_min(watch_g, margins)
        st2 = advance(K, good + back, good + 2.0 * back, np.int64(0), ltols, state, pos, d1, d2,
                      margins, np.bool_(False))
        v2 = watched_min(watch_g, margins)
        if st1 == OK and st2 == OK:
            x = fold_distance(d_good, v1, v2, FOLD_BACK)
            if math.isfinite(x) and x <= abs(bad - good) + 2.0 * FOLD_BACK:
                at = good - x * back / FOLD_BACK
        copy2(keep, state)
    found[0] = st_bad
    found[1] = at
    found[2] = g_bad
    return st_bad


@njit(**JIT_INNER)
def refine(advance, K, watch_g, lo, hi, tols, state, pos, d1, d2, margins, ww):
    """The walk from ``lo`` (``state``: its solution) to ``hi`` looked at closely:
    SUB sub-positions under the same certificate, zooming in on the worst
    window, until it is cleared (OK), a sub-position fails (its boundary
    located: ``locate``) or the window is narrower than tols[T_LOCATE] with a
    margin^2 at most tols[T_TOUCH] (SINGULAR there: a toggle passed between
    positions).  found = (status, crank angle, group).  Returns the status."""
    sub_phi, sub_val, sub_state, found = ww[3], ww[4], ww[5], ww[7]
    fail_g = margins.shape[0] - MARGIN_SLOTS     # margins: the groups', then 3 slots
    for level in range(200):
        copy2(state, sub_state[0])
        st = advance(K, lo, lo, np.int64(0), tols, state, pos, d1, d2, margins,
                     np.bool_(False))
        if st != OK:    # cannot happen: lo was solved before
            found[0] = st
            found[1] = lo
            found[2] = margins[fail_g]
            return st
        sub_phi[0] = lo
        watched_values(watch_g, margins, sub_val, np.int64(0))
        for i in range(1, SUB + 1):
            t = hi if i == SUB else lo + (hi - lo) * i / SUB
            st = advance(K, sub_phi[i - 1], t, np.int64(0), tols, state, pos, d1, d2,
                         margins, np.bool_(False))
            if st != OK:
                g = margins[fail_g]
                if st == SINGULAR and i >= 3:
                    # the group says toggle: where its margin^2 touches zero, the
                    # quadratic through the three sub-positions before, resolved
                    # (their margins well above rounding), has its vertex; the
                    # positions at the toggle itself are only rounding noise
                    for w in range(watch_g.shape[0]):
                        if watch_g[w] == g:
                            at, low = window_vertex(sub_phi[i - 3], sub_phi[i - 2],
                                                    sub_phi[i - 1], sub_val[w, i - 3],
                                                    sub_val[w, i - 2], sub_val[w, i - 1])
                            if ((at - sub_phi[i - 1]) * (t - at) >= 0.0
                                    and low <= tols[T_TOUCH]):
                                found[0] = SINGULAR
                                found[1] = at
                                found[2] = g
                                return SINGULAR
                return locate(advance, K, watch_g, sub_phi[i - 1], t, st, g, sub_state[i - 1], tols,
                              state, pos, d1, d2, margins, ww)
            sub_phi[i] = t
            watched_values(watch_g, margins, sub_val, i)
            copy2(state, sub_state[i])
        best, j, w, f3 = worst_window(sub_phi, sub_val, 1, SUB, SUB + 1)
        wide = abs(hi - lo) > tols[T_LOCATE]
        if best <= tols[T_TOUCH] and (not wide or cubic_bound(
                sub_phi[j - 1], sub_phi[j + 1], f3) <= RESOLVED * tols[T_TOUCH]):
            # resolved: the quadratic is exact here to well within T_TOUCH; its
            # smallest value is the margin^2 of a toggle passed between positions
            # (its vertex: exact to rounding where D itself is only noise)
            at, low = window_vertex(sub_phi[j - 1], sub_phi[j], sub_phi[j + 1],
                                    sub_val[w, j - 1], sub_val[w, j], sub_val[w, j + 1])
            if low <= tols[T_TOUCH]:
                # solved there: below zero the group cannot be assembled (a lock
                # narrower than the sub-steps), and the walk fails at its boundary
                jj = j - 1 if (at - sub_phi[j]) * (hi - lo) < 0.0 else j
                copy2(sub_state[jj], state)
                st = advance(K, sub_phi[jj], at, np.int64(0), tols, state, pos, d1, d2, margins,
                             np.bool_(False))
                if st != OK and st != SINGULAR:
                    return locate(advance, K, watch_g, sub_phi[jj], at, st, margins[fail_g],
                                  sub_state[jj], tols, state, pos, d1, d2, margins, ww)
                found[0] = SINGULAR
                found[1] = at
                found[2] = watch_g[w]
                return SINGULAR
        # a sub-position near a singular one (margin^2 at most T_WATCH): a fold
        # closer to it than any sub-step hides from the values, so the walk zooms
        # in on it until its first step from there is shorter than T_LOCATE
        # (the continuation's step control then slows into any fold)
        k_low = -1
        v_low = tols[T_WATCH]
        for i in range(SUB + 1):
            for q in range(watch_g.shape[0]):
                if sub_val[q, i] <= v_low:
                    v_low = sub_val[q, i]
                    k_low = i
        if not wide:
            return OK
        if k_low >= 0 and not (best <= tols[T_TOUCH] and best <= v_low):
            j = min(max(k_low, 1), SUB - 1)
        elif not best <= tols[T_TOUCH]:
            return OK
        lo = sub_phi[j - 1]
        hi = sub_phi[j + 1]
        copy2(sub_state[j - 1], state)
    return OK


@njit(**JIT_INNER)
def watch(advance, K, watch_g, k, phi, tols, state, pos, d1, d2, margins, ww):
    """Position ``k`` of a walk is solved at ``phi`` (OK): into the watch's
    history (a ring of the last four positions), and the window it completes
    (centred at position k - 1; at k = 3 also the first one) is certified
    (``uniform_hit`` where the positions are equally spaced, as a revolution's
    are, else ``window_score``) or looked at
    closely (``refine``, from the window's first position).  Returns OK or the
    failure found (ww[7]: status, angle, group); the walk's state is position
    k's again either way.  pos, d1, d2, margins are overwritten when a window
    is refined."""
    hist_phi, hist_val, hist_state = ww[0], ww[1], ww[2]
    slot = k & 3
    hist_phi[slot] = phi
    watched_values(watch_g, margins, hist_val, slot)
    copy2(state, hist_state[slot])     # (also the good end of a failure: locate)
    if watch_g.shape[0] == 0 or k < 3:
        return OK
    st = OK
    for c in range(1 if k == 3 else k - 1, k):     # in order: the first failure met
        i0 = (c - 1) & 3
        i1 = c & 3
        i2 = (c + 1) & 3
        i3 = (c - 2) & 3 if c >= 2 else (c + 2) & 3    # the fourth position
        hit = False
        p0, p1, p2, p3 = hist_phi[i0], hist_phi[i1], hist_phi[i2], hist_phi[i3]
        even = abs((p2 - p1) - (p1 - p0)) <= 1e-9 * abs(p1 - p0)
        for w in range(watch_g.shape[0]):
            v0, v1, v2, v3 = hist_val[w, i0], hist_val[w, i1], hist_val[w, i2], hist_val[w, i3]
            if even:
                hit = hit or uniform_hit(v0, v1, v2, v3, c < 2, tols[T_WATCH])
            else:     # a walk at uneven angles (a caller's own list): the general form
                f3 = (third_difference(p0, p1, p2, p3, v0, v1, v2, v3) if c < 2 else
                      third_difference(p3, p0, p1, p2, v3, v0, v1, v2))
                hit = hit or not (window_score(p0, p1, p2, v0, v1, v2, f3) > tols[T_WATCH])
        if not hit:
            continue
        copy2(hist_state[i0], state)
        st = refine(advance, K, watch_g, hist_phi[i0], hist_phi[i2], tols, state, pos, d1, d2,
                    margins, ww)
        if st != OK:
            break
    copy2(hist_state[slot], state)
    return st


@njit(**JIT_INNER)
def walk_angle(phis, k, phi_close):
    """Crank angle of step k of a watched walk: phis, then (a full revolution)
    phi_close and two more positions past it, so that the watch's windows
    wrap round the closing position."""
    n = phis.shape[0]
    return phis[k] if k < n else phi_close + (phis[k - n] - phis[0])


@njit(**JIT_INNER)
def walk_steps(phis, phi_close):
    """Steps of a watched walk (see walk_angle)."""
    n = phis.shape[0]
    return n + 3 if (math.isfinite(phi_close) and n >= 3) else n


@njit(**JIT_INNER)
def walk_start(start, K, phi0, state):
    """Crank angle where a walk to ``phi0`` starts."""
    s = start(K, state)
    return phi0 if math.isnan(s) else s
# ---- end of the skeleton ----


@njit(**JIT_INNER)
def record(k, st, order, state, pos, d1, d2, margins, pos_out, d1_out, d2_out, status_out,
           margin_out, iters_out):
    """Row ``k`` of a walk's outputs: the position just solved, its status ``st``,
    the groups' margins and the class III groups' Newton iterations summed."""
    status_out[k] = st
    it = 0.0
    for g in range(margin_out.shape[1]):
        margin_out[k, g] = margins[g]
    for j in range(state.shape[0]):
        it += state[j, S_ITERS]
    iters_out[k] = it
    copy2(pos, pos_out[k])
    if order >= 1:
        copy2(d1, d1_out[k])
    if order >= 2:
        copy2(d2, d2_out[k])


@njit(**JIT_ALLOC)
def walk_revolution(advance, start, K, watch_g, n_triads, phis, phi_close, order, tols, pos_out,
                    d1_out, d2_out, status_out, margin_out, iters_out, fail_out):
    """The mechanism at the crank angles ``phis`` (rad) by continuation.

    Outputs per position: pos_out/d1_out/d2_out (n_phi, n_points, 2),
    status_out (n_phi) int8, margin_out (n_phi, n_groups), iters_out (n_phi)
    Newton iterations summed over the n_triads class III groups.  With a finite
    ``phi_close`` the continuation goes on to it and the revolution must
    close on the state at phis[0] (BRANCH_JUMP otherwise).  Between positions
    the watch looks for failures the positions do not show.  Returns the
    first failure met along the walk, located between positions: fail_out =
    (its crank angle, its group; -1: the closure); OK with fail_out = (NaN,
    -1).  After a failure the walk goes on (a scene shows what can be shown)
    without the watch."""
    n_groups = margin_out.shape[1]
    pos, d1, d2, margins, state, start_state = work(pos_out.shape[1], n_groups, n_triads)
    ww = watch_work(watch_g.shape[0], n_triads)
    found = ww[7]
    keep = np.empty((n_triads, N_STATE))
    n = phis.shape[0]
    fail_out[0] = math.nan
    fail_out[1] = -1.0
    phi_prev = walk_start(start, K, phis[0], state)
    overall = OK
    for k in range(walk_steps(phis, phi_close)):
        phi = walk_angle(phis, k, phi_close)
        if k >= n and (overall != OK or (n_triads == 0 and watch_g.shape[0] == 0)):
            break       # the closing position and past it: only for a whole walk
        st = advance(K, phi_prev, phi, order if k < n else 0, tols, state, pos, d1, d2,
                     margins, k < n)
        if k == 0:
            copy2(state, start_state)
        if k < n:
            record(k, st, order, state, pos, d1, d2, margins, pos_out, d1_out, d2_out,
                   status_out, margin_out, iters_out)
        if overall == OK:
            if st != OK:
                overall = st
                found[1] = phi
                found[2] = margins[n_groups]
                if k > 0:     # located between the last good position and this one
                    copy2(state, keep)
                    overall = locate(advance, K, watch_g, phi_prev, phi, st, margins[n_groups],
                                     ww[2][(k - 1) & 3],
                                     tols, state, pos, d1, d2, margins, ww)
                    copy2(keep, state)
                fail_out[0] = found[1]
                fail_out[1] = found[2]
            elif k == n and n_triads > 0 and not closes(state, start_state, tols):
                overall = BRANCH_JUMP
                fail_out[0] = phi_close
                fail_out[1] = -1.0
            else:
                sw = watch(advance, K, watch_g, k, phi, tols, state, pos, d1, d2, margins, ww)
                if sw != OK:
                    overall = sw
                    fail_out[0] = found[1]
                    fail_out[1] = found[2]
        phi_prev = phi
    return overall


@njit(**JIT_ALLOC)
def walk_states(advance, start, K, n_points, n_groups, phis, order, tols, states_out):
    """states_out[k] (states_out: n_phi x n_triads x N_STATE): the continuation's
    state after position k of ``walk_revolution``'s walk over ``phis`` (no closing
    position), which its next step starts from.  The watch and a failure's
    location put back the state they look behind, so the state is the advances'
    alone."""
    pos, d1, d2, margins, state, _ = work(n_points, n_groups, states_out.shape[1])
    phi_prev = walk_start(start, K, phis[0], state)
    for k in range(phis.shape[0]):
        advance(K, phi_prev, phis[k], order, tols, state, pos, d1, d2, margins, True)
        copy2(state, states_out[k])
        phi_prev = phis[k]


@njit(**JIT_ALLOC)
def walk_on(advance, K, state_from, phi_from, phi, order, tols, pos_out, d1_out, d2_out,
            status_out, margin_out, iters_out):
    """Row 0 of ``walk_revolution``'s outputs for the position a walk reaches at
    ``phi`` from ``phi_from`` where its state was ``state_from`` (``walk_states``):
    the last row of the walk through the positions before and ``phi``, to the bit,
    for one step.  Returns its status."""
    pos, d1, d2, margins, state, _ = work(pos_out.shape[1], margin_out.shape[1],
                                          state_from.shape[0])
    copy2(state_from, state)
    st = advance(K, phi_from, phi, order, tols, state, pos, d1, d2, margins, True)
    # (np.int64: a literal 0 compiled ``record`` once more beside walk_revolution's int64 k)
    record(np.int64(0), st, order, state, pos, d1, d2, margins, pos_out, d1_out, d2_out,
           status_out, margin_out, iters_out)
    return st


# the signatures a generated module's advance and start have for the scene
# (pipeline.compiler.skeleton.careful's revolution): the constants as an array
_F1, _F2, _F3 = types.float64[::1], types.float64[:, ::1], types.float64[:, :, ::1]
ADVANCE = types.FunctionType(types.int64(_F1, types.float64, types.float64, types.int64, _F1, _F2,
                                         _F2, _F2, _F2, _F1, types.boolean))
START = types.FunctionType(types.float64(_F1, _F2))
REVOLUTION = types.int64(ADVANCE, START, _F1, types.int64[::1], types.int64, _F1,
                         types.float64, types.int64, _F1, _F3, _F3, _F3, types.int8[::1], _F2,
                         _F1, _F1)
STATES = types.none(ADVANCE, START, _F1, types.int64, types.int64, _F1, types.int64, _F1, _F3)
WALK_ON = types.int64(ADVANCE, _F1, _F2, types.float64, types.float64, types.int64, _F1, _F3,
                      _F3, _F3, types.int8[::1], _F2, _F1)


def compile_revolution() -> None:
    """``walk_revolution`` compiled (or loaded from numba's cache) for the types
    of REVOLUTION, and for no other, with the walk that goes on from a state
    (``walk_states``, ``walk_on``: a refined peak's trial angles): once per
    installation, not per mechanism (``pipeline.compiler.beside`` does it while
    the first sweep compiles)."""
    if not _READY:
        compile_for(walk_revolution, REVOLUTION)
        compile_for(walk_states, STATES)
        compile_for(walk_on, WALK_ON)
        _READY.append(True)


_READY: list = []       # walk_revolution compiled (its signatures: a new list at every ask)


class FixedFunction(CompileResultWAP):
    """A compiled function passed to kernels as a first-class function whose
    address and numba type are looked up once, for kernels that Python calls
    often (a refined peak's walks, the flywheel's terms): a Dispatcher passed
    instead is looked up again at every call (its compile result, both
    addresses: half of a 110 us one-position walk from Python).  The same
    compiled function, called through its C wrapper."""

    def __init__(self, dispatcher, ftype):
        super().__init__(dispatcher.get_compile_result(ftype.signature))
        self.ftype = types.FunctionType(self.cres.signature)


@typeof_impl.register(FixedFunction)
def _typeof_fixed(val, c):
    return val.ftype


def revolution(advance, start, K, watch_g, n_triads, *args):
    """``walk_revolution`` for a generated module's ``advance`` and ``start``
    (their first-class function types ADVANCE, START) and constants ``K`` (an
    array)."""
    compile_revolution()
    return walk_revolution(advance, start, K, watch_g, n_triads, *args)
