"""The careful path of a generated module: the walks, the scene's revolution and
forces (the sweep's careful stages are in ``sweep_stages``).

The text below the marker line is pasted into the generated module
(``pipeline.compiler.generate``, after ``watch``); the imports above it declare,
for linters and readers, the names the generated module gives it."""


from .header import (math, np, njit, JIT_ALLOC, JIT_INNER, OK, BRANCH_JUMP, S_ITERS, N_STATE,
                     closes, copy2, work, force_work)
from ._mechanism import (N_POINTS, N_GROUPS, N_TRIADS, N_WATCH, N_BODIES, N_JOINTS, N_SLIDES,
                         N_INPUTS, constants, start, advance, forces_at)
from .watch import (locate, watch, watch_work)

# ---- the skeleton: from here on, pasted into the generated module ----
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
