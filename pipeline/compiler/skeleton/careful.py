"""The careful path of a generated module: the between-sample watch, the walks,
the scene's revolution and forces, the sweep's careful stages (``evaluate_careful``,
``settle``) and crank dynamics (``begin`` .. ``terms_curve``).

The text below the marker line is pasted into the generated module
(``pipeline.compiler.generate``); the imports above it declare, for linters and
readers, the names the generated module gives it."""

from .header import (math, np, njit, JIT, JIT_ALLOC, OK, BRANCH_JUMP, SINGULAR, S_A, S_B,
                     S_ITERS, S_MARGIN, N_STATE, N_TOLS, T_MIN_STEP, T_NEWTON_TOL, T_WATCH,
                     T_TOUCH, T_LOCATE, closes, copy2, restore, work, drive,
                     lagrange_terms, potential, force_work, dwell_error, law_error,
                     relative_angle, M_STROKE, M_DWELL, M_DWELL_START, M_MARGIN, M_PEAK_R,
                     M_PEAK_JOINT, M_PEAK_PHI, M_PEAK_MBAL, M_FAIL_PHI, M_NEWTON_MEAN,
                     M_FORCES_DONE, M_FAIL_GROUP, M_PEAK_ACC, M_PEAK_EPS, M_MIN_TRANS,
                     M_LAW_RMS, M_LAW_MAX, M_LAW_SHIFT, N_METRICS, SET_STROKE_RADIUS,
                     SET_DWELL_W, SET_WANT_FORCES, SET_STROKE_LO, SET_STROKE_HI,
                     SET_MARGIN_MIN, SET_OMEGA1, SET_EPS1, SET_WANT_PEAKS, SET_WORK_POINT,
                     SET_WANT_TRANSMISSION, SET_WANT_LAW, SET_LAW0, LAW_BEST, FOLD_BACK,
                     LOCATE_MIN_STEP, LOCATE_NEWTON_TOL, RESOLVED, SUB, cubic_bound,
                     fold_distance, third_difference, uniform_hit, window_score,
                     window_vertex)
from ._mechanism import (N_POINTS, N_GROUPS, N_TRIADS, N_WATCH, N_BODIES, N_JOINTS,
                         N_SLIDES, N_INPUTS, GRAVITY, BODY_COM, BODY_TURN, BODY_MASS_OFF,
                         LOAD_BODY, LOAD_POINT, WATCH_G, constants, start, advance,
                         forces_at, transmission, ROCKER_PIVOT, ROCKER_POINT, NEWTON_STEPS)

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


@njit(**JIT)
def watched_values(margins, vals, col):
    """vals[w, col] = margin^2 of every watched group (D of pipeline.kernels.watch)."""
    for w in range(N_WATCH):
        m = margins[WATCH_G[w]]
        vals[w, col] = m * m


@njit(**JIT)
def watched_min(margins):
    """The smallest margin^2 of the watched groups."""
    v = math.inf
    for w in range(N_WATCH):
        v = min(v, margins[WATCH_G[w]] * margins[WATCH_G[w]])
    return v


@njit(**JIT)
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


@njit(**JIT)
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


@njit(**JIT)
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
        watched_values(margins, sub_val, 0)
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


@njit(**JIT)
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


@njit(**JIT)
def walk_angle(phis, k, phi_close):
    """Crank angle of step k of a watched walk: phis, then (a full revolution)
    phi_close and two more positions past it, so that the watch's windows
    wrap round the closing position."""
    n = phis.shape[0]
    return phis[k] if k < n else phi_close + (phis[k - n] - phis[0])


@njit(**JIT)
def walk_steps(phis, phi_close):
    """Steps of a watched walk (see walk_angle)."""
    n = phis.shape[0]
    return n + 3 if (math.isfinite(phi_close) and n >= 3) else n


@njit(**JIT)
def walk_start(K, phi0, state):
    """Crank angle where a walk to ``phi0`` starts."""
    s = start(K, state)
    return phi0 if math.isnan(s) else s


