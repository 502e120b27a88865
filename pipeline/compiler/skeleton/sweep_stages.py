"""The sweep's careful stages of a generated module: one candidate's revolution
on the careful path (``careful_positions``), its metrics (``settle_with``: the
GPU's ``settle`` and the CPU's ``settle_cpu``) and the force stage.  They depend
on the output rocker, so a sweep's module defines them and imports everything
else from the mechanism's own module (``pipeline.compiler.generate``).

The text below the marker line is pasted into the generated module
(``pipeline.compiler.generate``, after ``careful``); the imports above it declare,
for linters and readers, the names the generated module gives it."""

from .header import (math, np, njit, JIT, JIT_INNER, OK, BRANCH_JUMP, S_ITERS,
                     function_at,
                     S_MARGIN, closes, copy2, dwell_error, law_error,
                     relative_angle, M_STROKE, M_DWELL, M_DWELL_START, M_MARGIN, M_PEAK_R,
                     M_PEAK_JOINT, M_PEAK_PHI, M_PEAK_MBAL, M_FAIL_PHI, M_NEWTON_MEAN,
                     M_FORCES_DONE, M_FAIL_GROUP, M_PEAK_ACC, M_PEAK_EPS, M_MIN_TRANS, M_LAW_RMS,
                     M_LAW_MAX, M_LAW_SHIFT, N_METRICS, SET_STROKE_RADIUS, SET_DWELL_W,
                     SET_WANT_FORCES, SET_STROKE_LO, SET_STROKE_HI, SET_MARGIN_MIN, SET_OMEGA1,
                     SET_EPS1, SET_WANT_PEAKS, SET_WORK_POINT, SET_WANT_TRANSMISSION, SET_WANT_LAW,
                     SET_LAW0, LAW_BEST, SET_WANT_EQUILIBRIUM, SET_WANT_SHAKING)
from .header import M_EQUILIBRIUM, equilibrium_residual
from .header import S_HANDED, S_CA, S_SA, S_CB, S_SB, S_A, S_B, T_CLOSE, start_triad
from .header import M_SHAKING_F, M_SHAKING_M, shaking, may_reach
from ._mechanism import (N_GROUPS, N_TRIADS, N_JOINTS, constants, position, advance,
                         forces_at, transmission, ROCKER_PIVOT, ROCKER_POINT, NEWTON_STEPS,
                         WATCH_G, LANE_STEP_MAX)
from ._mechanism import BODY_COM, BODY_TURN, BODY_MASS_OFF, CRANK_PIVOT
from ...kernels.walk import walk_angle, walk_start, walk_steps, locate, watch, near_rounding

# ---- the skeleton: from here on, pasted into the generated module ----
# settle's ``vouched`` beyond the lane's 1 (and the careful path's <= 0): a lane's
# metrics up to the force stage (then NEEDS_FORCES: the force lanes run it), and a
# lane's force stage alone (the force lanes could not vouch for it); the careful
# path's two stages apart (a GPU's split kernels: ``pipeline.compiler.cuda_source``),
# each what settle(-1) runs of it, in the same order
LANE_METRICS = 2
LANE_FORCES = 3
NEEDS_FORCES = -2
CAREFUL_METRICS = -3
CAREFUL_FORCES = -4
# the function types of the kernels that settle_cpu, careful_tail, setup_lane, block_walk
# and force_flush call through their addresses (``callees``: advance at AT_ADVANCE, the
# watch after it, the lane walk at AT_WALK, the force lanes at AT_FORCE_LANES, locate at
# AT_LOCATE, the force stage at AT_FORCE_STAGE)
ADVANCE_FN = None
WATCH_FN = None
WALK_FN = None
FORCE_LANES_FN = None
LOCATE_FN = None
FORCE_STAGE_FN = None
AT_ADVANCE = 9
AT_WALK = 11
AT_FORCE_LANES = 12
AT_LOCATE = 13
AT_FORCE_STAGE = 14

@njit(inline='always', **JIT)
def no_metrics(out):
    """A candidate's metrics row before anything is known: NaN, no force stage."""
    for c in range(N_METRICS):
        out[c] = math.nan
    out[M_FORCES_DONE] = 0.0


