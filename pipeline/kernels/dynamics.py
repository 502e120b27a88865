"""Crank dynamics (DOMAIN.md section 7): Lagrange II with one degree of freedom.

    J(phi) phi'' + (1/2) dJ/dphi phi'^2 + b phi' = Q(phi) + M1

with the reduced moment of inertia and its half-derivative from the exact
kinematic analogs of the mechanism's generated ``position`` (order 2):

    J        = sum_i J_Si phi_i'^2 + m_i |S_i'|^2
    (1/2) J' = sum_i J_Si phi_i' phi_i'' + m_i S_i' . S_i''
    Q        = sum_i G_i . S_i' + sum_j (F_j . P_j' + M_j phi_body(j)')

(' = d/dphi1; S' in metres per radian = mm analogs / 1000; phi_i' and phi_i''
of a body are those of the link it turns with, 0 for a translating body).

External loads and the driving moment are "drive channels" sampled outside
the kernels: channel 0 is M1, channel 1 + 3k + (0, 1, 2) is (fx, fy, moment)
of load k.  Each channel is

    const[c] + periodic cubic spline in phi (period 2 pi) + cubic spline in t

(the Python layer puts a constant, a phi-only or a t-only expression in the
matching part and rejects the rest).  A table with zero intervals is absent.
Spline tables are (n_channels, n_intervals, 4) with the coefficients of the
local cubic in descending powers of (x - x_i), as scipy's ``CubicSpline.c``.

The integrator (RK4 over the mechanism's exact kinematics: ``rk4``, with
``acceleration``, ``begin`` and ``terms_curve``) is compiled once for every
mechanism: it calls the mechanism's continuation (its generated ``advance``,
pipeline.compiler) through its address.  Class III groups keep their
continuation state there, so the integrator's small steps never jump branch,
and a kinematic failure (or a non-finite acceleration) stops the integration
with its status.
"""

import math

import numpy as np
from numba import njit, types

from .config import JIT, JIT_ALLOC, OK, SINGULAR, compile_for
from .continuation import work
from .geometry import angle_analogs
from .walk import ADVANCE, START, walk_start

MM = 1e-3

# the integrator's own outcome (a status of a dynamics case only, never of a position:
# beyond kernels.config's kinematic statuses, and in no sweep's status column)
TOO_FAST = 16       # |omega1| passed omega_limit (the study's limit on a crank speed)
OMEGA_STOP = 10.0   # rk4 stops at once where |omega1| exceeds this many times omega_limit


# ----------------------------------------------------------------- drive channels
@njit(**JIT)
def spline_value(tab, h, periodic, c, x):
    """Channel c of a cubic spline table at x (nodes 0, h, 2h, ...).  Periodic
    tables wrap x into [0, n h); the others extrapolate the end cubics."""
    n = tab.shape[1]
    if periodic:
        x = x - n * h * math.floor(x / (n * h))
    i = int(math.floor(x / h))
    if i < 0:
        i = 0
    elif i > n - 1:
        i = n - 1
    u = x - i * h
    return ((tab[c, i, 0] * u + tab[c, i, 1]) * u + tab[c, i, 2]) * u + tab[c, i, 3]


@njit(**JIT)
def channel(const, tab_phi, h_phi, tab_t, h_t, c, phi, t):
    v = const[c]
    if tab_phi.shape[1] > 0:
        v += spline_value(tab_phi, h_phi, True, c, phi)
    if tab_t.shape[1] > 0:
        v += spline_value(tab_t, h_t, False, c, t)
    return v


@njit(**JIT)
def drive(const, tab_phi, h_phi, tab_t, h_t, phi, t, loads_k):
    """Fill loads_k (n_loads, 3) at (phi, t); return the driving moment M1."""
    for k in range(loads_k.shape[0]):
        for j in range(3):
            loads_k[k, j] = channel(const, tab_phi, h_phi, tab_t, h_t, 1 + 3 * k + j, phi, t)
    # np.int64: not the literal 0 (one compiled channel for every call)
    return channel(const, tab_phi, h_phi, tab_t, h_t, np.int64(0), phi, t)