@njit(**JIT_ALLOC)
def revolution(par, phis, phi_close, order, tols, pos_out, d1_out, d2_out, status_out,
               margin_out, iters_out, fail_out):
    """The mechanism at the crank angles ``phis`` (rad) by continuation.

    Outputs per position: pos_out/d1_out/d2_out (n_phi, n_points, 2),
    status_out (n_phi) int8, margin_out (n_phi, n_groups), iters_out (n_phi)
    Newton iterations summed over class III groups.  With a finite
    ``phi_close`` the continuation goes on to it and the revolution must
    close on the state at phis[0] (BRANCH_JUMP otherwise).  Between positions
    the watch (pipeline.kernels.watch) looks for failures the positions do
    not show.  Returns the first failure met along the walk, located between
    positions: fail_out = (its crank angle, its group; -1: the closure); OK
    with fail_out = (NaN, -1).  After a failure the walk goes on (a scene
    shows what can be shown) without the watch."""
    K = constants(par)
    pos, d1, d2, margins, state, start_state = work(N_POINTS, N_GROUPS, N_TRIADS)
    ww = watch_work()
    found = ww[7]
    keep = np.empty((N_TRIADS, N_STATE))
    n = phis.shape[0]
    fail_out[0] = math.nan
    fail_out[1] = -1.0
    phi_prev = walk_start(K, phis[0], state)
    overall = OK
    for k in range(walk_steps(phis, phi_close)):
        phi = walk_angle(phis, k, phi_close)
        if k >= n and (overall != OK or (N_TRIADS == 0 and N_WATCH == 0)):
            break       # the closing position and past it: only for a whole walk
        st = advance(K, phi_prev, phi, order if k < n else 0, tols, state, pos, d1, d2,
                     margins, k < n)
        if k == 0:
            copy2(state, start_state)
        if k < n:
            status_out[k] = st
            it = 0.0
            for g in range(N_GROUPS):
                margin_out[k, g] = margins[g]
            for j in range(N_TRIADS):
                it += state[j, S_ITERS]
            iters_out[k] = it
            copy2(pos, pos_out[k])
            if order >= 1:
                copy2(d1, d1_out[k])
            if order >= 2:
                copy2(d2, d2_out[k])
        if overall == OK:
            if st != OK:
                overall = st
                found[1] = phi
                found[2] = margins[N_GROUPS]
                if k > 0:     # located between the last good position and this one
                    copy2(state, keep)
                    overall = locate(K, phi_prev, phi, st, margins[N_GROUPS],
                                     ww[2][(k - 1) & 3],
                                     tols, state, pos, d1, d2, margins, ww)
                    copy2(keep, state)
                fail_out[0] = found[1]
                fail_out[1] = found[2]
            elif k == n and N_TRIADS > 0 and not closes(state, start_state, tols):
                overall = BRANCH_JUMP
                fail_out[0] = phi_close
                fail_out[1] = -1.0
            else:
                sw = watch(K, k, phi, tols, state, pos, d1, d2, margins, ww)
                if sw != OK:
                    overall = sw
                    fail_out[0] = found[1]
                    fail_out[1] = found[2]
        phi_prev = phi
    return overall


@njit(**JIT_ALLOC)
def forces_curve(par, pos, d1, d2, omega1, eps1, loads, loads_out, r_out, slide_out, m_out):
    """forces_at every position k of pos/d1/d2 (n, n_points, 2); loads (n, n_loads, 3)."""
    work_a, work_b, _l, _r, _s = force_work(N_BODIES, N_JOINTS, N_SLIDES + N_INPUTS)
    for k in range(pos.shape[0]):
        m_out[k] = forces_at(par, pos[k], d1[k], d2[k], omega1, eps1, loads[k], work_a,
                             work_b, loads_out[k], r_out[k], slide_out[k])


