"""Crank dynamics with friction in the joints ([mechanism.friction]).

The crank's equation is that of the kinetostatics: the driving moment balances
the moment the motion asks, M1 - b omega = M_bal(phi, omega, eps), M_bal with
friction (``kernels.friction.friction_forces``; without friction M_bal =
J eps + (1/2) J' omega^2 - Q, ``kernels.dynamics``'s equation).  M_bal's
friction part depends on eps through the reactions, so eps1 solves that
equation at every evaluation, by the secant method from the frictionless eps1
(``friction_eps``): implicit, not lagged.

The friction loads turn with the relative motions: the "regime" (per joint
and slide, the sign of its relative speed analog times omega1; per slide, the
branch of its normal force's magnitude, ``kernels.friction.slide_branch``)
changes where a relative speed passes zero (a rocker's reversal, a slider's
dead centre) or omega1 does, and the right-hand side jumps there; where a
slide's normal force changes its sign, or its block starts or stops bearing
on its edges, the right-hand side has a kink.  RK4 keeps its order
only between such switches, so every step is integrated in the regime of its
start (``rk4_in_regime``: the stages forced to it) and checked at its end: a
step whose end is in another regime is cut where the regime changes, located
by bisection on the piece's length to dt / 2^SWITCH_STEPS in time (the piece
just past the switch taken in its start's regime: an error of the jump times
that length squared); the step then goes on, in the new regime, to its end.
Two switches within one step that undo each other are not seen.

A position where the friction locks, or the secant does not converge, ends
the run with FRICTION_LOCK.  Compiled once per installation (its types:
``SIGNATURE``), as ``kernels.dynamics``'s integrator.
"""

import math

import numpy as np
from numba import njit, types

from .calls import unliteral
from .config import FRICTION_LOCK, JIT, JIT_ALLOC, OK, SINGULAR, compile_for
from .continuation import work
from .dynamics import (_DRIVE, _F1, _I1, _I2, MASSES, OMEGA_STOP, SIZES, TOO_FAST, acceleration,
                       begin, channel, lagrange_terms, record, step_counts)
from .walk import ADVANCE, START
from .friction import friction_forces, relative_speed_slopes

FRICTION_REL = 1e-12     # the friction's Newton (kernels.friction), relative
FRICTION_MAX_ITER = 50
EPS_REL = 1e-12          # the secant on eps1: |M_bal - (M1 - b omega)| within this of its terms
EPS_MAX_ITER = 60
SWITCH_STEPS = 30        # halvings of a step that changes regime: dt / 2^30 in time
MAX_PIECES = 64          # pieces of one step (each ends at a switch) before it counts as stuck


@njit(**JIT)
def _m_bal(eps, omega, pos, d1, d2, gravity, par, body_com, body_turn, body_mass_off,
           load_body, load_point, loads_k, friction, fw, keep):
    """(status, M_bal with friction [N*m]) at (omega, eps); ``keep``: in the
    regime fw[5] holds, else in the motion's own (written there)."""
    (_, f_rev, f_slide, radius, block, joint_point, joint_bodies, slide_bodies, slide_dir,
     slide_angle, crank_body) = friction
    a0, jac, b0, res, x, sense, loads_out, r_out, slide_out, fric, speed, found = fw
    friction_forces(pos, d1, d2, omega, eps, gravity, par, body_com, body_turn, body_mass_off,
                    joint_point, joint_bodies, slide_bodies, slide_dir, slide_angle, crank_body,
                    load_body, load_point, loads_k, f_rev, radius, f_slide, block, FRICTION_REL,
                    unliteral(FRICTION_MAX_ITER), a0, b0, jac, res, x, sense, loads_out, r_out,
                    slide_out, fric, speed, found, keep)
    if found[0] != OK:
        return FRICTION_LOCK, math.nan
    if not math.isfinite(found[1]):
        return SINGULAR, math.nan
    return OK, found[1]


