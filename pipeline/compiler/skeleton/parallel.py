"""The sweep's entry point of a generated module: ``evaluate`` (lock-step lanes,
the careful path for the rest; ``batch`` is the scene's).

The text below the marker line is pasted into the generated module
(``pipeline.compiler.generate``); the imports above it declare, for linters and
readers, the names the generated module gives it."""

from .header import (math, np, njit, JIT, JIT_ALLOC, OK, work, force_work, dwell_lanes,
                     M_FAIL_PHI, M_FAIL_GROUP, SET_DWELL_W,
                     SET_WANT_LAW)
from ._mechanism import (N_POINTS, N_GROUPS, N_TRIADS, N_BODIES, N_JOINTS, N_SLIDES,
                         N_INPUTS, LANES, N_LANE_ROWS, THETA_COLS, THETA_IN,
                         R_margin, R_flag, R_first_flag, R_last_flag, setup_lane,
                         block_walk, lanes_apply, constants, N_WATCH)
from ._mechanism import (HAS_LANE_FORCES, N_FROWS, FT_COLS, N_RCOLS, force_lane_in)
from ...kernels.walk import walk_angle, watch_work
from .sweep_stages import careful_tail, no_metrics, settle, LANE_METRICS, NEEDS_FORCES
from .lane_forces import lane_forces_apply, force_flush, force_refused

# ---- the skeleton: from here on, pasted into the generated module ----
@njit(**JIT_ALLOC)
def evaluate(pars, lo, hi, phis, phi_close, tols, settings, loads, status, metrics):
    """The sweep's stages for rows lo .. hi - 1 of ``pars``.  Candidates that
    assemble at the first crank position fill the lanes of a block, which
    walks the revolution in lock-step; the others, and every lane the fast
    path cannot vouch for, take the careful path.  A lane's numbers do not
    depend on its neighbours (every lane runs the same vector instructions),
    so a candidate gets the same numbers whatever the thread, chunk or engine
    that runs it.  Serial: the caller runs ranges on threads
    (``pipeline.compiler.parallel``; the kernels release the GIL)."""
    npos = phis.shape[0]
    w = int(settings[SET_DWELL_W])
    # the crank's cos/sin table, shared by every candidate: the positions, the
    # closing angle and two past it (the watch's windows wrap round the close)
    cph = np.empty(npos + 3)
    sph = np.empty(npos + 3)
    close = phi_close if math.isfinite(phi_close) else phis[0]
    crank_table(phis, close, cph, sph)
    # work arrays: once per call, never per candidate
    S = np.empty((N_LANE_ROWS, LANES))
    theta = np.empty((npos + 3, LANES * THETA_COLS))
    col = np.empty(npos)
    trail = np.empty((npos + 1, max(THETA_COLS - 1, 1)))
    W5 = np.empty((5, npos + w + 1, LANES))
    err = np.empty(LANES)
    start_k = np.empty(LANES, np.int64)
    full = np.empty(LANES)
    qmax = np.empty(npos + w + 1, np.int64)
    qmin = np.empty(npos + w + 1, np.int64)
    idx = np.empty(LANES, np.int64)
    corr = np.empty(npos)
    want_law = settings[SET_WANT_LAW] != 0.0
    wk = work(N_POINTS, N_GROUPS, N_TRIADS)
    fw = force_work(N_BODIES, N_JOINTS, N_SLIDES + N_INPUTS)
    ww = watch_work(N_WATCH, N_TRIADS)
    pos, d1, d2, margins, state, _ = wk
    fast = lanes_apply(phis, tols)
    # the force lanes: candidates the lanes vouched for that reach the force stage
    # gather in a block of their own (fidx), solved together when it is full
    in_force_lanes = HAS_LANE_FORCES and fast and lane_forces_apply(settings)
    nf = npos if in_force_lanes else 0      # (their arrays only where they run)
    FS = np.empty(N_FROWS * LANES)
    FT = np.empty((nf, FT_COLS * LANES))
    RB = np.empty((nf, N_RCOLS * LANES))
    crank_tab = np.empty((npos + 1, 2))
    crank_tab[0, 0] = math.nan
    fidx = np.empty(LANES, np.int64)
    forced = 0
    filled = 0
    for i in range(lo, hi + 1):          # i == hi: the last, partial block
        if i < hi:
            filled = candidate_into_lane(pars, i, filled, fast, phis, phi_close, close, tols,
                                         settings, loads, S, theta, col, trail, qmax, qmin, wk,
                                         fw, ww, corr, idx, status, metrics, pos, d1, d2,
                                         margins, state)
        if filled == LANES or (i == hi and filled > 0):
            pad_block(S, theta, filled, npos)
            block_walk(S, theta, cph, sph, phis, tols, settings)
            dwell_lanes(theta, npos, w, LANES, W5, err, start_k, full)
            for l in range(filled):
                st = lane_metrics(pars, idx[l], l, phis, phi_close, tols, settings, loads, S,
                                  theta, col, trail, qmax, qmin, err, start_k, full, want_law,
                                  in_force_lanes, wk, fw, ww, corr, metrics)
                if st != NEEDS_FORCES:
                    status[idx[l]] = st
                    continue
                force_lane_in(pars[idx[l]], np.int64(forced), trail, FS, FT, phis, crank_tab)
                fidx[forced] = idx[l]
                forced += 1
                if forced == LANES:
                    force_lanes_solved(pars, fidx, forced, FS, FT, RB, phis, phi_close, tols,
                                       settings, loads, col, trail, qmax, qmin, wk, fw, ww,
                                       corr, status, metrics)
                    forced = 0
            filled = 0
    if forced > 0:
        force_lanes_solved(pars, fidx, forced, FS, FT, RB, phis, phi_close, tols, settings,
                           loads, col, trail, qmax, qmin, wk, fw, ww, corr, status, metrics)