@njit(inline='always', **JIT)
def failed(K, k, phi_prev, phi, st, tols, out, wk, ww, loc):
    """Position ``k`` of a careful walk failed (status ``st``) on the step from
    phi_prev to phi: the failure located between them (``loc``: locate; at the
    walk's first position, phi itself), its angle and group into out[M_FAIL_PHI],
    out[M_FAIL_GROUP]; returns its status."""
    pos, d1, d2, margins, state, _ = wk
    found = ww[7]
    if k > 0:    # located between the last good position and this one
        st = loc(K, WATCH_G, phi_prev, phi, st, margins[N_GROUPS], ww[2][(k - 1) & 3], tols,
                    state, pos, d1, d2, margins, ww)
    else:
        found[1] = phi
        found[2] = margins[N_GROUPS]
    out[M_FAIL_PHI] = found[1]
    out[M_FAIL_GROUP] = found[2]
    return st


@njit(inline='always', **JIT)
def careful_step(K, k, phi_prev, phi, tols, out, wk, ww, adv, wat, loc):
    """Position ``k`` of a careful walk at ``phi``, from the last one at
    phi_prev: the step (``adv``: advance; a failure on it located, ``failed``
    with ``loc``), then the watch between the positions (``wat``).  Returns OK or the failure
    met (its angle and group in out[M_FAIL_PHI], out[M_FAIL_GROUP])."""
    pos, d1, d2, margins, state, _ = wk
    found = ww[7]
    st = adv(K, phi_prev, phi, np.int64(0), tols, state, pos, d1, d2, margins,
             np.bool_(False))
    if st != OK:
        return failed(K, k, phi_prev, phi, st, tols, out, wk, ww, loc)
    st = wat(K, WATCH_G, k, phi, tols, state, pos, d1, d2, margins, ww)
    if st != OK:
        out[M_FAIL_PHI] = found[1]
        out[M_FAIL_GROUP] = found[2]
    return st


# inline='always': one call site in the sweep; as its own function numba would
# build and link a library of everything it calls once more (compile time)
@njit(inline='always', **JIT)
def careful_positions(K, phis, phi_close, tols, theta, out, wk, ww, adv, wat, loc):
    """Stage 1 of the sweep for one candidate on the careful path: assembly
    over the revolution (triangle, Newton, branch, closure) and between its
    positions (the watch), the rocker angles ``theta`` from the first
    position, the singularity margin and the Newton iterations.  Returns
    (status, margin, iterations); a failure writes its crank angle (located
    between positions) and its group to out[M_FAIL_PHI], out[M_FAIL_GROUP].
    Always from the start, where the numbers are kept: a walk resumed midway
    decides its steps near a fold from another history (``careful_tail``, which
    only looks for a lane's failure, locates it the same to the location
    figures).  wk, ww: the walk's and the watch's work arrays (work,
    watch_work); adv, wat, loc: advance, the watch and locate (``settle_with``)."""
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
        st = adv(K, phi_prev, phi, np.int64(0), tols, state, pos, d1, d2, margins,
                 np.bool_(False))
        if st != OK:
            return failed(K, k, phi_prev, phi, st, tols, out, wk, ww, loc), margin, iters
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
        st = wat(K, WATCH_G, k, phi, tols, state, pos, d1, d2, margins, ww)
        if st != OK:
            out[M_FAIL_PHI] = found[1]
            out[M_FAIL_GROUP] = found[2]
            return st, margin, iters
    return OK, margin, iters


