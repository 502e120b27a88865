"""The sweep's entry point of a generated module: ``evaluate`` (lock-step lanes,
the careful path for the rest; ``batch`` is the scene's).

Candidates that assemble at the first crank position fill the lanes of a
block, which walks the revolution in lock-step; the others, and every lane
the fast path cannot vouch for, take the careful path.  A lane's numbers do
not depend on its neighbours (every lane runs the same vector instructions),
so a candidate gets the same numbers whatever the thread, chunk or engine
that runs it.

The text below the marker line is pasted into the generated module
(``pipeline.compiler.generate``); the imports above it declare, for linters and
readers, the names the generated module gives it."""

from .header import (math, np, njit, JIT, JIT_ALLOC, JIT_ALLOC_INNER, JIT_INNER, OK, work,
                     force_work, dwell_lanes, dwell_error, M_FAIL_PHI, M_FAIL_GROUP, SET_DWELL_W,
                     SET_WANT_LAW, DISABLE_JIT, first_class, function_at)
from ._mechanism import (N_POINTS, N_GROUPS, N_TRIADS, N_BODIES, N_JOINTS, N_SLIDES,
                         N_INPUTS, LANES, N_LANE_ROWS, THETA_COLS, THETA_IN, TRAIL_COLS,
                         MARGIN_COL, N_PARAMS,
                         R_margin, R_flag, R_first_flag, R_last_flag, setup_lane,
                         block_walk, lanes_apply, constants, N_WATCH, advance, WATCH_G,
                         HAS_LANES, walk)
from ._mechanism import (HAS_LANE_FORCES, N_FROWS, FT_COLS, N_RCOLS, force_lane_in,
                         force_lanes)
from ...kernels.walk import walk_angle, watch, watch_work, locate
from .sweep_stages import (careful_tail, no_metrics, settle_cpu, force_stage, LANE_METRICS,
                           NEEDS_FORCES)
from .lane_forces import lane_forces_apply, force_flush, force_refused

# ---- the skeleton: from here on, pasted into the generated module ----
@njit(**JIT_ALLOC_INNER)
def crank_table(phis, close):
    """The crank's cos/sin at the walk's angles, shared by every candidate: the
    positions, the closing angle and two past it (the watch's windows wrap
    round the close)."""
    npos = phis.shape[0]
    cph = np.empty(npos + 3)
    sph = np.empty(npos + 3)
    for k in range(npos + 3):
        phi = walk_angle(phis, k, close)
        cph[k] = math.cos(phi)
        sph[k] = math.sin(phi)
    return cph, sph


@njit(**JIT_ALLOC_INNER)
def lane_work(npos, w):
    """The work arrays of ``evaluate``: once per call, never per candidate (the
    lanes' S and theta, a rocker column, the handed-over trail, the dwell
    windows, the sorting queues, the force lanes' block of candidates)."""
    return (np.empty((N_LANE_ROWS, LANES)), np.empty((npos + 3, LANES * THETA_COLS)),
            np.empty(npos), np.empty((npos + 1, max(TRAIL_COLS, 1))),
            np.empty((5, npos + w + 1, LANES)), np.empty(LANES), np.empty(LANES, np.int64),
            np.empty(LANES), np.empty(npos + w + 1, np.int64), np.empty(npos + w + 1, np.int64),
            np.empty(LANES, np.int64), np.empty(npos), np.empty(LANES, np.int64))


@njit(**JIT_ALLOC_INNER)
def walk_work():
    """The careful walk's, the force stage's and the watch's work arrays."""
    return (work(N_POINTS, N_GROUPS, N_TRIADS), force_work(N_BODIES, N_JOINTS, N_SLIDES + N_INPUTS),
            watch_work(N_WATCH, N_TRIADS))


@njit(**JIT_INNER)
def fails_at_start(code, phis, margins, m):
    """A candidate that fails at phis[0], the careful path's first step: that is
    its report (its metrics row ``m``); returns its status ``code``."""
    no_metrics(m)
    m[M_FAIL_PHI] = phis[0]
    m[M_FAIL_GROUP] = margins[N_GROUPS]
    return code