# ----------------------------------------------------------------- Lagrange terms
@njit(**JIT)
def lagrange_terms(pos, d1, d2, gravity, par, body_com, body_turn, body_mass_off,
                   load_body, load_point, loads_k):
    """(J [kg m^2], (1/2) dJ/dphi [kg m^2], Q without M1 [N m]) at one position
    from its exact analogs (pos/d1/d2 in mm, mm/rad, mm/rad^2)."""
    J = 0.0
    half = 0.0
    Q = 0.0
    nb = body_com.shape[0]
    for i in range(nb):
        s = body_com[i]
        m = par[body_mass_off[i]]
        js = par[body_mass_off[i] + 1]
        s1x = d1[s, 0] * MM
        s1y = d1[s, 1] * MM
        s2x = d2[s, 0] * MM
        s2y = d2[s, 1] * MM
        J += m * (s1x * s1x + s1y * s1y)
        half += m * (s1x * s2x + s1y * s2y)
        Q -= m * gravity * s1y
        a = body_turn[i, 0]
        if a >= 0 and js != 0.0:
            b = body_turn[i, 1]
            _, w1, w2 = angle_analogs(pos[b, 0] - pos[a, 0], pos[b, 1] - pos[a, 1],
                                      d1[b, 0] - d1[a, 0], d1[b, 1] - d1[a, 1],
                                      d2[b, 0] - d2[a, 0], d2[b, 1] - d2[a, 1])
            J += js * w1 * w1
            half += js * w1 * w2
    for k in range(load_body.shape[0]):
        p = load_point[k]
        if p >= 0:
            Q += (loads_k[k, 0] * d1[p, 0] + loads_k[k, 1] * d1[p, 1]) * MM
        mom = loads_k[k, 2]
        i = load_body[k]
        a = body_turn[i, 0]
        if mom != 0.0 and a >= 0:
            b = body_turn[i, 1]
            _, w1, _w2 = angle_analogs(pos[b, 0] - pos[a, 0], pos[b, 1] - pos[a, 1],
                                       d1[b, 0] - d1[a, 0], d1[b, 1] - d1[a, 1],
                                       d2[b, 0] - d2[a, 0], d2[b, 1] - d2[a, 1])
            Q += mom * w1
    return J, half, Q


@njit(**JIT)
def potential(pos, gravity, par, body_com, body_mass_off):
    """Gravitational potential energy sum m g y_S [J] (y in mm -> m)."""
    v = 0.0
    for i in range(body_com.shape[0]):
        v += par[body_mass_off[i]] * gravity * pos[body_com[i], 1] * MM
    return v


# ----------------------------------------------------------------- the integrator
# Compiled once per installation, for every mechanism: the mechanism's
# continuation comes as first-class functions (``advance``, ``start``: the
# generated module's advance_first_class and start_first_class, called through
# their address), its constants as an array ``K`` (constants_array), its sizes
# and its mass model and loads as arguments: ``sizes`` = (n_points, n_groups,
# n_triads), ``masses`` = (gravity, body_com, body_turn, body_mass_off,
# load_body, load_point).  The generated module's begin, acceleration, rk4 and
# terms_curve pass them (pipeline.compiler.skeleton.crank_dynamics).

@njit(**JIT)
def begin(start, K, phi, state, last):
    """Start a dynamics continuation towards ``phi`` (last[0]: where the
    first evaluation walks from)."""
    last[0] = walk_start(start, K, phi, state)


@njit(**JIT)
def acceleration(advance, K, masses, par, tols, const, tab_phi, h_phi, tab_t, h_t, damping, t,
                 phi, omega, state, last, pos, d1, d2, margins, loads_k):
    """eps1 = (Q + M1 - (1/2) J' omega^2 - b omega) / J at (t, phi, omega).
    Returns (status, eps1); walks the continuation from last[0] to phi."""
    st = advance(K, last[0], phi, np.int64(2), tols, state, pos, d1, d2, margins, True)
    last[0] = phi
    if st != OK:
        return st, math.nan
    gravity, body_com, body_turn, body_mass_off, load_body, load_point = masses
    return eps_at(gravity, body_com, body_turn, body_mass_off, load_body, load_point, par, const,
                  tab_phi, h_phi, tab_t, h_t, damping, t, phi, omega, pos, d1, d2, loads_k)


@njit(**JIT)
def eps_at(gravity, body_com, body_turn, body_mass_off, load_body, load_point, par, const,
           tab_phi, h_phi, tab_t, h_t, damping, t, phi, omega, pos, d1, d2, loads_k):
    """(status, eps1) from the mechanism's analogs at crank angle ``phi``
    (pos/d1/d2 of order 2): the drive at (phi, t), the Lagrange terms, and
    eps1 = (Q + M1 - (1/2) J' omega^2 - b omega) / J (SINGULAR where it is not
    finite)."""
    m1 = drive(const, tab_phi, h_phi, tab_t, h_t, phi, t, loads_k)
    J, half, Q = lagrange_terms(pos, d1, d2, gravity, par, body_com, body_turn, body_mass_off,
                                load_body, load_point, loads_k)
    eps = (Q + m1 - half * omega * omega - damping * omega) / J
    if not math.isfinite(eps):
        return SINGULAR, math.nan
    return OK, eps