# its own function, compiled from the start in the process beside the run
# (pipeline.compiler.beside), which then loads it from numba's cache
@njit(**JIT_INNER)
def careful_tail(K, phis, k0, k1, trail, col, tols, out, wk, ww, called):
    """The careful walk of a lane that flagged itself, where the lane could not
    vouch: the first window, then positions ``k0`` .. k1 - 1 (3 < k0 < n, k1 <= n):
    from where the lane still vouched for its revolution to past the last
    position it flagged (``evaluate``: two positions before its first flag, two
    past its last).  The first window: the careful walk's positions 0 .. 3, which
    certify phis[0] .. phis[2] (the lanes certify the interval phis[0] ..
    phis[1] only round the close, at the end of their walk).  From k0: the class
    III groups start from the lane's solutions there (trail[k0]: e(a), e(b) per
    group) as a walk starts from its guesses, and positions k0 + 1 .. k1 - 1 are
    walked as careful_positions walks them, the watch between them included.
    Returns (status, spliced, the window's margin): the first failure met (its
    angle and group in out[M_FAIL_PHI], out[M_FAIL_GROUP]), or OK where it meets
    none or cannot start.  A failing lane so costs a few positions of the
    careful walk, not every position before its failure.

    A lane that meets no failure there is *spliced* (``spliced`` True) where
    the careful walk also passes position k1 < n (its watch then certifies the
    last window the lane had certified with a flagged position's margin) and
    finds there the lane's own solution (every class III group's e(a), e(b) and
    the rocker's angle within tols[T_CLOSE], the closing check's measure): the
    lane's numbers hold outside k0 .. k1, and inside the careful walk's replace
    them, walked once more to near rounding (``splice_window``): the rocker's
    angles in ``col`` (the lane's on entry) and the class III solutions in
    ``trail``; the window's margin is its positions' smallest.  Otherwise
    (False) the caller walks the whole revolution (careful_positions, which also
    checks that it closes).  It calls advance, the watch and locate through their
    addresses (``called``: ``callees()``), so its compile does not link their code."""
    adv = function_at(called[AT_ADVANCE], ADVANCE_FN)
    wat = function_at(called[AT_ADVANCE + 1], WATCH_FN)
    loc = function_at(called[AT_LOCATE], LOCATE_FN)
    pos, d1, d2, margins, state, _ = wk
    n = phis.shape[0]
    phi_prev = walk_start(K, phis[0], state)
    x0 = 0.0
    y0 = 0.0
    for k in range(4):     # the careful walk's own first steps: the same numbers
        st = careful_step(K, k, phi_prev, phis[k], tols, out, wk, ww, adv, wat, loc)
        if st != OK:
            return st, False, math.nan
        if k == 0:      # (the watch looks at nothing before position 3: pos is k's)
            x0 = pos[ROCKER_POINT, 0] - pos[ROCKER_PIVOT, 0]
            y0 = pos[ROCKER_POINT, 1] - pos[ROCKER_PIVOT, 1]
        phi_prev = phis[k]
    start_from_trail(state, trail, k0)
    # the lane's solutions at k0 confirmed by a solve there (a step of zero)
    if adv(K, phis[k0], phis[k0], np.int64(0), tols, state, pos, d1, d2, margins,
           np.bool_(False)) != OK:
        return OK, False, math.nan
    # (its history)
    wat(K, WATCH_G, np.int64(0), phis[k0], tols, state, pos, d1, d2, margins, ww)
    for k in range(k0 + 1, k1):
        st = careful_step(K, k - k0, phis[k - 1], phis[k], tols, out, wk, ww, adv, wat,
                          loc)
        if st != OK:
            return st, False, math.nan
    # one position past the window, where the lane vouches again: its watch certifies
    # the last window the lane certified with a flagged position's margin; where it
    # fails there (not reported: the whole walk decides) the lane is not spliced
    if k1 >= n or adv(K, phis[k1 - 1], phis[k1], np.int64(0), tols, state, pos, d1, d2,
                      margins, np.bool_(False)) != OK or wat(
            K, WATCH_G, k1 - k0, phis[k1], tols, state, pos, d1, d2, margins, ww) != OK:
        return OK, False, math.nan
    margin = splice_window(K, phis, k0, k1, x0, y0, trail, col, tols, wk, ww, adv)
    return OK, margin >= 0.0, margin


@njit(inline='always', **JIT)
def start_from_trail(state, trail, k):
    """The class III groups started from a lane's solutions at position ``k``
    (trail[k]: e(a), e(b) per group), as a walk starts from its guesses."""
    for j in range(N_TRIADS):
        start_triad(state, j, math.atan2(trail[k, 4 * j + 1], trail[k, 4 * j]),
                    math.atan2(trail[k, 4 * j + 3], trail[k, 4 * j + 2]))