@njit(**JIT_ALLOC_INNER)
def force_lane_work(nf):
    """The force lanes' arrays (``nf`` positions: 0 where they do not run): the
    block's constants FS, the table handed over FT, the reactions RB, the
    crank's table."""
    crank_tab = np.empty((nf + 1, 2))
    crank_tab[0, 0] = math.nan
    return (np.empty(N_FROWS * LANES), np.empty((nf, FT_COLS * LANES)),
            np.empty((nf, N_RCOLS * LANES)), crank_tab)


@njit(inline='always', **JIT)
def lane_trail(theta, l, npos, trail):
    """Lane ``l``'s solutions at every position (its class III groups' e(a), e(b),
    its inputs' laws) into ``trail``, as the careful tail and the force stages
    take them."""
    for k in range(npos):
        for q in range(TRAIL_COLS):
            trail[k, q] = theta[k, (1 + q) * LANES + l]


@njit(inline='always', **JIT)
def lane_angles(theta, l, npos, col):
    """Lane ``l``'s rocker angles at every position into ``col``."""
    for k in range(npos):
        col[k] = theta[k, l]


@njit(inline='always', **JIT)
def flagged_lane(par, S, theta, l, phis, tols, w, trail, col, qmax, qmin, out, wk, ww,
                 tail_at, called):
    """Lane ``l`` flagged itself (its candidate ``par``, metrics row ``out``): the
    careful walk from two positions before its first flag to three past its
    last (``careful_tail``, called through its address ``tail_at``), to the
    failure it most likely meets.  Returns
    (status, how, dwell error, its start, full range, margin): the failure met,
    or OK and how ``settle`` goes on, 0 (the careful path: the whole revolution)
    or, where the tail met no failure and spliced its careful window into the
    lane's rocker angles ``col`` and solutions ``trail``, 1 (the lane's metrics,
    the scalar force stage from those solutions: the window is where the lane's
    own forms were ill-conditioned).  ``called``: ``callees()``, the tail's own
    callees' addresses among them."""
    npos = phis.shape[0]
    k0 = np.int64(S[R_first_flag, l]) - 2
    k1 = min(np.int64(S[R_last_flag, l]) + 3, npos)
    if not (k0 > 3 and k0 < npos):
        return OK, np.int64(0), math.nan, np.int64(-1), math.nan, math.nan
    no_metrics(out)
    lane_trail(theta, l, npos, trail)
    lane_angles(theta, l, npos, col)     # (the window splices them)
    st, spliced, margin = tail_at(constants(par), phis, k0, k1, trail, col, tols, out, wk, ww,
                                  called)
    if st != OK or not spliced:
        return st, np.int64(0), math.nan, np.int64(-1), math.nan, math.nan
    # the lane's numbers outside the window, the careful walk's inside
    err, start, full = dwell_error(col, w, qmax, qmin)
    return OK, np.int64(1), err, start, full, lane_margin(theta, l, k0, k1, npos, margin)


@njit(inline='always', **JIT)
def lane_margin(theta, l, k0, k1, npos, margin):
    """A spliced lane's singularity margin: the smallest of its careful window's
    (``margin``: positions k0 .. k1) and of the lane's own at every other
    position of its walk (theta's MARGIN_COL: to the close and two past it, as
    the lane's running margin)."""
    for k in range(npos + 3):
        if k < k0 or k > k1:
            margin = min(margin, theta[k, MARGIN_COL * LANES + l])
    return margin


@njit(**JIT_INNER)
def pad_block(S, theta, filled, npos):
    """A partial block's lanes from ``filled`` on: copies of lane 0 (their
    constants, their start, and the inputs' laws at every step)."""
    for l in range(filled, LANES):
        for r in range(N_LANE_ROWS):
            S[r, l] = S[r, 0]
        for q in range(THETA_COLS):
            theta[0, q * LANES + l] = theta[0, q * LANES]
        for k in range(1, npos + 3):
            for q in range(THETA_IN, THETA_COLS):
                theta[k, q * LANES + l] = theta[k, q * LANES]


