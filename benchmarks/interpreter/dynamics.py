"""FROZEN COPY of the pre-compiler interpreter kernels (agreement check and
benchmarks only).

Crank dynamics (DOMAIN.md section 7): Lagrange II with one degree of freedom.

    J(phi) phi'' + (1/2) dJ/dphi phi'^2 + b phi' = Q(phi) + M1

with the reduced moment of inertia and its half-derivative from the exact
kinematic analogs of ``assembly.solve_position`` (order 2):

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

Class III groups keep their Newton continuation state: every evaluation
walks from the last solved crank angle (``last[0]``) with ``advance``, so
the integrator's small steps never jump branch.  Dyad-only plans are closed
form and the walk is a single solve.

Failures are data: a kinematic failure (or a non-finite acceleration)
stops the integration with its status; the unrecorded samples keep the NaN
the caller filled them with.
"""

import math

import numpy as np
from numba import njit

from .assembly import advance, has_newton, init_state, kinematic_work, start_angle
from pipeline.kernels.config import ACCELERATIONS, JIT_ALLOC as JIT, OK, SINGULAR
from pipeline.kernels.geometry import angle_analogs

MM = 1e-3


# drive channels, Lagrange terms and the potential: the product's own formulas
# (unchanged by the compiler), so only the interpreter's walk is frozen here
from pipeline.kernels.dynamics import drive, lagrange_terms, potential  # noqa: E402,F401


# ----------------------------------------------------------------- one evaluation
@njit(**JIT)
def begin(codes, goff, par, phi, state, last):
    """Start a continuation towards ``phi``: the class III groups from their
    declared guess at their start angle (last[0] = that angle, so the first
    evaluation walks from there to ``phi``); dyad-only plans start at ``phi``."""
    init_state(codes, goff, par, state)
    last[0] = start_angle(codes, goff, par) if has_newton(codes) else phi


@njit(**JIT)
def acceleration(codes, gidx, goff, par, fixed_idx, fixed_off, tols, newton,
                 gravity, body_com, body_turn, body_mass_off, load_body, load_point,
                 const, tab_phi, h_phi, tab_t, h_t, damping,
                 t, phi, omega, state, last, pos, d1, d2, margins, loads_k):
    """eps1 = (Q + M1 - (1/2) J' omega^2 - b omega) / J at (t, phi, omega).
    Returns (status, eps1); walks the continuation from last[0] to phi."""
    st = advance(codes, gidx, goff, par, fixed_idx, fixed_off, last[0], phi, ACCELERATIONS,
                 tols, state, newton, pos, d1, d2, margins)
    last[0] = phi
    if st != OK:
        return st, math.nan
    m1 = drive(const, tab_phi, h_phi, tab_t, h_t, phi, t, loads_k)
    J, half, Q = lagrange_terms(pos, d1, d2, gravity, par, body_com, body_turn, body_mass_off,
                                load_body, load_point, loads_k)
    eps = (Q + m1 - half * omega * omega - damping * omega) / J
    if not math.isfinite(eps):
        return SINGULAR, math.nan
    return OK, eps


# ----------------------------------------------------------------- integrator
@njit(**JIT)
def pos_count(gidx, fixed_idx):
    """Number of points of a plan: one more than the largest point index used."""
    n = 0
    for g in range(gidx.shape[0]):
        for k in range(gidx.shape[1]):
            if gidx[g, k] + 1 > n:
                n = gidx[g, k] + 1
    for k in range(fixed_idx.shape[0]):
        if fixed_idx[k] + 1 > n:
            n = fixed_idx[k] + 1
    return n


@njit(**JIT)
def rk4(codes, gidx, goff, par, fixed_idx, fixed_off, tols,
        gravity, body_com, body_turn, body_mass_off, load_body, load_point,
        const, tab_phi, h_phi, tab_t, h_t, damping,
        phi0, omega0, dt, n_sub, out_t, out_phi, out_omega, out_eps,
        tail_t, tail_phi, tail_omega, tail_eps):
    """Classical fixed-step RK4 for y = (phi1, omega1) from t = 0.

    Records (t, phi1, omega1, eps1) every ``n_sub`` steps into the out_*
    arrays (n_samples = out_t.shape[0]; the run has (n_samples - 1) n_sub
    steps) and at every one of the last tail_t.shape[0] steps into the tail_*
    arrays (the fine record for the steady-rotation statistics).  eps1 of a
    sample is the first stage of the following step (no extra evaluation).
    Returns (status, samples recorded).
    """
    pos, d1, d2, margins, state, _ = kinematic_work(pos_count(gidx, fixed_idx),
                                                    codes.shape[0])
    last = np.empty(1)
    loads_k = np.empty((load_body.shape[0], 3))
    newton = has_newton(codes)
    n_samples = out_t.shape[0]
    n_steps = (n_samples - 1) * n_sub
    n_tail = tail_t.shape[0]
    tail0 = n_steps - n_tail + 1
    begin(codes, goff, par, phi0, state, last)
    p = phi0
    w = omega0
    h = dt
    e = 0.0
    st = OK
    recorded = 0
    # One call site of ``acceleration`` (numba inlines callees per call site, so
    # this keeps the compile time down): evaluation s = 0 is the start, s = 1..3
    # are RK4 stages 2..4, s = 4 is the new state (= stage 1 of the next step).
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
        st, es = acceleration(codes, gidx, goff, par, fixed_idx, fixed_off, tols, newton,
                              gravity, body_com, body_turn, body_mass_off, load_body,
                              load_point, const, tab_phi, h_phi, tab_t, h_t, damping,
                              ts, ps, ws, state, last, pos, d1, d2, margins, loads_k)
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
        # at a step point: record, then start the next step with stage 1
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


# ----------------------------------------------------------------- curves (tests, energy)
@njit(**JIT)
def terms_curve(codes, gidx, goff, par, fixed_idx, fixed_off, tols,
                gravity, body_com, body_turn, body_mass_off, load_body, load_point,
                const, tab_phi, h_phi, tab_t, h_t, phis, ts,
                out_J, out_half, out_Q, out_M1, out_V, out_status):
    """J, (1/2) J', Q (without M1), M1 and V at the crank angles ``phis`` (and
    times ``ts`` for the drive channels), by continuation in the given order."""
    pos, d1, d2, margins, state, _ = kinematic_work(pos_count(gidx, fixed_idx),
                                                    codes.shape[0])
    last = np.empty(1)
    loads_k = np.empty((load_body.shape[0], 3))
    newton = has_newton(codes)
    worst = OK
    if phis.shape[0] > 0:
        begin(codes, goff, par, phis[0], state, last)
    for k in range(phis.shape[0]):
        st = advance(codes, gidx, goff, par, fixed_idx, fixed_off, last[0], phis[k],
                     ACCELERATIONS, tols, state, newton, pos, d1, d2, margins)
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