@njit(**JIT)
def friction_eps(eps0, t, phi, omega, damping, const, tab_phi, h_phi, tab_t, h_t, pos, d1, d2,
                 gravity, par, body_com, body_turn, body_mass_off, load_body, load_point,
                 loads_k, friction, fw, keep):
    """(status, eps1) with friction at (t, phi, omega) from the frictionless
    ``eps0`` (pos/d1/d2 and loads_k there): the root of g(eps) = M_bal(phi,
    omega, eps) - (M1 - b omega) by the secant method (its slope is J where
    the friction is nil), converged where |g| is within EPS_REL of the sum of
    its terms' magnitudes."""
    m1 = channel(const, tab_phi, h_phi, tab_t, h_t, np.int64(0), phi, t)
    J, half, Q = lagrange_terms(pos, d1, d2, gravity, par, body_com, body_turn, body_mass_off,
                                load_body, load_point, loads_k)
    target = m1 - damping * omega
    scale = abs(m1) + abs(damping * omega) + abs(half * omega * omega) + abs(Q)
    e0 = eps0
    st, m = _m_bal(e0, omega, pos, d1, d2, gravity, par, body_com, body_turn, body_mass_off,
                   load_body, load_point, loads_k, friction, fw, keep)
    if st != OK:
        return st, math.nan
    g0 = m - target
    if abs(g0) <= EPS_REL * (scale + abs(m) + abs(J * e0)):
        return OK, e0
    e1 = e0 - g0 / J
    for _ in range(EPS_MAX_ITER):
        st, m = _m_bal(e1, omega, pos, d1, d2, gravity, par, body_com, body_turn,
                       body_mass_off, load_body, load_point, loads_k, friction, fw, keep)
        if st != OK:
            return st, math.nan
        g1 = m - target
        if abs(g1) <= EPS_REL * (scale + abs(m) + abs(J * e1)):
            return OK, e1
        slope = (g1 - g0) / (e1 - e0) if e1 != e0 else J
        if not (slope != 0.0 and math.isfinite(slope)):
            slope = J
        e0, g0 = e1, g1
        e1 = e1 - g1 / slope
        if not math.isfinite(e1):
            break
    return FRICTION_LOCK, math.nan


@njit(**JIT)
def _eval(advance, K, masses, par, tols, const, tab_phi, h_phi, tab_t, h_t, damping, t, phi,
          omega, state, last, pos, d1, d2, margins, loads_k, friction, fw, regime, keep, speed):
    """(status, eps1) at (t, phi, omega): in ``regime`` (``keep``), or in the
    motion's own, then written to ``regime`` with the relative speed analogs
    and their slopes (``speed``: (2, joints + slides))."""
    st, e0 = acceleration(advance, K, masses, par, tols, const, tab_phi, h_phi, tab_t, h_t,
                          damping, t, phi, omega, state, last, pos, d1, d2, margins, loads_k)
    if st != OK:
        return st, math.nan
    sense = fw[5]
    if keep:
        for e in range(sense.shape[0]):
            sense[e] = regime[e]
    gravity, body_com, body_turn, body_mass_off, load_body, load_point = masses
    st, e = friction_eps(e0, t, phi, omega, damping, const, tab_phi, h_phi, tab_t, h_t, pos, d1,
                         d2, gravity, par, body_com, body_turn, body_mass_off, load_body,
                         load_point, loads_k, friction, fw, keep)
    if not keep:
        for k in range(sense.shape[0]):
            regime[k] = sense[k]
        for k in range(fw[10].shape[0]):
            speed[0, k] = fw[10][k]
        relative_speed_slopes(pos, d1, d2, body_com, body_turn, friction[6], friction[7],
                              friction[8], friction[9], speed[1])
    return st, e