# inline='always': one call site in the sweep; as its own function numba would
# build and link a library of everything it calls once more (compile time)
@njit(inline='always', **JIT)
def careful_positions(K, phis, phi_close, tols, theta, out, wk, ww):
    """Stage 1 of the sweep for one candidate on the careful path: assembly
    over the revolution (triangle, Newton, branch, closure) and between its
    positions (the watch), the rocker angles ``theta`` from the first
    position, the singularity margin and the Newton iterations.  Returns
    (status, margin, iterations); a failure writes its crank angle (located
    between positions) and its group to out[M_FAIL_PHI], out[M_FAIL_GROUP].
    Always from the start: a walk resumed midway decides its steps near a fold
    from another history, and may name a failure differently.  wk, ww: the
    walk's and the watch's work arrays (work, watch_work)."""
    n = phis.shape[0]
    pos, d1, d2, margins, state, start_state = wk
    found = ww[7]
    phi_prev = walk_start(K, phis[0], state)
    margin = math.inf
    iters = 0.0
    x0 = 0.0
    y0 = 0.0
    for k in range(walk_steps(phis, phi_close)):
        phi = walk_angle(phis, k, phi_close)   # k >= n: the closing position and past it
        st = advance(K, phi_prev, phi, np.int64(0), tols, state, pos, d1, d2, margins,
                     np.bool_(False))
        if st != OK:
            if k > 0:    # located between the last good position and this one
                st = locate(K, phi_prev, phi, st, margins[N_GROUPS], ww[2][(k - 1) & 3],
                            tols, state, pos, d1, d2, margins, ww)
            else:
                found[1] = phi
                found[2] = margins[N_GROUPS]
            out[M_FAIL_PHI] = found[1]
            out[M_FAIL_GROUP] = found[2]
            return st, margin, iters
        phi_prev = phi
        if k == n and N_TRIADS > 0 and not closes(state, start_state, tols):
            out[M_FAIL_PHI] = phi_close
            out[M_FAIL_GROUP] = -1.0
            return BRANCH_JUMP, margin, iters
        if k < n:
            rx = pos[ROCKER_POINT, 0] - pos[ROCKER_PIVOT, 0]
            ry = pos[ROCKER_POINT, 1] - pos[ROCKER_PIVOT, 1]
            if k == 0:
                copy2(state, start_state)
                x0 = rx
                y0 = ry
            for j in range(N_TRIADS):
                margin = min(margin, state[j, S_MARGIN])
                iters += state[j, S_ITERS]
            theta[k] = relative_angle(x0, y0, rx, ry)
        st = watch(K, k, phi, tols, state, pos, d1, d2, margins, ww)
        if st != OK:
            out[M_FAIL_PHI] = found[1]
            out[M_FAIL_GROUP] = found[2]
            return st, margin, iters
    return OK, margin, iters


@njit(**JIT_ALLOC)
def evaluate_careful(par, phis, phi_close, tols, settings, loads, theta, trail, qmax, qmin,
                     out):
    """The sweep's stages for one candidate on the careful path; writes
    ``out`` (N_METRICS) and returns its status.  theta, trail, qmax, qmin:
    work arrays (n, (n + 1, 4 N_TRIADS), and n + w + 1 integers twice).
    One candidate alone (tests, tools); ``evaluate`` calls ``settle``."""
    return settle(par, np.int64(-1), phis, phi_close, tols, settings, loads, theta,
                  trail, qmax, qmin, 0.0, np.int64(-1), 0.0, 0.0,
                  work(N_POINTS, N_GROUPS, N_TRIADS),
                  force_work(N_BODIES, N_JOINTS, N_SLIDES + N_INPUTS), watch_work(),
                  np.empty(phis.shape[0]), out)


