"""Generators of hard candidates for the numerical-stability stress suite.

Near-singular class III groups are built, not hoped for: a triad is at a
singular (uncertainty) position exactly when the lines of its three leads
meet in one point.  Each candidate places the ternary link, picks a point Q
on the line of lead 2-3, puts the pivots P6 and P7 on the lines from the
vertices 4 and 5 towards Q, then moves Q off that line by a relative
distance from 1e-10 to 1e-1 (or not at all).  The start guess (a, b) is the
exact assembly at phi1 = 0.
"""

from __future__ import annotations

import math

import numpy as np


def e(x):
    return np.stack([np.cos(x), np.sin(x)], axis=-1)


def near_singular_triads(plan, n, seed=0):
    """Parameter rows (n, n_par) for the class III plan of mechanism B, and the
    relative offset of each from the exactly singular construction (0 = exact)."""
    rng = np.random.default_rng(seed)
    par = np.repeat(plan.par[None, :], n, axis=0)
    g = plan.group_names.index("triad")
    o = plan.goff[g]
    phim0 = plan.par[plan.param("crank.phiM0")]
    l12 = rng.uniform(20, 80, n)
    p2 = l12[:, None] * e(np.full(n, phim0))
    l23 = rng.uniform(150, 350, n)
    a = rng.uniform(-math.pi, math.pi, n)
    b = rng.uniform(-math.pi, math.pi, n)
    l34 = rng.uniform(50, 150, n)
    l35 = rng.uniform(80, 220, n)
    u = rng.uniform(0.2, 2.5, n)                 # angle at vertex 3
    l45 = np.sqrt(l34 ** 2 + l35 ** 2 - 2 * l34 * l35 * np.cos(u))
    p3 = p2 + l23[:, None] * e(a)
    p4 = p3 + l34[:, None] * e(b)
    p5 = p3 + l35[:, None] * e(b + u)
    s = rng.uniform(-400, 700, n)
    s = np.where(np.abs(s - l23) < 30, s + 60, s)          # keep Q away from P3
    q = p2 + s[:, None] * e(a)
    offset = np.where(rng.random(n) < 0.1, 0.0, 10 ** rng.uniform(-10, -1, n))
    q = q + (offset * l23)[:, None] * e(a + math.pi / 2)   # off the line of lead 2-3
    l46 = rng.uniform(60, 200, n)
    l57 = rng.uniform(150, 350, n)
    side6 = np.where(rng.random(n) < 0.5, 1.0, -1.0)
    side7 = np.where(rng.random(n) < 0.5, 1.0, -1.0)
    d6 = (q - p4) / np.linalg.norm(q - p4, axis=1)[:, None]
    d7 = (q - p5) / np.linalg.norm(q - p5, axis=1)[:, None]
    p6 = p4 + (side6 * l46)[:, None] * d6
    p7 = p5 + (side7 * l57)[:, None] * d7
    par[:, plan.param("crank.length")] = l12
    par[:, plan.param("P6.x")], par[:, plan.param("P6.y")] = p6[:, 0], p6[:, 1]
    par[:, plan.param("P7.x")], par[:, plan.param("P7.y")] = p7[:, 0], p7[:, 1]
    for k, v in enumerate((l23, l34, l45, l35, l46, l57)):
        par[:, o + k] = v
    par[:, o + 6] = 1.0          # orientation: U435 > 0 by construction
    par[:, o + 7] = a
    par[:, o + 8] = b
    par[:, o + 9] = 0.0
    return np.ascontiguousarray(par), offset


def scaled_rows(plan, scales):
    """Mechanism B scaled by each factor (every length and pivot coordinate)."""
    rows = []
    length_like = [i for i, n in enumerate(plan.par_names)
                   if n.endswith((".x", ".y", ".length", ".L23", ".L34", ".L45", ".L35", ".L46",
                                  ".L57"))]
    for s in scales:
        r = plan.par.copy()
        r[length_like] *= s
        rows.append(r)
    return np.array(rows)


def fourbar_rows(plan, n, seed=0, toggle_fraction=0.5):
    """Four-bars (mechanism D's plan) near Grashof's change-point condition
    l_min + l_max = p + q, where the linkage passes through a toggle, and with
    nearly coincident ground pivots."""
    rng = np.random.default_rng(seed)
    par = np.repeat(plan.par[None, :], n, axis=0)
    crank = rng.uniform(5, 20, n)
    coupler = rng.uniform(30, 50, n)
    rocker = rng.uniform(30, 50, n)
    # ground length at the change point, nudged by +-eps (log-uniform)
    ground = coupler + rocker - crank
    eps = 10 ** rng.uniform(-12, -2, n) * np.where(rng.random(n) < 0.5, 1.0, -1.0)
    exact = rng.random(n) < 0.1
    eps[exact] = 0.0
    ground = np.where(rng.random(n) < toggle_fraction, ground * (1 + eps), ground)
    # a few nearly coincident pivots
    tiny = rng.random(n) < 0.05
    ground = np.where(tiny, 10 ** rng.uniform(-12, -3, n), ground)
    par[:, plan.param("crank.length")] = crank
    par[:, plan.param("RRR[1].L_AB")] = coupler
    par[:, plan.param("RRR[1].L_CB")] = rocker
    par[:, plan.param("P4.x")] = ground
    return np.ascontiguousarray(par)