@njit(inline='always', **JIT)
def splice_window(K, phis, k0, k1, x0, y0, trail, col, tols, wk, ww, adv):
    """The numbers of a spliced lane's window (``careful_tail``, which found no
    failure there): positions k0 .. k1 walked again from the lane's solutions
    at k0, each solved to near rounding (Newton's closure LOCATE_NEWTON_TOL, as
    a located boundary's: the walk's own tolerance leaves the solution of a
    short step within it, not at it), into col and trail (``window_row``).
    Returns the window's margin, or NaN where a step fails, k1 is not the lane's
    own solution or a step of the lane's rocker angle was beyond its series."""
    pos, d1, d2, margins, state, _ = wk
    ltols = near_rounding(tols, ww)
    for k in range(k0 + 1, k1 + 1):
        # the lane's rocker angles past the window are the sums of its increments, each
        # the atan series of a step's tan: exact where every step is within its range
        if not abs(col[k] - col[k - 1]) <= LANE_STEP_MAX:
            return math.nan
    start_from_trail(state, trail, k0)
    margin = math.inf
    for k in range(k0, k1 + 1):
        if adv(K, phis[max(k - 1, k0)], phis[k], np.int64(0), ltols, state, pos, d1, d2,
               margins, np.bool_(False)) != OK:
            return math.nan
        margin = window_row(k, k1, x0, y0, trail, col, tols, pos, state, margin)
        if not margin >= 0.0:
            return math.nan
    return margin


@njit(inline='always', **JIT)
def window_row(k, k1, x0, y0, trail, col, tols, pos, state, margin):
    """Position ``k`` of a spliced lane's careful window walked (``careful_tail``):
    its rocker angle into col[k] and its class III solutions into trail[k]; at
    k1, past the window, first checked to be the lane's own (within
    tols[T_CLOSE]: else NaN is returned).  Returns the window's margin so far."""
    th = relative_angle(x0, y0, pos[ROCKER_POINT, 0] - pos[ROCKER_PIVOT, 0],
                        pos[ROCKER_POINT, 1] - pos[ROCKER_PIVOT, 1])
    close = tols[T_CLOSE]
    if k == k1 and not abs(th - col[k]) <= close:
        return math.nan
    col[k] = th
    for j in range(N_TRIADS):
        ca = math.cos(state[j, S_A])
        sa = math.sin(state[j, S_A])
        cb = math.cos(state[j, S_B])
        sb = math.sin(state[j, S_B])
        if k == k1 and not (abs(ca * trail[k, 4 * j + 1] - sa * trail[k, 4 * j]) <= close
                            and abs(cb * trail[k, 4 * j + 3] - sb * trail[k, 4 * j + 2])
                            <= close and ca * trail[k, 4 * j] + sa * trail[k, 4 * j + 1] > 0.0
                            and cb * trail[k, 4 * j + 2] + sb * trail[k, 4 * j + 3] > 0.0):
            return math.nan
        trail[k, 4 * j] = ca
        trail[k, 4 * j + 1] = sa
        trail[k, 4 * j + 2] = cb
        trail[k, 4 * j + 3] = sb
        margin = min(margin, state[j, S_MARGIN])
    return margin


@njit(**JIT)   # the GPU kernel calls it (under numba's simulator: from Python)
def settle(par, vouched, phis, phi_close, tols, settings, loads, col, trail, qmax, qmin,
           err, start_k, full, margin, wk, fw, ww, corr, out):
    """Metrics of one candidate into ``out`` (N_METRICS); returns its status.
    Where ``vouched`` (> 0) the lane path's dwell (err, start_k, full),
    margin and class III solutions ``trail`` are taken (and its rocker
    angles in ``col`` where the law error is asked for); otherwise the
    careful path walks the revolution first.  Then stroke, dwell and margin
    metrics, the law error where asked, and the force stage where it
    applies.  col, trail, qmax, qmin, wk (work), fw (force_work), corr (n):
    work arrays of the caller, so nothing is allocated per candidate.
    ``vouched`` LANE_METRICS: a lane's, returning NEEDS_FORCES instead of
    running the force stage (the force lanes run it); LANE_FORCES: a lane's
    force stage alone, its other metrics already in ``out``.  CAREFUL_METRICS
    and CAREFUL_FORCES: the same two halves of the careful path (-1).
    It calls advance, the watch, locate and the force stage directly: the GPU's
    kernel compiles it (numba.cuda calls no function through an address); the
    CPU's sweep calls ``settle_cpu``, the same with those four through their
    addresses."""
    return settle_with(par, vouched, phis, phi_close, tols, settings, loads, col, trail, qmax,
                       qmin, err, start_k, full, margin, wk, fw, ww, corr, out, advance, watch,
                       locate, force_stage)