# (called through its address: ``callees``; settle likewise, not linked into it)
@njit(**JIT_ALLOC_INNER)
def flush_forces(pars, fidx, forced, FS, FT, RB, phis, phi_close, tols, settings, loads, col,
                 trail, qmax, qmin, wk, fw, ww, corr, status, metrics, called):
    """The force lanes' block of ``forced`` candidates solved together, then those
    it refused by the scalar force stage (``forced``: np.int64, no literal
    argument, one compiled version; ``called``: ``callees()``, force_flush's and
    settle_cpu's addresses among them)."""
    function_at(called[5], FORCE_FLUSH_FN)(fidx, forced, FS, FT, RB, phis, tols, settings,
                                           loads, status, metrics, called)
    force_refused(pars, fidx, forced, FS, FT, phis, phi_close, tols, settings, loads, col,
                  trail, qmax, qmin, wk, fw, ww, corr, status, metrics,
                  function_at(called[0], SETTLE_FN), called)


# the function types of the kernels evaluate_lanes and flush_forces call through their
# addresses (``callees``): settle_cpu, flush_forces, setup_lane, careful_tail, block_walk,
# force_flush, and the dwell in lanes, the force lanes' input and the partial block's padding
# (and theirs: sweep_stages' ADVANCE_FN, WATCH_FN, WALK_FN, FORCE_LANES_FN, LOCATE_FN,
# FORCE_STAGE_FN)
SETTLE_FN = None
FLUSH_FN = None
SETUP_FN = None
TAIL_FN = None
BLOCK_WALK_FN = None
FORCE_FLUSH_FN = None
DWELL_LANES_FN = None
LANE_IN_FN = None
PAD_FN = None
_CALLEES = []


def callee_samples():
    """Sample arguments of the types ``evaluate_lanes`` and ``flush_forces`` pass
    the kernels they call through their addresses, by kernel name, in the
    order ``callees`` compiles them (each before its callers); the process
    beside compiles some of them for the same types (``pipeline.compiler.beside``)."""
    n = 4
    a1, a2, i1 = np.zeros(n), np.zeros((n, n)), np.zeros(n, np.int64)
    i64, f64 = np.int64(0), 0.0
    wk = (work.py_func(N_POINTS, N_GROUPS, N_TRIADS),
          force_work.py_func(N_BODIES, N_JOINTS, N_SLIDES + N_INPUTS),
          watch_work.py_func(N_WATCH, N_TRIADS))
    loads = np.zeros((n, 1, 3))
    status = np.zeros(n, np.int8)       # (the run's: pipeline.runs.problem)
    pos, d1, d2, margins, state, _ = wk[0]
    K = constants(np.ones(N_PARAMS))
    watch_g = WATCH_G.copy()
    watch_g.flags.writeable = False     # (a global array: numba's constant, read-only)
    return {
        "advance": (K, f64, f64, i64, a1, state, pos, d1, d2, margins, np.bool_(False)),
        "watch": (K, watch_g, i64, f64, a1, state, pos, d1, d2, margins, wk[2]),
        "settle_cpu": (a1, i64, a1, f64, a1, a1, loads, a1, a2, i1, i1, f64, i64, f64, f64,
                       *wk, a1, a1, i1),
        "locate": (K, watch_g, f64, f64, i64, f64, wk[2][2][0], a1, state, pos, d1, d2,
                   margins, wk[2]),
        "force_stage": (a1, K, a1, a1, a1, loads, a1, a2, np.bool_(False), wk[0], wk[1]),
        "force_flush": (i1, i64, a1, a2, a2, a1, a1, a1, loads, status, a2, i1),
        "flush_forces": (a2, i1, i64, a1, a2, a2, a1, f64, a1, a1, loads, a1, a2, i1, i1, *wk,
                         a1, status, a2, i1),
        "setup_lane": (a2, i64, i64, a1, f64, a1, a2, a2, pos, d1, d2, margins, state, i1),
        "careful_tail": (K, a1, i64, i64, a2, a1, a1, a1, wk[0], wk[2], i1),
        "block_walk": (a2, a2, a1, a1, a1, a1, a1, i1),
        "walk": (a1, i64, a2, a1, a1, i64, i64, f64, f64, f64, f64, f64, f64),
        "force_lanes": (a1, a2, a2, i64, i64, f64, f64, f64, f64, loads, i64),
        "dwell_lanes": (a2, i64, i64, i64, np.zeros((1, 1, 1)), a1, i1, a1),
        "force_lane_in": (a1, i64, a2, a1, a2, a1, a2),
        "pad_block": (a2, a2, i64, i64),
    }