@njit(inline='always', **JIT)
def crank_table(phis, close, cph, sph):
    """The crank's cos/sin at the walk's positions (``walk_angle``: the grid, the
    closing angle ``close`` and two past it) into cph, sph."""
    for k in range(phis.shape[0] + 3):
        phi = walk_angle(phis, k, close)
        cph[k] = math.cos(phi)
        sph[k] = math.sin(phi)


@njit(inline='always', **JIT)
def candidate_into_lane(pars, i, filled, fast, phis, phi_close, close, tols, settings, loads,
                        S, theta, col, trail, qmax, qmin, wk, fw, ww, corr, idx, status,
                        metrics, pos, d1, d2, margins, state):
    """Candidate ``i`` into the next free lane (``filled``) where it assembles at
    phis[0] and the lanes apply; else its report: a failure at phis[0] as the
    careful path's first step gives it, or the careful path's metrics.  Returns
    the lanes filled after it.  pos .. state: ``wk``'s arrays, unpacked once by
    the caller (an unpacking here, per candidate, counts every array's references:
    2 % of the sweep's time)."""
    code = -1
    if fast:
        # np.int64(...): no literal argument, one compiled version
        code = setup_lane(pars, i, np.int64(filled), phis, close, tols, S, theta, pos,
                          d1, d2, margins, state)
    if code == OK:
        idx[filled] = i
        return filled + 1
    if code > 0:
        # it fails at phis[0], the careful path's first step: that is its report
        no_metrics(metrics[i])
        metrics[i, M_FAIL_PHI] = phis[0]
        metrics[i, M_FAIL_GROUP] = margins[N_GROUPS]
        status[i] = code
    else:
        status[i] = settle(pars[i], np.int64(-1), phis, phi_close, tols, settings,
                           loads, col, trail, qmax, qmin, 0.0, np.int64(-1), 0.0,
                           0.0, wk, fw, ww, corr, metrics[i])
    return filled


@njit(inline='always', **JIT)
def pad_block(S, theta, filled, npos):
    """A partial block's free lanes filled with lane 0 (the walk runs every lane)."""
    for l in range(filled, LANES):
        for r in range(N_LANE_ROWS):
            S[r, l] = S[r, 0]
        for q in range(THETA_COLS):
            theta[0, q * LANES + l] = theta[0, q * LANES]
        for k in range(1, npos + 3):   # (the inputs' laws: every step)
            for q in range(THETA_IN, THETA_COLS):
                theta[k, q * LANES + l] = theta[k, q * LANES]


@njit(inline='always', **JIT)
def lane_metrics(pars, i, l, phis, phi_close, tols, settings, loads, S, theta, col, trail,
                 qmax, qmin, err, start_k, full, want_law, in_force_lanes, wk, fw, ww, corr,
                 metrics):
    """Metrics of candidate ``i`` from lane ``l`` after the block's walk: its
    class III solutions into ``trail``, the careful walk where the lane flagged
    itself, then ``settle``.  Returns its status, or NEEDS_FORCES where the
    force lanes are to run its force stage."""
    npos = phis.shape[0]
    # the lane vouches for its candidate unless it flagged itself
    vouched = np.int64(1) if S[R_flag, l] == 0.0 else np.int64(0)
    for k in range(npos):
        for q in range(THETA_COLS - 1):
            trail[k, q] = theta[k, (1 + q) * LANES + l]
    if vouched == 0:
        # a lane that flagged itself: first the careful walk from two
        # positions before its first flag (the lane vouched for the
        # revolution up to there) to the failure it most likely meets,
        # at most to two positions past its last flag
        k0 = np.int64(S[R_first_flag, l]) - 2
        k1 = min(np.int64(S[R_last_flag, l]) + 3, npos)
        if k0 > 3 and k0 < npos:
            no_metrics(metrics[i])
            st = careful_tail(constants(pars[i]), phis, k0, k1, trail, tols, metrics[i], wk, ww)
            if st != OK:
                return st
    if want_law:     # the lane's rocker angles, for the law error
        for k in range(npos):
            col[k] = theta[k, l]
    how = vouched
    if in_force_lanes and vouched > 0:
        how = np.int64(LANE_METRICS)    # the force stage in the force lanes
    return settle(pars[i], how, phis, phi_close, tols, settings, loads, col, trail, qmax, qmin,
                  err[l], start_k[l], full[l], S[R_margin, l], wk, fw, ww, corr, metrics[i])


@njit(inline='always', **JIT)
def force_lanes_solved(pars, fidx, forced, FS, FT, RB, phis, phi_close, tols, settings, loads,
                       col, trail, qmax, qmin, wk, fw, ww, corr, status, metrics):
    """The force lanes' block of candidates fidx[:forced] solved together, and
    those whose lane could not vouch for them on the scalar force stage."""
    # np.int64(...): no literal argument, one compiled version
    force_flush(fidx, np.int64(forced), FS, FT, RB, phis, tols, settings, loads, status,
                metrics)
    force_refused(pars, fidx, np.int64(forced), FS, FT, phis, phi_close, tols, settings,
                  loads, col, trail, qmax, qmin, wk, fw, ww, corr, status, metrics)