@njit(**JIT)
def rk4_in_regime(advance, K, masses, par, tols, const, tab_phi, h_phi, tab_t, h_t, damping,
                  t, p, w, e, h, state, last, pos, d1, d2, margins, loads_k, friction, fw,
                  regime, out):
    """One RK4 step of length h from (t, p, w), every stage in ``regime``, the
    first one eps1 = e (the start's, in that regime: the evaluation that ended
    the piece before): out[0:2] = (phi1, omega1) at its end.  Returns its
    status."""
    sp = w
    sw = e
    kp = w
    kw = e
    for s in range(1, 4):
        c = 0.5 if s < 3 else 1.0
        ts, ps, ws = t + c * h, p + c * h * kp, w + c * h * kw
        if not math.isfinite(ws):
            return SINGULAR
        st, es = _eval(advance, K, masses, par, tols, const, tab_phi, h_phi, tab_t, h_t,
                       damping, ts, ps, ws, state, last, pos, d1, d2, margins, loads_k,
                       friction, fw, regime, unliteral(True), fw[0])
        if st != OK:
            return st
        weight = 2.0 if s < 3 else 1.0
        sp += weight * ws
        sw += weight * es
        kp = ws
        kw = es
    out[0] = p + h / 6.0 * sp
    out[1] = w + h / 6.0 * sw
    return OK


@njit(**JIT)
def _trial(advance, K, masses, par, tols, const, tab_phi, h_phi, tab_t, h_t, damping, t, p, w,
           e, h, omega_limit, state, last, pos, d1, d2, margins, loads_k, friction, fw, regime,
           after, end, speed0, speed1):
    """A piece of length h from (t, p, w) (eps1 there e) in ``regime`` (``rk4_in_regime``),
    then the motion's own regime at its end (``after``, its speeds and slopes
    ``speed1``; ``speed0``: at its start): (status, eps1 at its end, whether
    it stays in its regime: the same at its end, and no relative speed that
    changes sign twice within it, ``_dips``)."""
    st = rk4_in_regime(advance, K, masses, par, tols, const, tab_phi, h_phi, tab_t, h_t,
                       damping, t, p, w, e, h, state, last, pos, d1, d2, margins, loads_k,
                       friction, fw, regime, end)
    if st != OK:
        return st, math.nan, False
    if not abs(end[1]) <= OMEGA_STOP * omega_limit:
        return TOO_FAST, math.nan, False
    st, e = _eval(advance, K, masses, par, tols, const, tab_phi, h_phi, tab_t, h_t, damping,
                  t + h, end[0], end[1], state, last, pos, d1, d2, margins, loads_k, friction,
                  fw, after, unliteral(False), speed1)
    return st, e, st == OK and _same(after, regime) and not _dips(speed0, speed1,
                                                                   end[0] - p)


@njit(**JIT)
def _dips(speed0, speed1, dphi):
    """Whether a relative speed analog of the same sign at both ends of a piece
    (``speed``: values and slopes by the crank angle) changes sign twice within
    it, as the cubic through its ends' values and slopes does (a rocker that
    nearly stops and goes on: two switches no end sees)."""
    for e in range(speed0.shape[1]):
        v0 = speed0[0, e]
        v1 = speed1[0, e]
        if not (v0 * v1 > 0.0):
            continue
        m0 = speed0[1, e] * dphi
        m1 = speed1[1, e] * dphi
        # H(t) = (2t^3 - 3t^2 + 1) v0 + (t^3 - 2t^2 + t) m0 + (3t^2 - 2t^3) v1 + (t^3 - t^2) m1
        a = 6.0 * v0 + 3.0 * m0 - 6.0 * v1 + 3.0 * m1      # H'(t) = a t^2 + b t + c
        b = -6.0 * v0 - 4.0 * m0 + 6.0 * v1 - 2.0 * m1
        c = m0
        for r in _roots(a, b, c):
            if 0.0 < r < 1.0:
                h = ((2 * r - 3) * r * r + 1) * v0 + ((r - 2) * r + 1) * r * m0 \
                    + (3 - 2 * r) * r * r * v1 + (r - 1) * r * r * m1
                if h * v0 <= 0.0:
                    return True
    return False