@njit(**JIT)
def settle(par, vouched, phis, phi_close, tols, settings, loads, col, trail, qmax, qmin,
           err, start_k, full, margin, wk, fw, ww, corr, out):
    """Metrics of one candidate into ``out`` (N_METRICS); returns its status.
    Where ``vouched`` (> 0) the lane path's dwell (err, start_k, full),
    margin and class III solutions ``trail`` are taken (and its rocker
    angles in ``col`` where the law error is asked for); otherwise the
    careful path walks the revolution first.  Then stroke, dwell and margin
    metrics, the law error where asked, and the force stage where it
    applies.  col, trail, qmax, qmin, wk (work), fw (force_work), corr (n):
    work arrays of the caller, so nothing is allocated per candidate."""
    for c in range(N_METRICS):
        out[c] = math.nan
    out[M_FORCES_DONE] = 0.0
    n = phis.shape[0]
    K = constants(par)
    iters = float(NEWTON_STEPS * N_TRIADS * n)
    if vouched <= 0:
        st, margin, iters = careful_positions(K, phis, phi_close, tols, col, out, wk, ww)
        if st != OK:
            return st
        err, start_k, full = dwell_error(col, int(settings[SET_DWELL_W]), qmax, qmin)
    out[M_STROKE] = settings[SET_STROKE_RADIUS] * full
    out[M_DWELL] = err
    out[M_DWELL_START] = phis[start_k] if start_k >= 0 else math.nan
    out[M_MARGIN] = margin if N_TRIADS > 0 else math.nan
    out[M_NEWTON_MEAN] = iters / n
    if settings[SET_WANT_LAW] != 0.0:
        # the rocker angles against the required law (settings[SET_LAW0:], two turns)
        rms, top, sh = law_error(col, settings, SET_LAW0,
                                 settings[SET_WANT_LAW] == LAW_BEST, corr)
        out[M_LAW_RMS] = rms
        out[M_LAW_MAX] = top
        out[M_LAW_SHIFT] = sh * (2.0 * math.pi / n) if sh >= 0 else math.nan
    if (settings[SET_WANT_FORCES] == 0.0 and settings[SET_WANT_PEAKS] == 0.0
            and settings[SET_WANT_TRANSMISSION] == 0.0):
        return OK
    if not (out[M_STROKE] >= settings[SET_STROKE_LO]
            and out[M_STROKE] <= settings[SET_STROKE_HI]):
        return OK
    if N_TRIADS > 0 and not (margin >= settings[SET_MARGIN_MIN]):
        return OK
    st = OK
    for attempt in range(2):
        # with the lane path's solutions first; if a direct solve refuses, the
        # careful walk (one call site: numba inlines per call site)
        trail_ok = vouched > 0 and attempt == 0
        st = force_stage(par, K, phis, tols, settings, loads, out, trail, trail_ok, wk, fw)
        if st == OK or not trail_ok:
            break
    return st


