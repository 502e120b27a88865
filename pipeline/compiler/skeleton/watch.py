"""The between-sample watch of a generated module: the groups' margins between
two computed positions, where a failure begins (``locate``, ``refine``) and the
walk's check at every step (``watch``).

The text below the marker line is pasted into the generated module
(``pipeline.compiler.generate``, before ``careful``); the imports above it
declare, for linters and readers, the names the generated module gives it."""


from .header import (math, np, njit, JIT_ALLOC, JIT_INNER, OK, SINGULAR, N_STATE, N_TOLS,
                     T_MIN_STEP, T_NEWTON_TOL, T_WATCH, T_TOUCH, T_LOCATE, copy2, restore,
                     FOLD_BACK, LOCATE_MIN_STEP, LOCATE_NEWTON_TOL, RESOLVED, SUB, cubic_bound,
                     fold_distance, third_difference, uniform_hit, window_score, window_vertex)
from ._mechanism import (N_GROUPS, N_TRIADS, N_WATCH, WATCH_G, advance)

# ---- the skeleton: from here on, pasted into the generated module ----
@njit(**JIT_ALLOC)
def watch_work():
    """Work arrays of the between-sample watch (pipeline.kernels.watch):
    (hist_phi (4), hist_val (N_WATCH, 4), hist_state (4, N_TRIADS, N_STATE): the
    last four positions of a walk; sub_phi (SUB + 1), sub_val (N_WATCH, SUB + 1),
    sub_state (SUB + 1, N_TRIADS, N_STATE): an interval looked at closely; keep
    (N_TRIADS, N_STATE); found (3): status, crank angle, group of a failure;
    ltols (N_TOLS): the tolerances of ``locate``)."""
    return (np.empty(4), np.empty((N_WATCH, 4)), np.empty((4, N_TRIADS, N_STATE)),
            np.empty(SUB + 1), np.empty((N_WATCH, SUB + 1)),
            np.empty((SUB + 1, N_TRIADS, N_STATE)), np.empty((N_TRIADS, N_STATE)),
            np.empty(3), np.empty(N_TOLS))


@njit(**JIT_INNER)
def watched_values(margins, vals, col):
    """vals[w, col] = margin^2 of every watched group (D of pipeline.kernels.watch)."""
    for w in range(N_WATCH):
        m = margins[WATCH_G[w]]
        vals[w, col] = m * m


@njit(**JIT_INNER)
def watched_min(margins):
    """The smallest margin^2 of the watched groups."""
    v = math.inf
    for w in range(N_WATCH):
        v = min(v, margins[WATCH_G[w]] * margins[WATCH_G[w]])
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
        for w in range(N_WATCH):
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