@njit(**JIT)
def _roots(a, b, c):
    """The real roots of a t^2 + b t + c (NaN for those missing)."""
    if a == 0.0:
        return (-c / b if b != 0.0 else math.nan), math.nan
    d = b * b - 4.0 * a * c
    if d < 0.0:
        return math.nan, math.nan
    q = -0.5 * (b + math.copysign(math.sqrt(d), b))
    return q / a, (c / q if q != 0.0 else math.nan)


@njit(**JIT)
def _copy(regime_from, speed_from, regime_to, speed_to):
    """A regime and its relative speeds and slopes, copied."""
    for k in range(regime_from.shape[0]):
        regime_to[k] = regime_from[k]
    for k in range(speed_from.shape[1]):
        speed_to[0, k] = speed_from[0, k]
        speed_to[1, k] = speed_from[1, k]


@njit(**JIT)
def _same(a, b):
    for k in range(a.shape[0]):
        if a[k] != b[k]:
            return False
    return True


@njit(**JIT_ALLOC)
def rk4_friction(advance, start, K, sizes, masses, par, tols, const, tab_phi, h_phi, tab_t, h_t,
                 damping, phi0, omega0, dt, n_sub, omega_limit, out_t, out_phi, out_omega,
                 out_eps, tail_t, tail_phi, tail_omega, tail_eps, friction):
    """``kernels.dynamics.rk4`` (the same arguments, records and outcomes) with
    the friction ``friction`` (``friction_args``): each step in the regime of
    its start, halved where it ends in another (the module's docstring)."""
    n_points, n_groups, n_triads = sizes
    pos, d1, d2, margins, state, _ = work(n_points, n_groups, n_triads)
    last = np.empty(1)
    loads_k = np.empty((masses[4].shape[0], 3))
    nb = masses[1].shape[0]
    nj = friction[5].shape[0]
    ns = friction[7].shape[0]
    m = 3 * nb
    # the regime: per joint and slide the direction of its friction, then per slide
    # the branch of its normal force's magnitude (kernels.friction.slide_branch)
    fw = (np.empty((m, m)), np.empty((m, m)), np.empty(m), np.empty(m), np.empty(m),
          np.empty(nj + 2 * ns), np.empty((nb, 3)), np.empty((nj, 2)), np.empty((ns, 2)),
          np.empty(nj + ns), np.empty(nj + ns), np.empty(4))
    regime = np.empty(nj + 2 * ns)
    after = np.empty(nj + 2 * ns)
    switched = np.empty(nj + 2 * ns)
    speed0 = np.empty((2, nj + ns))     # the relative speeds and slopes at a piece's start
    speed1 = np.empty((2, nj + ns))     # ... at a trial's end
    speed_sw = np.empty((2, nj + ns))   # ... at the end of the piece past a switch
    end = np.empty(2)
    n_steps, tail0 = step_counts(out_t, tail_t, n_sub)
    begin(start, K, phi0, state, last)
    p = phi0
    w = omega0
    crossing = -1
    st, e = _eval(advance, K, masses, par, tols, const, tab_phi, h_phi, tab_t, h_t, damping,
                  0.0, p, w, state, last, pos, d1, d2, margins, loads_k, friction, fw, regime,
                  unliteral(False), speed0)
    n = 0
    while st == OK:
        if record(n, n_sub, tail0, dt, p, w, e, out_t, out_phi, out_omega, out_eps, tail_t,
                  tail_phi, tail_omega, tail_eps) and crossing >= 0:
            st = TOO_FAST
        if n == n_steps or st != OK:
            break
        # the step to t = (n + 1) dt, in pieces that each keep their start's regime
        t = n * dt
        t_end = (n + 1) * dt
        pieces = 0
        while st == OK and t < t_end:
            pieces += 1
            if pieces > MAX_PIECES:     # the regime flips back and forth: held by friction
                st = FRICTION_LOCK
                crossing = n
                break
            r = t_end - t
            e_start = e     # eps1 at the piece's start, in its regime: every trial's first stage
            st, e, same = _trial(advance, K, masses, par, tols, const, tab_phi, h_phi, tab_t,
                                 h_t, damping, t, p, w, e_start, r, omega_limit, state, last,
                                 pos, d1, d2, margins, loads_k, friction, fw, regime, after, end,
                                 speed0, speed1)
            h = r
            if st == OK and not same:
                # the switch by bisection on the piece's length: [lo, hi] brackets it
                lo = 0.0
                hi = r
                hi_p, hi_w, hi_e = end[0], end[1], e
                _copy(after, speed1, switched, speed_sw)
                for _ in range(SWITCH_STEPS):
                    mid = 0.5 * (lo + hi)
                    st, e, same = _trial(advance, K, masses, par, tols, const, tab_phi, h_phi,
                                         tab_t, h_t, damping, t, p, w, e_start, mid,
                                         omega_limit, state, last, pos, d1, d2, margins,
                                         loads_k, friction, fw, regime, after, end, speed0,
                                         speed1)
                    if st != OK:
                        break
                    if same:
                        lo = mid
                    else:
                        hi = mid
                        hi_p, hi_w, hi_e = end[0], end[1], e
                        _copy(after, speed1, switched, speed_sw)
                # taken: the piece just past the switch, in the regime of its start
                h = hi
                end[0] = hi_p
                end[1] = hi_w
                e = hi_e
                _copy(switched, speed_sw, after, speed1)
            if st != OK:
                break
            t = t_end if h == r else t + h
            p = end[0]
            w = end[1]
            _copy(after, speed1, regime, speed0)
        if st != OK:
            break
        n += 1
        if crossing < 0 and abs(w) > omega_limit:
            crossing = n
    if st == TOO_FAST and crossing < 0:
        crossing = n + 1
    return st, crossing


