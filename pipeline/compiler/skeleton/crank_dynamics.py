"""Crank dynamics of a generated module (``begin`` .. ``terms_curve``): the
motion of the crank under its driving moment, integrated along the mechanism's
exact reduced inertia.

The text below the marker line is pasted into the generated module
(``pipeline.compiler.generate``, after ``careful``); the imports above it
declare, for linters and readers, the names the generated module gives it."""


from .header import (math, np, njit, JIT, JIT_ALLOC, OK, SINGULAR, work, drive, lagrange_terms,
                     potential)
from ._mechanism import (N_POINTS, N_GROUPS, N_TRIADS, GRAVITY, BODY_COM, BODY_TURN, BODY_MASS_OFF,
                         LOAD_BODY, LOAD_POINT)
from .careful import advance_first_class
from ...kernels.walk import walk_start

# ---- the skeleton: from here on, pasted into the generated module ----
@njit(**JIT)
def begin(K, phi, state, last):
    """Start a dynamics continuation towards ``phi`` (last[0]: where the
    first evaluation walks from).  K: the constants as an array (constants_array:
    the scene's positions, compiled once for the walk and the dynamics)."""
    last[0] = walk_start(K, phi, state)


@njit(**JIT)
def acceleration(par, K, tols, const, tab_phi, h_phi, tab_t, h_t, damping, t, phi, omega,
                 state, last, pos, d1, d2, margins, loads_k):
    """eps1 = (Q + M1 - (1/2) J' omega^2 - b omega) / J at (t, phi, omega).
    Returns (status, eps1); walks the continuation from last[0] to phi."""
    st = advance_first_class(K, last[0], phi, np.int64(2), tols, state, pos, d1, d2, margins,
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
def rk4(par, K, tols, const, tab_phi, h_phi, tab_t, h_t, damping, phi0, omega0, dt, n_sub,
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
    begin(K, phi0, state, last)
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
        st, es = acceleration(par, K, tols, const, tab_phi, h_phi, tab_t, h_t, damping, ts, ps,
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
def terms_curve(par, K, tols, const, tab_phi, h_phi, tab_t, h_t, phis, ts, out_J, out_half,
                out_Q, out_M1, out_V, out_status):
    """J, (1/2) J', Q (without M1), M1 and V at the crank angles ``phis`` (and
    times ``ts`` for the drive channels), by continuation in the given order."""
    pos, d1, d2, margins, state, _ = work(N_POINTS, N_GROUPS, N_TRIADS)
    last = np.empty(1)
    loads_k = np.empty((LOAD_BODY.shape[0], 3))
    worst = OK
    if phis.shape[0] > 0:
        last[0] = walk_start(K, phis[0], state)
    for k in range(phis.shape[0]):
        st = advance_first_class(K, last[0], phis[k], np.int64(2), tols, state, pos, d1, d2,
                                 margins, np.bool_(True))
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