# the CPU's: its own function, called through its address (``callees``)
@njit(**JIT_INNER)
def settle_cpu(par, vouched, phis, phi_close, tols, settings, loads, col, trail, qmax, qmin,
               err, start_k, full, margin, wk, fw, ww, corr, out, called):
    """``settle``, its advance, watch, locate and force stage called through their
    addresses (``called``: ``callees()``): its compile links none of their code,
    which ``settle``'s had LLVM optimise and emit once more."""
    return settle_with(par, vouched, phis, phi_close, tols, settings, loads, col, trail, qmax,
                       qmin, err, start_k, full, margin, wk, fw, ww, corr, out,
                       function_at(called[AT_ADVANCE], ADVANCE_FN),
                       function_at(called[AT_ADVANCE + 1], WATCH_FN),
                       function_at(called[AT_LOCATE], LOCATE_FN),
                       function_at(called[AT_FORCE_STAGE], FORCE_STAGE_FN))


@njit(inline='always', **JIT)
def settle_with(par, vouched, phis, phi_close, tols, settings, loads, col, trail, qmax, qmin,
                err, start_k, full, margin, wk, fw, ww, corr, out, adv, wat, loc, fst):
    """``settle`` with ``adv``, ``wat``, ``loc`` and ``fst`` as its advance, watch,
    locate and force stage (the functions, or function values at their addresses)."""
    K = constants(par)
    if vouched != LANE_FORCES and vouched != CAREFUL_FORCES:
        st = lane_or_careful_metrics(K, vouched, phis, phi_close, tols, settings, col, qmax,
                                     qmin, err, start_k, full, margin, wk, ww, corr, out, adv,
                                     wat, loc)
        if st != NEEDS_FORCES or vouched == LANE_METRICS or vouched == CAREFUL_METRICS:
            return st
    st = OK
    for attempt in range(2):
        # with the lane path's solutions first; if a direct solve refuses, the
        # careful walk (one call site: numba inlines per call site)
        trail_ok = vouched > 0 and attempt == 0
        st = fst(par, K, phis, tols, settings, loads, out, trail, trail_ok, wk, fw)
        if st == OK or not trail_ok:
            break
    return st


@njit(inline='always', **JIT)
def lane_or_careful_metrics(K, vouched, phis, phi_close, tols, settings, col, qmax, qmin, err,
                            start_k, full, margin, wk, ww, corr, out, adv, wat, loc):
    """``settle``'s metrics before the force stage: its status, or NEEDS_FORCES
    where the force stage applies (the stroke and margin within the gates)."""
    no_metrics(out)
    n = phis.shape[0]
    iters = float(NEWTON_STEPS * N_TRIADS * n)
    if vouched <= 0:
        st, margin, iters = careful_positions(K, phis, phi_close, tols, col, out, wk, ww, adv,
                                              wat, loc)
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
    return NEEDS_FORCES