def lane_callees():
    """The addresses of the lane walk (``walk``) and the force lanes
    (``force_lanes``) compiled (or loaded from numba's cache) for the types
    ``block_walk`` and ``force_flush`` pass them (0 where the module has none);
    their function types into WALK_FN and FORCE_LANES_FN, which those compiles
    read (``callees``, and the process beside before it compiles them)."""
    global WALK_FN, FORCE_LANES_FN
    s = callee_samples()
    at_walk = at_force_lanes = 0
    if HAS_LANES:
        WALK_FN, at_walk = first_class(walk, s["walk"])
    if HAS_LANE_FORCES:
        FORCE_LANES_FN, at_force_lanes = first_class(force_lanes, s["force_lanes"])
    return at_walk, at_force_lanes


def tail_callees():
    """The addresses of ``advance``, ``watch`` and ``locate`` compiled (or loaded
    from numba's cache) for the types ``setup_lane``, ``careful_tail`` and
    ``settle_cpu`` pass them; their function types into ADVANCE_FN, WATCH_FN and
    LOCATE_FN, which those compiles read (``callees``, and the process beside
    before it compiles them)."""
    global ADVANCE_FN, WATCH_FN, LOCATE_FN
    s = callee_samples()
    ADVANCE_FN, at_advance = first_class(advance, s["advance"])
    WATCH_FN, at_watch = first_class(watch, s["watch"])
    LOCATE_FN, at_locate = first_class(locate, s["locate"])
    return at_advance, at_watch, at_locate


def callees():
    """The addresses of ``settle_cpu``, ``flush_forces``, ``setup_lane``,
    ``careful_tail``, ``block_walk``, ``force_flush``, ``dwell_lanes``,
    ``force_lane_in``, ``pad_block``, and the ones they call: ``advance`` and
    ``watch`` (at AT_ADVANCE), ``walk`` (AT_WALK), ``force_lanes``
    (AT_FORCE_LANES), ``locate`` (AT_LOCATE) and ``force_stage``
    (AT_FORCE_STAGE), compiled (or loaded from numba's cache)
    for the types ``evaluate_lanes`` and ``flush_forces`` pass them
    (``callee_samples``), which call them through these
    (``pipeline.kernels.calls``): their own compiles then do not link these
    kernels' code and optimise it once more.  Each is called once per
    candidate or per block, never in a loop over positions.  Once per process;
    in numba's Python mode the kernels themselves."""
    global SETTLE_FN, FLUSH_FN, SETUP_FN, TAIL_FN, BLOCK_WALK_FN, FORCE_FLUSH_FN
    global DWELL_LANES_FN, LANE_IN_FN, PAD_FN, FORCE_STAGE_FN
    if DISABLE_JIT:
        return (settle_cpu, flush_forces, setup_lane, careful_tail, block_walk, force_flush,
                dwell_lanes, force_lane_in, pad_block, advance, watch,
                walk if HAS_LANES else None, force_lanes if HAS_LANE_FORCES else None, locate,
                force_stage)
    if not _CALLEES:
        s = callee_samples()
        at_advance, at_watch, at_locate = tail_callees()
        at_lane_walk, at_force_lanes = lane_callees()
        FORCE_STAGE_FN, at_force_stage = first_class(force_stage, s["force_stage"])
        SETTLE_FN, at_settle = first_class(settle_cpu, s["settle_cpu"])
        FORCE_FLUSH_FN, at_force_flush = first_class(force_flush, s["force_flush"])
        FLUSH_FN, at_flush = first_class(flush_forces, s["flush_forces"])
        SETUP_FN, at_setup = first_class(setup_lane, s["setup_lane"])
        TAIL_FN, at_tail = first_class(careful_tail, s["careful_tail"])
        BLOCK_WALK_FN, at_walk = first_class(block_walk, s["block_walk"])
        DWELL_LANES_FN, at_dwell = first_class(dwell_lanes, s["dwell_lanes"])
        LANE_IN_FN, at_lane_in = first_class(force_lane_in, s["force_lane_in"])
        PAD_FN, at_pad = first_class(pad_block, s["pad_block"])
        _CALLEES[:] = [np.array([at_settle, at_flush, at_setup, at_tail, at_walk,
                                 at_force_flush, at_dwell, at_lane_in, at_pad, at_advance,
                                 at_watch, at_lane_walk, at_force_lanes, at_locate,
                                 at_force_stage], np.int64)]
    return _CALLEES[0]