# inline='always': one call site in the sweep; as its own function numba would
# build and link a library of everything it calls once more (compile time)
@njit(inline='always', **JIT)
def force_stage(par, K, phis, tols, settings, loads, out, trail, use_trail, wk, fw):
    """Stage 2 at every position of the grid, what the settings ask for:
    kinetostatics (SET_WANT_FORCES: the peak reaction, its joint and angle,
    the peak |balancing moment|), the working point's peak |a| and the
    output rocker's peak |eps| (SET_WANT_PEAKS), the smallest transmission
    angle (SET_WANT_TRANSMISSION); maxima (minima) over the grid's
    positions.  With ``use_trail`` every position is solved directly from
    the class III solution the lane path found there (trail[k] = e(a), e(b)
    per group: Newton confirms it, the branch checks still apply);
    otherwise by the careful continuation.  wk, fw: work arrays (work,
    force_work)."""
    omega1 = settings[SET_OMEGA1]
    eps1 = settings[SET_EPS1]
    want_f = settings[SET_WANT_FORCES] != 0.0
    want_p = settings[SET_WANT_PEAKS] != 0.0
    want_t = settings[SET_WANT_TRANSMISSION] != 0.0
    order = 2 if (want_f or want_p) else 0
    iw = int(settings[SET_WORK_POINT])
    pos, d1, d2, margins, state, _ = wk
    work_a, work_b, loads_out, r_out, slide_out = fw
    phi_prev = walk_start(K, phis[0], state)
    peak = -1.0
    peak_j = -1
    peak_phi = math.nan
    peak_m = 0.0
    peak_a = 0.0
    peak_e = 0.0
    trans = math.inf
    for k in range(phis.shape[0]):
        if use_trail:
            # a walk of length zero: Newton at phis[k] from the lane's solution
            for j in range(N_TRIADS):
                state[j, S_A] = math.atan2(trail[k, 4 * j + 1], trail[k, 4 * j])
                state[j, S_B] = math.atan2(trail[k, 4 * j + 3], trail[k, 4 * j + 2])
            phi_prev = phis[k]
        st = advance(K, phi_prev, phis[k], order, tols, state, pos, d1, d2, margins,
                     want_f)
        phi_prev = phis[k]
        if st != OK:  # cannot happen after stage 1 unless the solver is not deterministic
            out[M_FAIL_PHI] = phis[k]
            return st
        if want_f:
            mb = forces_at(par, pos, d1, d2, omega1, eps1, loads[k], work_a, work_b,
                           loads_out, r_out, slide_out)
            if abs(mb) > abs(peak_m) or not math.isfinite(mb):
                peak_m = mb
            for j in range(N_JOINTS):
                r = math.hypot(r_out[j, 0], r_out[j, 1])
                if r > peak or not math.isfinite(r):
                    peak = r
                    peak_j = j
                    peak_phi = phis[k]
        if want_p:
            # |a| = |r'' omega1^2 + r' eps1| of the working point (mm/s^2)
            ax = d2[iw, 0] * omega1 ** 2 + d1[iw, 0] * eps1
            ay = d2[iw, 1] * omega1 ** 2 + d1[iw, 1] * eps1
            a = math.hypot(ax, ay)
            if a > peak_a or not math.isfinite(a):
                peak_a = a
            # the rocker's angle analogs (geometry.angle_analogs), eps = theta'' w^2 + theta' eps1
            dx = pos[ROCKER_POINT, 0] - pos[ROCKER_PIVOT, 0]
            dy = pos[ROCKER_POINT, 1] - pos[ROCKER_PIVOT, 1]
            d1x = d1[ROCKER_POINT, 0] - d1[ROCKER_PIVOT, 0]
            d1y = d1[ROCKER_POINT, 1] - d1[ROCKER_PIVOT, 1]
            d2x = d2[ROCKER_POINT, 0] - d2[ROCKER_PIVOT, 0]
            d2y = d2[ROCKER_POINT, 1] - d2[ROCKER_PIVOT, 1]
            r2 = dx * dx + dy * dy
            c1 = dx * d1y - dy * d1x
            th1 = c1 / r2
            th2 = (dx * d2y - dy * d2x) / r2 - 2.0 * (dx * d1x + dy * d1y) * c1 / (r2 * r2)
            e = abs(th2 * omega1 ** 2 + th1 * eps1)
            if e > peak_e or not math.isfinite(e):
                peak_e = e
        if want_t:
            t = transmission(K, pos)
            if t < trans or not math.isfinite(t):
                trans = t
    if want_f:
        out[M_PEAK_R] = peak
        out[M_PEAK_JOINT] = peak_j
        out[M_PEAK_PHI] = peak_phi
        out[M_PEAK_MBAL] = abs(peak_m)
    if want_p:
        out[M_PEAK_ACC] = peak_a / 1000.0        # m/s^2
        out[M_PEAK_EPS] = peak_e
    if want_t:
        out[M_MIN_TRANS] = trans if trans <= 0.5 * math.pi else math.nan
    out[M_FORCES_DONE] = 1.0
    return OK


@njit(**JIT)
def begin(par, phi, state, last):
    """Start a dynamics continuation towards ``phi`` (last[0]: where the
    first evaluation walks from)."""
    last[0] = walk_start(constants(par), phi, state)


@njit(**JIT)
def acceleration(par, tols, const, tab_phi, h_phi, tab_t, h_t, damping, t, phi, omega,
                 state, last, pos, d1, d2, margins, loads_k):
    """eps1 = (Q + M1 - (1/2) J' omega^2 - b omega) / J at (t, phi, omega).
    Returns (status, eps1); walks the continuation from last[0] to phi."""
    K = constants(par)
    st = advance(K, last[0], phi, np.int64(2), tols, state, pos, d1, d2, margins,
                 np.bool_(True))
    last[0] = phi
    if st != OK:
        return st, math.nan
    m1 = drive(const, tab_phi, h_phi, tab_t, h_t, phi, t, loads_k)
    J, half, Q = lagrange_terms(pos, d1, d2, GRAVITY, par, BODY_COM, BODY_TURN,
                                BODY_MASS_OFF, LOAD_BODY, LOAD_POINT, loads_k)
    eps = (Q + m1 - half * omega * omega - damping * omega) / J
    if not math.isfinite(eps):
        return SINGULAR, math.nan
    return OK, eps


