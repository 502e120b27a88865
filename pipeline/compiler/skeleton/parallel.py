"""The sweep's entry point of a generated module: ``evaluate`` (lock-step lanes,
the careful path for the rest; ``batch`` is the scene's).

The text below the marker line is pasted into the generated module
(``pipeline.compiler.generate``); the imports above it declare, for linters and
readers, the names the generated module gives it."""

from .header import (math, np, njit, JIT_ALLOC, OK, work, force_work, dwell_lanes,
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
    for k in range(npos + 3):
        phi = walk_angle(phis, k, close)
        cph[k] = math.cos(phi)
        sph[k] = math.sin(phi)
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
            code = -1
            if fast:
                # np.int64(...): no literal argument, one compiled version
                code = setup_lane(pars, i, np.int64(filled), phis, close, tols, S, theta, pos,
                                  d1, d2, margins, state)
            if code == OK:
                idx[filled] = i
                filled += 1
            elif code > 0:
                # it fails at phis[0], the careful path's first step: that is its report
                no_metrics(metrics[i])
                metrics[i, M_FAIL_PHI] = phis[0]
                metrics[i, M_FAIL_GROUP] = margins[N_GROUPS]
                status[i] = code
            else:
                status[i] = settle(pars[i], np.int64(-1), phis, phi_close, tols, settings,
                                   loads, col, trail, qmax, qmin, 0.0, np.int64(-1), 0.0,
                                   0.0, wk, fw, ww, corr, metrics[i])
        if filled == LANES or (i == hi and filled > 0):
            for l in range(filled, LANES):     # pad a partial block with lane 0
                for r in range(N_LANE_ROWS):
                    S[r, l] = S[r, 0]
                for q in range(THETA_COLS):
                    theta[0, q * LANES + l] = theta[0, q * LANES]
                for k in range(1, npos + 3):   # (the inputs' laws: every step)
                    for q in range(THETA_IN, THETA_COLS):
                        theta[k, q * LANES + l] = theta[k, q * LANES]
            block_walk(S, theta, cph, sph, phis, tols, settings)
            dwell_lanes(theta, npos, w, LANES, W5, err, start_k, full)
            for l in range(filled):
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
                        no_metrics(metrics[idx[l]])
                        st = careful_tail(constants(pars[idx[l]]), phis, k0, k1, trail, tols,
                                          metrics[idx[l]], wk, ww)
                        if st != OK:
                            status[idx[l]] = st
                            continue
                if want_law:     # the lane's rocker angles, for the law error
                    for k in range(npos):
                        col[k] = theta[k, l]
                how = vouched
                if in_force_lanes and vouched > 0:
                    how = np.int64(LANE_METRICS)    # the force stage in the force lanes
                st = settle(pars[idx[l]], how, phis, phi_close, tols, settings, loads, col,
                            trail, qmax, qmin, err[l], start_k[l], full[l], S[R_margin, l],
                            wk, fw, ww, corr, metrics[idx[l]])
                if st != NEEDS_FORCES:
                    status[idx[l]] = st
                    continue
                force_lane_in(pars[idx[l]], np.int64(forced), trail, FS, FT, phis, crank_tab)
                fidx[forced] = idx[l]
                forced += 1
                if forced == LANES:
                    # np.int64(...): no literal argument, one compiled version
                    force_flush(fidx, np.int64(forced), FS, FT, RB, phis, tols, settings,
                                loads, status, metrics)
                    force_refused(pars, fidx, np.int64(forced), FS, FT, phis, phi_close, tols,
                                  settings, loads, col, trail, qmax, qmin, wk, fw, ww, corr,
                                  status, metrics)
                    forced = 0
            filled = 0
    if forced > 0:
        force_flush(fidx, np.int64(forced), FS, FT, RB, phis, tols, settings, loads, status,
                    metrics)
        force_refused(pars, fidx, np.int64(forced), FS, FT, phis, phi_close, tols, settings,
                      loads, col, trail, qmax, qmin, wk, fw, ww, corr, status, metrics)