# its own function, compiled from the start in the process beside the run
# (pipeline.compiler.beside), which then loads it from numba's cache
@njit(**JIT_INNER)
def force_stage(par, K, phis, tols, settings, loads, out, trail, use_trail, wk, fw):
    """Stage 2 at every position of the grid, what the settings ask for:
    kinetostatics (SET_WANT_FORCES: the peak reaction, its joint and angle,
    the peak |balancing moment|, the worst relative virtual-power residual:
    kernels.forces.equilibrium_residual; the peak |shaking force| and |shaking
    moment| about the crank's pivot: kernels.forces.shaking), the working
    point's peak |a| and the output rocker's peak |eps| (SET_WANT_PEAKS), the
    smallest transmission angle (SET_WANT_TRANSMISSION); maxima (minima) over
    the grid's positions.  With ``use_trail`` every position is solved directly from
    the class III solution the lane path found there (trail[k] = e(a), e(b)
    per group, handed over as unit vectors: its closure residual confirms it,
    Newton runs only where that is above the tolerance, the branch check on
    det J still applies);
    otherwise by the careful continuation.  wk, fw: work arrays (work,
    force_work)."""
    omega1 = settings[SET_OMEGA1]
    eps1 = settings[SET_EPS1]
    want_f = settings[SET_WANT_FORCES] != 0.0
    want_p = settings[SET_WANT_PEAKS] != 0.0
    want_t = settings[SET_WANT_TRANSMISSION] != 0.0
    want_eq = settings[SET_WANT_EQUILIBRIUM] != 0.0
    want_sh = settings[SET_WANT_SHAKING] != 0.0
    order = 2 if (want_f or want_p) else 0
    iw = int(settings[SET_WORK_POINT])
    pos, d1, d2, margins, state, _ = wk
    phi_prev = walk_start(K, phis[0], state)
    peak = -1.0
    peak_j = -1
    peak_phi = math.nan
    peak_m = 0.0
    worst_eq = 0.0
    peak_sf = 0.0
    peak_sm = 0.0
    peak_a = 0.0
    peak_e = 0.0
    trans = math.inf
    trans_cos = math.nan
    trans_sin = math.nan
    for k in range(phis.shape[0]):
        st = solve_position(K, k, phi_prev, phis, order, tols, trail, use_trail, want_f, wk)
        phi_prev = phis[k]
        if st != OK:  # cannot happen after stage 1 unless the solver is not deterministic
            out[M_FAIL_PHI] = phis[k]
            return st
        if want_f:
            peak, peak_j, peak_phi, peak_m, worst_eq, peak_sf, peak_sm = force_peaks_at(
                par, phis[k], loads[k], omega1, eps1, want_eq, want_sh, wk, fw, peak, peak_j,
                peak_phi, peak_m, worst_eq, peak_sf, peak_sm)
        if want_p:
            peak_a, peak_e = motion_peaks_at(pos, d1, d2, iw, omega1, eps1, peak_a, peak_e)
        if want_t:
            # (angles certainly above the smallest so far need no atan2: the same minimum)
            t = transmission(K, pos, trans_cos, trans_sin)
            if t < trans or (not math.isfinite(t) and t != math.inf):
                trans = t
                trans_cos = math.cos(t)
                trans_sin = math.sin(t)
    if want_f:
        force_peaks_out(out, peak, peak_j, peak_phi, peak_m, want_eq, worst_eq, want_sh,
                        peak_sf, peak_sm)
    if want_p:
        out[M_PEAK_ACC] = peak_a / 1000.0        # m/s^2
        out[M_PEAK_EPS] = peak_e
    if want_t:
        out[M_MIN_TRANS] = trans if trans <= 0.5 * math.pi else math.nan
    out[M_FORCES_DONE] = 1.0
    return OK


@njit(inline='always', **JIT)
def solve_position(K, k, phi_prev, phis, order, tols, trail, use_trail, with_com, wk):
    """Every group at phis[k] to ``order`` (the centres of mass ``with_com``):
    directly from the lane path's class III solution there (``use_trail``), or
    by the careful continuation from phi_prev; returns its status."""
    pos, d1, d2, margins, state, _ = wk
    if use_trail:
        # a walk of length zero at phis[k], the lane's solution handed over as
        # unit vectors: the class III solve confirms it by its residual (Newton
        # from its angles only where that is above the tolerance)
        for j in range(N_TRIADS):
            state[j, S_HANDED] = 1.0
            state[j, S_CA] = trail[k, 4 * j]
            state[j, S_SA] = trail[k, 4 * j + 1]
            state[j, S_CB] = trail[k, 4 * j + 2]
            state[j, S_SB] = trail[k, 4 * j + 3]
        # (no continuation step to take: ``advance`` over a step of zero was
        # its predictor and bookkeeping around this one solve, a tenth of a
        # tolerance build's kernel time in perf, for nothing the solve reads:
        # the same bits)
        return position(K, phis[k], order, tols, state, pos, d1, d2, margins, with_com)
    return advance(K, phi_prev, phis[k], order, tols, state, pos, d1, d2, margins, with_com)