@njit(**JIT_ALLOC)
def rk4(par, tols, const, tab_phi, h_phi, tab_t, h_t, damping, phi0, omega0, dt, n_sub,
        out_t, out_phi, out_omega, out_eps, tail_t, tail_phi, tail_omega, tail_eps):
    """Classical fixed-step RK4 for y = (phi1, omega1) from t = 0.

    Records (t, phi1, omega1, eps1) every ``n_sub`` steps into the out_*
    arrays (n_samples = out_t.shape[0]; the run has (n_samples - 1) n_sub
    steps) and at every one of the last tail_t.shape[0] steps into the tail_*
    arrays.  eps1 of a sample is the first stage of the following step.
    Returns (status, samples recorded)."""
    pos, d1, d2, margins, state, _ = work(N_POINTS, N_GROUPS, N_TRIADS)
    last = np.empty(1)
    loads_k = np.empty((LOAD_BODY.shape[0], 3))
    n_samples = out_t.shape[0]
    n_steps = (n_samples - 1) * n_sub
    n_tail = tail_t.shape[0]
    tail0 = n_steps - n_tail + 1
    begin(par, phi0, state, last)
    p = phi0
    w = omega0
    h = dt
    e = 0.0
    st = OK
    recorded = 0
    # one call site of ``acceleration`` (numba inlines per call site: this keeps
    # the compile time down): evaluation s = 0 is the start, s = 1..3 are RK4
    # stages 2..4, s = 4 is the new state (= stage 1 of the next step)
    n = 0
    s = 0
    kp = 0.0
    kw = 0.0
    sum_p = 0.0
    sum_w = 0.0
    while True:
        if s == 0:
            ts, ps, ws = 0.0, p, w
        elif s < 4:
            c = 0.5 if s < 3 else 1.0
            ts, ps, ws = n * h + c * h, p + c * h * kp, w + c * h * kw
        else:
            p = p + h / 6.0 * sum_p
            w = w + h / 6.0 * sum_w
            n += 1
            ts, ps, ws = n * h, p, w
        st, es = acceleration(par, tols, const, tab_phi, h_phi, tab_t, h_t, damping, ts, ps,
                              ws, state, last, pos, d1, d2, margins, loads_k)
        if st != OK:
            break
        if 0 < s < 4:
            weight = 2.0 if s < 3 else 1.0
            sum_p += weight * ws
            sum_w += weight * es
            kp = ws
            kw = es
            s += 1
            continue
        e = es
        if n % n_sub == 0:
            k = n // n_sub
            out_t[k] = n * h
            out_phi[k] = p
            out_omega[k] = w
            out_eps[k] = e
            recorded = k + 1
        if n >= tail0:
            j = n - tail0
            tail_t[j] = n * h
            tail_phi[j] = p
            tail_omega[j] = w
            tail_eps[j] = e
        if n == n_steps:
            break
        kp = w
        kw = e
        sum_p = w
        sum_w = e
        s = 1
    return st, recorded


@njit(**JIT_ALLOC)
def terms_curve(par, tols, const, tab_phi, h_phi, tab_t, h_t, phis, ts, out_J, out_half,
                out_Q, out_M1, out_V, out_status):
    """J, (1/2) J', Q (without M1), M1 and V at the crank angles ``phis`` (and
    times ``ts`` for the drive channels), by continuation in the given order."""
    pos, d1, d2, margins, state, _ = work(N_POINTS, N_GROUPS, N_TRIADS)
    last = np.empty(1)
    loads_k = np.empty((LOAD_BODY.shape[0], 3))
    K = constants(par)
    worst = OK
    if phis.shape[0] > 0:
        last[0] = walk_start(K, phis[0], state)
    for k in range(phis.shape[0]):
        st = advance(K, last[0], phis[k], np.int64(2), tols, state, pos, d1, d2, margins,
                     np.bool_(True))
        last[0] = phis[k]
        out_status[k] = st
        if worst == OK and st != OK:
            worst = st
        m1 = drive(const, tab_phi, h_phi, tab_t, h_t, phis[k], ts[k], loads_k)
        J, half, Q = lagrange_terms(pos, d1, d2, GRAVITY, par, BODY_COM, BODY_TURN,
                                    BODY_MASS_OFF, LOAD_BODY, LOAD_POINT, loads_k)
        out_J[k] = J
        out_half[k] = half
        out_Q[k] = Q
        out_M1[k] = m1
        out_V[k] = potential(pos, GRAVITY, par, BODY_COM, BODY_MASS_OFF)
    return worst
