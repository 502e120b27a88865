"""The crank's reduced dynamics (DOMAIN.md section 7): the reduced moment of
inertia J(phi), (1/2) dJ/dphi and the generalised force Q(phi) of a compiled
plan at any crank angles (``reduced_terms``), its kinetic and potential energy
(``energy``), and over one revolution with the equilibria Q = 0
(``reduced_dynamics``).  The equation of motion they enter and its integration
are ``crank_motion``'s."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..kernels import config as kc
from .crank_drive import Drive, build_drive
from .crank_motion import _kernels, _plan_args


def _zero_drive(n_loads):
    """No driving moment and no loads (the channel count must match the plan)."""
    empty = np.zeros((1 + 3 * n_loads, 0, 4))
    return Drive(np.zeros(1 + 3 * n_loads), empty, 1.0, empty, 1.0)


def _curve(plan, phi, t=0.0, mechanism=None, loads=True, tols=None):
    if len(plan.body_names) == 0:
        raise ValueError("crank dynamics needs mass data (bodies)")
    n_loads = len(plan.load_body)
    if loads and n_loads and mechanism is None:
        raise ValueError("the plan has external loads: pass the mechanism that declares them")
    tols = kc.default_tolerances() if tols is None else tols
    phis = np.atleast_1d(np.asarray(phi, dtype=np.float64)).ravel().copy()
    ts = np.broadcast_to(np.asarray(t, dtype=np.float64), np.shape(phi)).ravel().copy()
    if loads and n_loads:
        from ..base.expressions import parse_expression
        t_max = max(1e-3, float(np.max(ts))) if ts.size else 1e-3
        drive = build_drive(mechanism, parse_expression(0.0, "M1"), t_end=t_max,
                            dt=t_max / 2000)
    else:
        drive = _zero_drive(n_loads)
    out = [np.full(phis.shape, np.nan) for _ in range(5)]
    status = np.zeros(phis.shape, np.int8)
    kern = _kernels(plan)
    kern.terms_curve(*_plan_args(plan, tols, kern), *drive.args(), phis, ts, *out, status)
    return out, status


def reduced_terms(plan, phi, t=0.0, mechanism=None):
    """(J [kg·m²], (1/2) dJ/dphi [kg·m²], Q without M1 [N·m]) at crank
    angle(s) ``phi`` (rad).  ``mechanism`` supplies the load expressions when
    the plan has loads (evaluated at ``t``).  Scalars in, scalars out."""
    (J, half, Q, _m1, _V), _ = _curve(plan, phi, t, mechanism)
    if np.ndim(phi) == 0:
        return float(J[0]), float(half[0]), float(Q[0])
    shape = np.shape(phi)
    return J.reshape(shape), half.reshape(shape), Q.reshape(shape)


def energy(plan, phi, omega):
    """(T, V) [J]: kinetic energy J(phi) omega^2 / 2 and gravitational
    potential sum m g y_S at the states (phi [rad], omega [rad/s])."""
    (J, _h, _Q, _m1, V), _ = _curve(plan, phi, loads=False)
    shape = np.shape(phi)
    T = 0.5 * J * np.broadcast_to(np.asarray(omega, float), J.shape) ** 2
    if len(shape) == 0:
        return float(T[0]), float(V[0])
    return T.reshape(shape), V.reshape(shape)


@dataclass
class Reduced:
    """The crank's reduced dynamics over one revolution (loads at t = 0):
    J(phi), (1/2) dJ/dphi and the generalised force Q(phi) without M1, and
    the equilibria (Q = 0) with their stability."""
    phi: np.ndarray             # rad, absolute crank angle, increasing over [0, 2 pi)
    J: np.ndarray               # kg·m²
    half_dJ: np.ndarray         # kg·m²
    Q: np.ndarray               # N·m
    equilibria: list            # (phi deg, stable) where Q = 0

    def summary(self) -> dict:
        if not self.equilibria:
            return {"equilibria": "none (Q does not change sign over the revolution)"}
        return {"equilibria": ", ".join(f"{p:.4f} deg ({'stable' if st else 'unstable'})"
                                        for p, st in self.equilibria)}


def reduced_dynamics(study, plan, n=None) -> Reduced:
    """J, (1/2) J' and Q over the revolution and the equilibria: Q = 0 found
    by Brent's method between samples where Q changes sign; stable where Q
    falls through zero as phi grows (a restoring force)."""
    from scipy.optimize import brentq
    n = n or study.output.dense_positions
    phis = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    J, half, Q = reduced_terms(plan, phis, 0.0, study.mechanism)

    def q(phi):
        return reduced_terms(plan, float(phi), 0.0, study.mechanism)[2]

    eq = []
    for k in range(n):
        a, b = phis[k], phis[k + 1] if k + 1 < n else 2.0 * math.pi
        qa, qb = Q[k], Q[(k + 1) % n]
        if not (np.isfinite(qa) and np.isfinite(qb)) or qa * qb > 0.0 or qa == qb == 0.0:
            continue
        if qb == 0.0 and k + 1 < n:
            continue                  # the root is the next sample's left end
        root = a if qa == 0.0 else brentq(q, a, b, xtol=1e-13)
        eq.append((math.degrees(root) % 360.0, bool(qa > qb)))
    return Reduced(phis, J, half, Q, eq)
