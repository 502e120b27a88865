"""Balancing the shaking force with a counterweight on the crank.

The shaking force F(phi1) is what the moving links' inertia puts on the frame,
sum(-m a_S) (``kernels.forces.shaking``, computed with the reactions by
``solve.reactions.scene_forces``).  A point mass m_c on the crank at radius
r_c and at the angle beta from the crank line pivot -> tip (counter-clockwise)
sits at O + (r_c / L) rot(P_tip - P_pivot, beta): m_c times its position is
(m_c r_c / L) e^(i beta) (P_tip - P_pivot) in complex notation, so its inertia
force is -w a(phi1) with the complex weight w = m_c r_c e^(i beta) / L [kg] and
a the acceleration of the crank's tip relative to its pivot, exact from the
analogs (a = r'' omega1^2 + r' eps1).  The frame then feels F - w a: linear in
w, and the peak over the revolution, max |F_k - w a_k|, is convex in w.  It is
minimised in three steps, the best kept: the least-squares weight, the minimax
over the positions with the norm as a 64-gon (a linear programme, within 0.12 %
of the optimum), and SLSQP on the exact norms from there.

Only the product m_c r_c matters for the force (kg*mm); the shaking moment
about the crank's pivot does not change at a uniform crank speed (the point
mass is pulled along its radius, through the pivot)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

POLYGON = 64        # sides of the LP's polygon for the norm |.|


@dataclass
class Counterweight:
    mass_radius: float       # kg*mm: m_c r_c
    angle: float             # deg: from the crank line pivot -> tip, counter-clockwise
    before: float            # N: peak |shaking force| over the positions, without it
    before_phi1: float       # deg: where
    after: float             # N: the peak with it
    after_phi1: float        # deg
    phi: np.ndarray          # rad: the positions it was chosen over (the dense revolution)
    force_after: np.ndarray  # (n, 2) N: the shaking force with it
    crank: tuple = ()        # (pivot, tip) point names

    def summary(self) -> dict:
        pivot, tip = self.crank
        return {"counterweight": (
            f"{self.mass_radius:.6g} kg·mm at {self.angle:.4f} deg from the crank line "
            f"{pivot}->{tip} (m_c r_c; counter-clockwise): peak shaking force over the "
            f"{len(self.phi)} positions {self.before:.6g} N (phi1 = {self.before_phi1:g} deg) "
            f"-> {self.after:.6g} N (phi1 = {self.after_phi1:g} deg)")}


def minimax_weight(F, A):
    """The complex w that minimises max_k |F_k - w A_k| (F, A complex arrays)."""
    F = np.asarray(F, complex)
    A = np.asarray(A, complex)
    sF, sA = np.abs(F).max(), np.abs(A).max()
    if not (sF > 0.0 and sA > 0.0):
        return 0j
    f, b = F / sF, A / sA           # scaled: the peak and the weight of order 1

    def peak(w):
        return float(np.abs(f - w * b).max())

    tried = [0j, complex(np.vdot(b, f) / np.vdot(b, b))]      # none; least squares
    tried.append(_polygon_lp(f, b))
    tried.append(_slsqp(f, b, min(tried, key=peak)))
    return min(tried, key=peak) * sF / sA


def _polygon_lp(f, b):
    """The minimax with |z| replaced by max over directions u_j of Re(conj(u_j) z):
    min t subject to Re(conj(u_j) (f_k - w b_k)) <= t for every k, j."""
    from scipy.optimize import linprog
    th = 2.0 * math.pi * np.arange(POLYGON) / POLYGON
    u = np.exp(1j * th)[None, :]
    ub = np.conj(u) * b[:, None]        # Re(conj(u) b w) = x Re(ub) - y Im(ub)
    rows = np.stack([-ub.real.ravel(), ub.imag.ravel(), -np.ones(ub.size)], axis=1)
    rhs = -(np.conj(u) * f[:, None]).real.ravel()
    r = linprog([0.0, 0.0, 1.0], A_ub=rows, b_ub=rhs,
                bounds=[(None, None), (None, None), (0.0, None)], method="highs")
    return complex(r.x[0], r.x[1]) if r.status == 0 else 0j


def _slsqp(f, b, w0):
    """min t subject to t^2 >= |f_k - w b_k|^2, from w0 (smooth constraints)."""
    from scipy.optimize import minimize

    def gaps(v):
        z = f - complex(v[0], v[1]) * b
        return v[2] ** 2 - (z.real ** 2 + z.imag ** 2)

    def jac(v):
        z = f - complex(v[0], v[1]) * b
        # d|z|^2/dx = -2 Re(conj(z) b), d|z|^2/dy = -2 Re(conj(z) i b)
        return np.stack([2.0 * (np.conj(z) * b).real, 2.0 * (np.conj(z) * 1j * b).real,
                         np.full(z.shape, 2.0 * v[2])], axis=1)

    t0 = float(np.abs(f - w0 * b).max())
    r = minimize(lambda v: v[2], [w0.real, w0.imag, t0], jac=lambda v: np.array([0.0, 0.0, 1.0]),
                 method="SLSQP", constraints=[{"type": "ineq", "fun": gaps, "jac": jac}],
                 options={"ftol": 1e-15, "maxiter": 500})
    return complex(r.x[0], r.x[1]) if np.all(np.isfinite(r.x)) else w0


def crank_counterweight(mechanism, plan, curves, force) -> Counterweight | None:
    """The counterweight on the crank that minimises the peak |shaking force|
    ``force`` (n, 2) [N] over the positions of ``curves`` (None where the
    shaking force is not finite everywhere, or 0 everywhere: nothing to balance)."""
    crank = mechanism.crank
    force = np.asarray(force, float)
    if force.size == 0 or not np.isfinite(force).all() or not np.any(force != 0.0):
        return None
    ip, it = plan.point(crank.pivot), plan.point(crank.tip)
    w1, e1 = crank.omega1, crank.eps1
    a = ((curves.d2[:, it] - curves.d2[:, ip]) * w1 * w1
         + (curves.d1[:, it] - curves.d1[:, ip]) * e1) / 1000.0     # m/s²
    F = force[:, 0] + 1j * force[:, 1]
    A = a[:, 0] + 1j * a[:, 1]
    w = minimax_weight(F, A)
    after = F - w * A
    phi = np.rad2deg(curves.phi)
    kb, ka = int(np.argmax(np.abs(F))), int(np.argmax(np.abs(after)))
    angle = math.degrees(math.atan2(w.imag, w.real)) if w != 0 else 0.0
    return Counterweight(abs(w) * crank.length, angle, float(abs(F[kb])), float(phi[kb]),
                         float(abs(after[ka])), float(phi[ka]), np.asarray(curves.phi, float),
                         np.stack([after.real, after.imag], axis=1), (crank.pivot, crank.tip))


def scene_counterweight(res) -> Counterweight | None:
    """The crank's counterweight of the scene ``res`` (pipeline.solve.scene.SceneResult)
    over its dense revolution: None without forces or where it does not assemble."""
    dense = res.dense
    if dense.forces is None or dense.overall != 0 or dense.forces.shaking is None:
        return None
    return crank_counterweight(res.study.mechanism, res.plan, dense, dense.forces.shaking[:, :2])