@njit(inline='always', **JIT)
def force_peaks_at(par, phi, loads_k, omega1, eps1, want_eq, want_sh, wk, fw, peak, peak_j,
                   peak_phi, peak_m, worst_eq, peak_sf, peak_sm):
    """Kinetostatics at one position (``forces_at``, at crank angle ``phi``) and
    the running peaks after it: |R| (with its joint and angle), |M_bal|, the
    virtual-power residual (``want_eq``), |shaking force| and |shaking moment|
    (``want_sh``); NaN and inf take them."""
    pos, d1, d2, margins, state, _ = wk
    work_a, work_b, loads_out, r_out, slide_out = fw
    mb = forces_at(par, pos, d1, d2, omega1, eps1, loads_k, work_a, work_b, loads_out, r_out,
                   slide_out)
    if abs(mb) > abs(peak_m) or not math.isfinite(mb):
        peak_m = mb
    if want_eq:
        eq = equilibrium_residual(pos, d1, d2, mb, loads_out, BODY_COM, BODY_TURN)
        if eq > worst_eq or not math.isfinite(eq):
            worst_eq = eq
    if want_sh:
        sfx, sfy, sm = shaking(pos, d1, d2, omega1, eps1, par, BODY_COM, BODY_TURN,
                               BODY_MASS_OFF, CRANK_PIVOT)
        if may_reach(sfx, sfy, peak_sf):
            sf = math.hypot(sfx, sfy)
            if sf > peak_sf or not math.isfinite(sf):
                peak_sf = sf
        if abs(sm) > peak_sm or not math.isfinite(sm):
            peak_sm = abs(sm)
    for j in range(N_JOINTS):
        peak, peak_j, peak_phi = reaction_peak(r_out[j, 0], r_out[j, 1], j, phi, peak, peak_j,
                                               peak_phi)
    return peak, peak_j, peak_phi, peak_m, worst_eq, peak_sf, peak_sm


@njit(inline='always', **JIT)
def motion_peaks_at(pos, d1, d2, iw, omega1, eps1, peak_a, peak_e):
    """The running peaks of the working point's |a| (mm/s^2) and of the output
    rocker's |angular acceleration| after this position; NaN and inf take them."""
    # |a| = |r'' omega1^2 + r' eps1| of the working point (mm/s^2)
    ax = d2[iw, 0] * omega1 ** 2 + d1[iw, 0] * eps1
    ay = d2[iw, 1] * omega1 ** 2 + d1[iw, 1] * eps1
    if may_reach(ax, ay, peak_a):
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
    return peak_a, peak_e


@njit(inline='always', **JIT)
def reaction_peak(rx, ry, j, phi, peak, peak_j, peak_phi):
    """The running maximum of |R| with the joint and the crank angle where it is
    (peak -1: none yet), after joint ``j``'s reaction (rx, ry) at ``phi``; NaN and
    inf take it (``may_reach``: the same peak to the bit without most hypots)."""
    if may_reach(rx, ry, peak):
        r = math.hypot(rx, ry)
        if r > peak or not math.isfinite(r):
            return r, j, phi
    return peak, peak_j, peak_phi


@njit(inline='always', **JIT)
def force_peaks_out(out, peak, peak_j, peak_phi, peak_m, want_eq, worst_eq, want_sh, peak_sf,
                    peak_sm):
    """The kinetostatics' peaks into a candidate's metrics row (NaN for those not
    asked for)."""
    out[M_PEAK_R] = peak
    out[M_PEAK_JOINT] = peak_j
    out[M_PEAK_PHI] = peak_phi
    out[M_PEAK_MBAL] = abs(peak_m)
    out[M_EQUILIBRIUM] = worst_eq if want_eq else math.nan
    out[M_SHAKING_F] = peak_sf if want_sh else math.nan
    out[M_SHAKING_M] = peak_sm if want_sh else math.nan