# its types, for which it is compiled once (compile_friction_integrator)
FRICTION = types.Tuple((types.int64, types.float64, types.float64, _F1, _F1, _I1, _I2, _I2, _I2,
                        _F1, types.int64))
SIGNATURE = types.Tuple((types.int64, types.int64))(
    ADVANCE, START, _F1, SIZES, MASSES, _F1, _F1, *_DRIVE, types.float64, types.float64,
    types.float64, types.float64, types.int64, types.float64, *[_F1] * 8, FRICTION)


def friction_args(plan, friction):
    """``rk4_friction``'s ``friction`` for ``plan`` with ``friction``
    (model.friction.Friction): (1, f_rev, f_slide, pin radius per joint [m],
    block length per slide [mm], joint_point, joint_bodies, slide_bodies,
    slide_dir, slide_angle, crank_body)."""
    nj, ns = len(plan.joint_names), len(plan.slide_names)
    return (1, float(friction.revolute), float(friction.slide),
            np.asarray(friction.diameters(), float).reshape(nj) * 0.5e-3,
            np.asarray(friction.block_lengths(), float).reshape(ns),
            np.ascontiguousarray(plan.joint_point, np.int64).reshape(nj),
            np.ascontiguousarray(plan.joint_bodies, np.int64).reshape(nj, 2),
            np.ascontiguousarray(plan.slide_bodies, np.int64).reshape(ns, 2),
            np.ascontiguousarray(plan.slide_dir, np.int64).reshape(ns, 2),
            np.ascontiguousarray(plan.slide_angle, float).reshape(ns), int(plan.crank_body))


def compile_friction_integrator() -> None:
    """``rk4_friction`` compiled (or loaded from numba's cache) for SIGNATURE and
    no other: once per installation, not per mechanism."""
    compile_for(rk4_friction, SIGNATURE)
