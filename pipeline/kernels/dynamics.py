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

The integrator itself (RK4 over the mechanism's exact kinematics) is a
generated kernel of the mechanism (``pipeline.compiler``): class III groups
keep their continuation state there, so the integrator's small steps never
jump branch, and a kinematic failure (or a non-finite acceleration) stops the
integration with its status.
"""

import math

import numpy as np
from numba import njit

from .config import JIT
from .geometry import angle_analogs

MM = 1e-3


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