@njit(**JIT_ALLOC)
def careful_alone(par, phis, phi_close, tols, settings, loads, theta, trail, qmax, qmin, out,
                  called):
    """``evaluate_careful``'s compiled part: ``settle_cpu`` through its address
    on the careful path, its work arrays allocated here."""
    return function_at(called[0], SETTLE_FN)(
        par, np.int64(-1), phis, phi_close, tols, settings, loads, theta, trail, qmax, qmin,
        0.0, np.int64(-1), 0.0, 0.0, work(N_POINTS, N_GROUPS, N_TRIADS),
        force_work(N_BODIES, N_JOINTS, N_SLIDES + N_INPUTS), watch_work(N_WATCH, N_TRIADS),
        np.empty(phis.shape[0]), out, called)


def evaluate_careful(par, phis, phi_close, tols, settings, loads, theta, trail, qmax, qmin,
                     out):
    """The sweep's stages for one candidate on the careful path; writes
    ``out`` (N_METRICS) and returns its status.  theta, trail, qmax, qmin:
    work arrays (n, (n + 1, 4 N_TRIADS), and n + w + 1 integers twice).
    One candidate alone (tests, tools); ``evaluate`` calls ``settle_cpu`` so
    too, the GPU's kernel ``settle``."""
    return careful_alone(par, phis, phi_close, tols, settings, loads, theta, trail, qmax, qmin,
                         out, callees())


def evaluate(pars, lo, hi, phis, phi_close, tols, settings, loads, status, metrics):
    """``evaluate_lanes`` for rows lo .. hi - 1 of ``pars`` (C-ordered, as
    ``status`` and ``metrics``): the sweep's stages, the big ones called
    through their addresses (``callees``)."""
    return evaluate_lanes(pars, lo, hi, np.ascontiguousarray(phis), phi_close,
                          np.ascontiguousarray(tols), np.ascontiguousarray(settings),
                          np.ascontiguousarray(loads), status, metrics, callees())


