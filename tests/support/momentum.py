"""The shaking force and moment as the test sees them: minus the rates of change
of the moving links' total momentum and angular momentum, by central
differences in time of the centres' velocities along a uniform crank rotation
(never the acceleration analogs the package's shaking kernel uses); and a
study with a counterweight on the crank, rigidly part of the crank's body."""

import dataclasses
import math

import numpy as np

from pipeline.kernels import config as kc
from pipeline.solve.scene import solve_curves

# 8th-order central differences of a first derivative, offsets 1..4
W1 = np.array([4.0 / 5.0, -1.0 / 5.0, 4.0 / 105.0, -1.0 / 280.0])
STEP = 2e-3          # rad of crank angle per time step (the stencil spans +-0.46 deg)


def momenta(plan, curves, crank, about):
    """Per row of ``curves``: the total momentum p = sum m v_S (n, 2) [kg*m/s] and
    the angular momentum about the point ``about`` (an index), H = sum J_S omega
    + (S - O) x m v_S (n,) [kg*m^2/s], at the crank's speed omega1 (v = S'
    omega1, omega = phi' omega1 with phi' = (r x r') / |r|^2 of the body's turn
    vector r)."""
    w1 = crank.omega1
    n = curves.pos.shape[0]
    p = np.zeros((n, 2))
    h = np.zeros(n)
    O = curves.pos[:, about]
    for i, s in enumerate(plan.body_com):
        m, J = plan.par[plan.body_mass_off[i]], plan.par[plan.body_mass_off[i] + 1]
        v = curves.d1[:, s] * w1 / 1000.0
        r = (curves.pos[:, s] - O) / 1000.0
        a, b = plan.body_turn[i]
        om = np.zeros(n)
        if a >= 0:
            d = curves.pos[:, b] - curves.pos[:, a]
            dd = curves.d1[:, b] - curves.d1[:, a]
            om = (d[:, 0] * dd[:, 1] - d[:, 1] * dd[:, 0]) / (d ** 2).sum(axis=1) * w1
        p += m * v
        h += J * om + m * (r[:, 0] * v[:, 1] - r[:, 1] * v[:, 0])
    return p, h


def momentum_rates(study, plan, phis, k):
    """(-dp/dt (2,) [N], -dH/dt [N*m]) at the crank angle phis[k] of the
    revolution ``phis``: the crank turns uniformly at omega1, so at t_k + j tau
    its angle is phis[k] + omega1 j tau; the positions and velocity analogs
    there are walked from phis[0] along the revolution (its own branch), and
    dp/dt = sum_q W1[q] (p(t + q tau) - p(t - q tau)) / tau."""
    crank = study.mechanism.crank
    tau = STEP / abs(crank.omega1)
    j = np.arange(-4, 5)
    stencil = phis[k] + crank.omega1 * tau * j
    order = np.argsort(crank.rot * stencil)           # along the walk
    path = np.concatenate([phis[:k], stencil[order]])
    c = solve_curves(plan, path, kc.VELOCITIES)
    assert c.overall == kc.OK and (c.status == kc.OK).all()
    rows = np.empty(9, np.int64)
    rows[order] = k + np.arange(9)
    sub = dataclasses.replace(c, pos=c.pos[rows], d1=c.d1[rows])
    p, h = momenta(plan, sub, crank, plan.point(crank.pivot))
    dp = sum(W1[q - 1] * (p[4 + q] - p[4 - q]) for q in range(1, 5)) / tau
    dh = sum(W1[q - 1] * (h[4 + q] - h[4 - q]) for q in range(1, 5)) / tau
    return -dp, -dh


def with_counterweight(study, mass_radius, angle_deg, radius=None):
    """``study`` with a point mass m_c at radius r_c (``radius``, mm; the crank's
    length by default) and ``angle_deg`` from the crank line pivot -> tip
    (counter-clockwise) fixed to the crank, m_c r_c = ``mass_radius`` [kg*mm].
    The crank's body takes it: one rigid body of mass m1 + m_c whose centre is
    the two masses' centre and whose J_S adds both about it (parallel axes; the
    point mass has no J_S of its own).  Its centre of mass must be declared on
    the crank line from the pivot (base = pivot, along = (pivot, tip))."""
    mech = study.mechanism
    crank = mech.crank
    plan = mech.compile()
    i = plan.crank_body
    body = mech.bodies[i]
    com = body.com
    assert com.base == crank.pivot and tuple(com.along) == (crank.pivot, crank.tip), com
    r_c = crank.length if radius is None else radius
    m_c = mass_radius / r_c
    s1 = com.lS * np.array([math.cos(com.US), math.sin(com.US)])      # crank frame, mm
    c = r_c * np.array([math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))])
    m = body.mass + m_c
    sc = (body.mass * s1 + m_c * c) / m
    J = body.J_S + (body.mass * ((s1 - sc) ** 2).sum() + m_c * ((c - sc) ** 2).sum()) * 1e-6
    new = dataclasses.replace(body, mass=m, J_S=J, com=dataclasses.replace(
        com, lS=float(math.hypot(*sc)), US=float(math.atan2(sc[1], sc[0]))))
    bodies = mech.bodies[:i] + (new,) + mech.bodies[i + 1:]
    return dataclasses.replace(study, mechanism=dataclasses.replace(mech, bodies=bodies))