@njit(**JIT_INNER)
def locate(K, good, bad, st_bad, g_bad, good_state, tols, state, pos, d1, d2, margins,
           ww):
    """Bisect between ``good`` (assembled: ``good_state`` is its solution) and
    ``bad`` (the walk from good to bad failed with st_bad at group g_bad) down to
    tols[T_LOCATE]; found = (status, crank angle of the first failing position,
    group).  Returns the status; ``state`` is the solution at the good end.
    Called right after the walk from good to bad failed (``state`` as it left
    it): its last accepted angle and the angle of its failing step
    (margins[N_GROUPS + 1], margins[N_GROUPS + 2]) narrow the bracket, the state
    before the failing step (``restore``) the solution there.
    Where a watched group's margin^2 on the good side has come down to
    tols[T_WATCH] or less the group folds there: a dead position the crank
    cannot pass, reported SINGULAR whatever the solver met beyond it."""
    reached = margins[N_GROUPS + 1]
    tried = margins[N_GROUPS + 2]
    keep = ww[6]
    found = ww[7]
    # each trial a short walk from the good side with few halvings (a trial
    # beyond the boundary fails fast; the bracket shrinks anyway)
    ltols = ww[8]
    for q in range(N_TOLS):
        ltols[q] = tols[q]
    # closure to near rounding: Newton's tolerance blurs where a fold is
    ltols[T_NEWTON_TOL] = min(tols[T_NEWTON_TOL], LOCATE_NEWTON_TOL)
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
            d_good = watched_min(margins)
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
            d_good = watched_min(margins)
        else:
            bad = mid
            st_bad = st
            g_bad = margins[N_GROUPS]
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
        v1 = watched_min(margins)
        st2 = advance(K, good + back, good + 2.0 * back, np.int64(0), ltols, state, pos, d1, d2,
                      margins, np.bool_(False))
        v2 = watched_min(margins)
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
def refine(K, lo, hi, tols, state, pos, d1, d2, margins, ww):
    """The walk from ``lo`` (``state``: its solution) to ``hi`` looked at closely:
    SUB sub-positions under the same certificate, zooming in on the worst
    window, until it is cleared (OK), a sub-position fails (its boundary
    located: ``locate``) or the window is narrower than tols[T_LOCATE] with a
    margin^2 at most tols[T_TOUCH] (SINGULAR there: a toggle passed between
    positions).  found = (status, crank angle, group).  Returns the status."""
    sub_phi, sub_val, sub_state, found = ww[3], ww[4], ww[5], ww[7]
    for level in range(200):
        copy2(state, sub_state[0])
        st = advance(K, lo, lo, np.int64(0), tols, state, pos, d1, d2, margins,
                     np.bool_(False))
        if st != OK:    # cannot happen: lo was solved before
            found[0] = st
            found[1] = lo
            found[2] = margins[N_GROUPS]
            return st
        sub_phi[0] = lo
        watched_values(margins, sub_val, np.int64(0))
        for i in range(1, SUB + 1):
            t = hi if i == SUB else lo + (hi - lo) * i / SUB
            st = advance(K, sub_phi[i - 1], t, np.int64(0), tols, state, pos, d1, d2,
                         margins, np.bool_(False))
            if st != OK:
                g = margins[N_GROUPS]
                if st == SINGULAR and i >= 3:
                    # the group says toggle: where its margin^2 touches zero, the
                    # quadratic through the three sub-positions before, resolved
                    # (their margins well above rounding), has its vertex; the
                    # positions at the toggle itself are only rounding noise
                    for w in range(N_WATCH):
                        if WATCH_G[w] == g:
                            at, low = window_vertex(sub_phi[i - 3], sub_phi[i - 2],
                                                    sub_phi[i - 1], sub_val[w, i - 3],
                                                    sub_val[w, i - 2], sub_val[w, i - 1])
                            if (at - sub_phi[i - 1]) * (t - at) >= 0.0 and                                         low <= tols[T_TOUCH]:
                                found[0] = SINGULAR
                                found[1] = at
                                found[2] = g
                                return SINGULAR
                return locate(K, sub_phi[i - 1], t, st, g, sub_state[i - 1], tols, state,
                              pos, d1, d2, margins, ww)
            sub_phi[i] = t
            watched_values(margins, sub_val, i)
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
                    return locate(K, sub_phi[jj], at, st, margins[N_GROUPS],
                                  sub_state[jj], tols, state, pos, d1, d2, margins, ww)
                found[0] = SINGULAR
                found[1] = at
                found[2] = WATCH_G[w]
                return SINGULAR
        # a sub-position near a singular one (margin^2 at most T_WATCH): a fold
        # closer to it than any sub-step hides from the values, so the walk zooms
        # in on it until its first step from there is shorter than T_LOCATE
        # (the continuation's step control then slows into any fold)
        k_low = -1
        v_low = tols[T_WATCH]
        for i in range(SUB + 1):
            for q in range(N_WATCH):
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
def watch(K, k, phi, tols, state, pos, d1, d2, margins, ww):
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
    watched_values(margins, hist_val, slot)
    copy2(state, hist_state[slot])     # (also the good end of a failure: locate)
    if N_WATCH == 0 or k < 3:
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
        for w in range(N_WATCH):
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
        st = refine(K, hist_phi[i0], hist_phi[i2], tols, state, pos, d1, d2, margins, ww)
        if st != OK:
            break
    copy2(hist_state[slot], state)
    return st