@njit(inline='always', **JIT)
def step_counts(out_t, tail_t, n_sub):
    """(the RK4 steps of a run, the first step the fine tail records) for
    samples ``out_t`` every ``n_sub`` steps and a tail of ``tail_t``'s length."""
    n_steps = (out_t.shape[0] - 1) * n_sub
    return n_steps, n_steps - tail_t.shape[0] + 1


@njit(inline='always', **JIT)
def record(n, n_sub, tail0, h, p, w, e, out_t, out_phi, out_omega, out_eps, tail_t, tail_phi,
           tail_omega, tail_eps):
    """The state (phi1, omega1, eps1) after step n (t = n h) into the samples
    (every n_sub steps) and the fine tail (from step tail0 on); whether it was
    a sample."""
    sample = n % n_sub == 0
    if sample:
        k = n // n_sub
        out_t[k] = n * h
        out_phi[k] = p
        out_omega[k] = w
        out_eps[k] = e
    if n >= tail0:
        j = n - tail0
        tail_t[j] = n * h
        tail_phi[j] = p
        tail_omega[j] = w
        tail_eps[j] = e
    return sample


@njit(**JIT_ALLOC)
def rk4(advance, start, K, sizes, masses, par, tols, const, tab_phi, h_phi, tab_t, h_t, damping,
        phi0, omega0, dt, n_sub, omega_limit, out_t, out_phi, out_omega, out_eps, tail_t,
        tail_phi, tail_omega, tail_eps):
    """Classical fixed-step RK4 for y = (phi1, omega1) from t = 0.

    Records (t, phi1, omega1, eps1) every ``n_sub`` steps into the out_*
    arrays (n_samples = out_t.shape[0]; the run has (n_samples - 1) n_sub
    steps) and at every one of the last tail_t.shape[0] steps into the tail_*
    arrays.  eps1 of a sample is the first stage of the following step.
    The first step that ends with |omega1| > omega_limit (the crossing) ends
    the run with TOO_FAST at the next sample, recorded (the state past the
    crossing that a second run checks), or at once where |omega1| (of the
    state or of a stage) exceeds OMEGA_STOP omega_limit or is not finite
    before it.  Returns (status, the crossing's step or -1)."""
    n_points, n_groups, n_triads = sizes
    pos, d1, d2, margins, state, _ = work(n_points, n_groups, n_triads)
    last = np.empty(1)
    loads_k = np.empty((masses[4].shape[0], 3))       # (load_body: the loads)
    n_steps, tail0 = step_counts(out_t, tail_t, n_sub)
    begin(start, K, phi0, state, last)
    p = phi0
    w = omega0
    h = dt
    e = 0.0
    st = OK
    crossing = -1
    # one call site of ``acceleration``: evaluation s = 0 is the start, s = 1..3
    # are RK4 stages 2..4, s = 4 is the new state (= stage 1 of the next step)
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
            if not abs(ws) <= OMEGA_STOP * omega_limit:     # a stage runs away: so does
                st = TOO_FAST                                # the step
                if crossing < 0:
                    crossing = n + 1
                break
        else:
            p = p + h / 6.0 * sum_p
            w = w + h / 6.0 * sum_w
            n += 1
            if not abs(w) <= OMEGA_STOP * omega_limit:
                st = TOO_FAST
                if crossing < 0:
                    crossing = n
                break
            if crossing < 0 and abs(w) > omega_limit:
                crossing = n
            ts, ps, ws = n * h, p, w
        st, es = acceleration(advance, K, masses, par, tols, const, tab_phi, h_phi, tab_t, h_t,
                              damping, ts, ps, ws, state, last, pos, d1, d2, margins, loads_k)
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
        if record(n, n_sub, tail0, h, p, w, e, out_t, out_phi, out_omega, out_eps, tail_t,
                  tail_phi, tail_omega, tail_eps) and crossing >= 0:
            st = TOO_FAST
        if n == n_steps or st == TOO_FAST:
            break
        kp = w
        kw = e
        sum_p = w
        sum_w = e
        s = 1
    return st, crossing