@njit(**JIT_ALLOC)
def evaluate_lanes(pars, lo, hi, phis, phi_close, tols, settings, loads, status, metrics,
                   called):
    """The sweep's stages for rows lo .. hi - 1 of ``pars``: candidates that assemble at
    phis[0] fill a block of lanes walked in lock-step, the others and every lane the lanes
    cannot vouch for the careful path; those vouched for that reach the force stage gather
    in a block (fidx) for the force lanes.  Serial (the caller runs ranges on threads)."""
    settle_at, flush_at = function_at(called[0], SETTLE_FN), function_at(called[1], FLUSH_FN)
    setup_at, tail_at = function_at(called[2], SETUP_FN), function_at(called[3], TAIL_FN)
    block_walk_at, pad_at = function_at(called[4], BLOCK_WALK_FN), function_at(called[8], PAD_FN)
    dwell_at, lane_in_at = (function_at(called[6], DWELL_LANES_FN),
                            function_at(called[7], LANE_IN_FN))
    npos = phis.shape[0]
    w = int(settings[SET_DWELL_W])
    close = phi_close if math.isfinite(phi_close) else phis[0]
    cph, sph = crank_table(phis, close)
    S, theta, col, trail, W5, err, start_k, full, qmax, qmin, idx, corr, fidx = \
        lane_work(npos, w)
    want_law = settings[SET_WANT_LAW] != 0.0
    wk, fw, ww = walk_work()
    pos, d1, d2, margins, state, _ = wk
    fast = lanes_apply(phis, tols)
    in_force_lanes = HAS_LANE_FORCES and fast and lane_forces_apply(settings)
    FS, FT, RB, crank_tab = force_lane_work(npos if in_force_lanes else 0)
    forced = 0
    filled = 0
    for i in range(lo, hi + 1):          # i == hi: the last, partial block
        if i < hi:
            code = -1
            if fast:     # (np.int64(...): no literal argument, one compiled version)
                code = setup_at(pars, i, np.int64(filled), phis, close, tols, S, theta, pos,
                                d1, d2, margins, state, called)
            if code == OK:
                idx[filled] = i
                filled += 1
            elif code > 0:
                status[i] = fails_at_start(code, phis, margins, metrics[i])
            else:
                status[i] = settle_at(pars[i], np.int64(-1), phis, phi_close, tols, settings,
                                      loads, col, trail, qmax, qmin, 0.0, np.int64(-1), 0.0,
                                      0.0, wk, fw, ww, corr, metrics[i], called)
        if filled == LANES or (i == hi and filled > 0):
            pad_at(S, theta, np.int64(filled), npos)
            block_walk_at(S, theta, cph, sph, phis, tols, settings, called)
            dwell_at(theta, npos, w, W5.shape[2], W5, err, start_k, full)  # (lanes: run time)
            for l in range(filled):
                # the lane vouches for its candidate unless it flagged itself: where it
                # vouched, the force stage in the force lanes (LANE_METRICS)
                flagged = S[R_flag, l] != 0.0
                how = np.int64(LANE_METRICS) if in_force_lanes else np.int64(1)
                err_l, start_l, full_l, margin_l = err[l], start_k[l], full[l], S[R_margin, l]
                if flagged:     # the careful tail: its failure, or its window spliced
                    st, how, err_l, start_l, full_l, margin_l = flagged_lane(
                        pars[idx[l]], S, theta, l, phis, tols, w, trail, col, qmax, qmin,
                        metrics[idx[l]], wk, ww, tail_at, called)
                    if st != OK:
                        status[idx[l]] = st
                        continue
                elif want_law:
                    lane_angles(theta, l, npos, col)
                if how == 1 and not flagged:     # (settle's force stage reads its solutions)
                    lane_trail(theta, l, npos, trail)
                st = settle_at(pars[idx[l]], how, phis, phi_close, tols, settings, loads,
                               col, trail, qmax, qmin, err_l, start_l, full_l, margin_l, wk, fw,
                               ww, corr, metrics[idx[l]], called)
                if st != NEEDS_FORCES:
                    status[idx[l]] = st
                    continue
                lane_trail(theta, l, npos, trail)     # (a vouched lane's, for the force lanes)
                lane_in_at(pars[idx[l]], np.int64(forced), trail, FS, FT, phis, crank_tab)
                fidx[forced] = idx[l]
                forced += 1
                if forced == LANES:
                    flush_at(pars, fidx, np.int64(forced), FS, FT, RB, phis, phi_close, tols,
                             settings, loads, col, trail, qmax, qmin, wk, fw, ww, corr, status,
                             metrics, called)
                    forced = 0
            filled = 0
    if forced > 0:
        flush_at(pars, fidx, np.int64(forced), FS, FT, RB, phis, phi_close, tols, settings,
                 loads, col, trail, qmax, qmin, wk, fw, ww, corr, status, metrics, called)