@njit(**JIT_ALLOC)
def terms_curve(advance, start, K, sizes, masses, par, tols, const, tab_phi, h_phi, tab_t, h_t,
                phis, ts, out_J, out_half, out_Q, out_M1, out_V, out_status):
    """J, (1/2) J', Q (without M1), M1 and V at the crank angles ``phis`` (and
    times ``ts`` for the drive channels), by continuation in the given order."""
    gravity, body_com, body_turn, body_mass_off, load_body, load_point = masses
    n_points, n_groups, n_triads = sizes
    pos, d1, d2, margins, state, _ = work(n_points, n_groups, n_triads)
    last = np.empty(1)
    loads_k = np.empty((load_body.shape[0], 3))
    worst = OK
    if phis.shape[0] > 0:
        last[0] = walk_start(start, K, phis[0], state)
    for k in range(phis.shape[0]):
        st = advance(K, last[0], phis[k], np.int64(2), tols, state, pos, d1, d2, margins, True)
        last[0] = phis[k]
        out_status[k] = st
        if worst == OK and st != OK:
            worst = st
        m1 = drive(const, tab_phi, h_phi, tab_t, h_t, phis[k], ts[k], loads_k)
        J, half, Q = lagrange_terms(pos, d1, d2, gravity, par, body_com, body_turn,
                                    body_mass_off, load_body, load_point, loads_k)
        out_J[k] = J
        out_half[k] = half
        out_Q[k] = Q
        out_M1[k] = m1
        out_V[k] = potential(pos, gravity, par, body_com, body_mass_off)
    return worst


# their types, for which they are compiled once (compile_integrator)
_F1, _F2 = types.float64[::1], types.float64[:, ::1]
_I1, _I2 = types.int64[::1], types.int64[:, ::1]
SIZES = types.UniTuple(types.int64, 3)
MASSES = types.Tuple((types.float64, _I1, _I2, _I1, _I1, _I1))
_TAB = types.float64[:, :, ::1]
_DRIVE = (_F1, _TAB, types.float64, _TAB, types.float64)     # Drive.args()
SIGNATURES = {
    begin: types.void(START, _F1, types.float64, _F2, _F1),
    acceleration: types.Tuple((types.int64, types.float64))(
        ADVANCE, _F1, MASSES, _F1, _F1, *_DRIVE, types.float64, types.float64, types.float64,
        types.float64, _F2, _F1, _F2, _F2, _F2, _F1, _F2),
    rk4: types.Tuple((types.int64, types.int64))(
        ADVANCE, START, _F1, SIZES, MASSES, _F1, _F1, *_DRIVE, types.float64, types.float64,
        types.float64, types.float64, types.int64, types.float64, *[_F1] * 8),
    terms_curve: types.int64(ADVANCE, START, _F1, SIZES, MASSES, _F1, _F1, *_DRIVE, _F1, _F1,
                             *[_F1] * 5, types.int8[::1]),
}


@njit(**JIT)
def energy_orbit(J, drive, h, b, K):
    """The crank's kinetic energy K at the nodes of one revolution from K[0]
    (the flywheel's orbit, ``pipeline.solve.flywheel``): RK4 in the crank angle
    of dK/dphi = drive - b |omega|, |omega| = sqrt(2 K / J), with J and the drive
    at the nodes and half steps (2n + 1 samples for K's n + 1).  False where
    the crank stops (K not > 0): K is then written up to there."""
    k = K[0]
    for j in range(K.shape[0] - 1):
        i = 2 * j
        k1 = drive[i] - b * math.sqrt(_not_below_zero(2.0 * k / J[i]))
        k2 = drive[i + 1] - b * math.sqrt(_not_below_zero(2.0 * (k + 0.5 * h * k1) / J[i + 1]))
        k3 = drive[i + 1] - b * math.sqrt(_not_below_zero(2.0 * (k + 0.5 * h * k2) / J[i + 1]))
        k4 = drive[i + 2] - b * math.sqrt(_not_below_zero(2.0 * (k + h * k3) / J[i + 2]))
        k = k + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        if not k > 0.0:
            return False            # the crank stops: no rotation from this K[0]
        K[j + 1] = k
    return True


@njit(inline="always", **JIT)
def _not_below_zero(x):
    """Python's max(x, 0.0): x unless 0.0 is greater (NaN and -0.0 kept)."""
    return 0.0 if 0.0 > x else x


def compile_integrator() -> None:
    """begin, acceleration, rk4 and terms_curve compiled (or loaded from
    numba's cache) for their SIGNATURES and no other: once per installation,
    not per mechanism (``pipeline.compiler.beside`` does it while the first
    sweep compiles).  Cheap once done (DOP853 calls acceleration from Python
    at every step)."""
    if _COMPILED:
        return
    for kernel, sig in SIGNATURES.items():
        compile_for(kernel, sig)
    _COMPILED.append(True)


_COMPILED: list = []       # (not empty once compile_integrator has run)
