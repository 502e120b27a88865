"""Naive, slow, obviously-correct reference implementations (test oracle).

This module is deliberately independent of the ``pipeline`` package: it never
imports it and uses none of its formulas.  Positions are found with a generic
root finder (``scipy.optimize.fsolve``) on the plain distance / closure
equations, then polished with a few Newton steps whose Jacobian comes from the
complex-step derivative of the same residuals.  All derivatives with respect
to the crank angle (the "analogs") come from 8th-order central finite
differences of the position solver, never from an analytic velocity formula.

Conventions (DOMAIN.md section 2)
---------------------------------
* angles in radians, lengths in mm, forces in N, moments in N*m;
* analogs are derivatives with respect to the generalized coordinate phi1
  (the crank angle); the crank's absolute angle is phi1 + phiM0;
* ``rot(r, alpha, L)``: r rotated by alpha about +Z, rescaled to length L;
* a link a_b has the angle atan2(Pb - Pa);
* RRR dyad joining known A to known C through A-B and C-B, mode W:
  C->B = rot(A - C, -W*U, L_CB) with U in [0, pi].  Hence the sign of
  cross(A - C, B - C) is -W; W = -1 <=> cross(A - C, B - C) > 0.

Kinetostatics sign convention
-----------------------------
Every joint is named as an ordered pair (first body, second body), the first
being the ground or the lower-numbered link.  The reaction R_k = (Rx, Ry)
returned for the joint is the force that the FIRST body exerts on the SECOND;
the first body receives -R_k.  ``M_bal`` is the moment (about +Z, N*m) that
the driver applies to the crank.  Per-link ``F`` is the resultant of all
applied and inertia forces of the link (gravity + (-m a_S) + external
forces), reduced to the centre of mass S; ``M`` is the resultant moment about
S (-J_S eps + moments of external forces about S).  With these, the virtual
power identity M_bal*omega1 + sum(F . v_S + M * omega) = 0 holds.
"""

from __future__ import annotations

import functools
import inspect
import math

import mpmath
import numpy as np
from scipy.optimize import fsolve

DEG = math.pi / 180.0
G = 9.81

# ---------------------------------------------------------------------------
# small geometric helpers
# ---------------------------------------------------------------------------


def e(angle):
    """Unit vector at ``angle`` (works for complex angles too)."""
    return np.array([np.cos(angle), np.sin(angle)])


def rot(r, alpha, length):
    """rot(r, alpha, L): r rotated by alpha about +Z and rescaled to length L."""
    r = np.asarray(r, dtype=float)
    c, s = math.cos(alpha), math.sin(alpha)
    v = np.array([c * r[0] - s * r[1], s * r[0] + c * r[1]])
    return v * (length / math.hypot(v[0], v[1]))


def cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


def angle_of(p_from, p_to):
    d = np.asarray(p_to) - np.asarray(p_from)
    return math.atan2(d[1], d[0])


def _wrap(x):
    """Wrap an angle difference into (-pi, pi]."""
    return (x + math.pi) % (2.0 * math.pi) - math.pi


def _complex_step_jacobian(fun, x, h=1e-30):
    """Jacobian of a real-analytic vector function by the complex step."""
    x = np.asarray(x, dtype=float)
    f0 = np.asarray(fun(x.astype(complex)))
    jac = np.zeros((f0.size, x.size))
    for j in range(x.size):
        xc = x.astype(complex)
        xc[j] += 1j * h
        jac[:, j] = np.imag(np.asarray(fun(xc))) / h
    return jac


def _solve(fun, guess, polish=3, tol=1e-9):
    """fsolve (xtol 1e-14) followed by Newton polish steps; returns x."""
    x, _info, ier, msg = fsolve(lambda z: np.real(fun(z)), np.asarray(guess, float),
                                xtol=1e-14, full_output=True)
    for _ in range(polish):
        jac = _complex_step_jacobian(fun, x)
        res = np.real(fun(x))
        x = x - np.linalg.solve(jac, res)
    res = np.abs(np.real(fun(x))).max()
    if not np.isfinite(res) or res > tol:
        raise ValueError(f"no solution (residual {res:.3e}; fsolve: {msg})")
    return x


def solve_rrr(A, C, L_AB, L_CB, W=-1):
    """Point B of an RRR dyad (A-B length L_AB, C-B length L_CB), mode W.

    Solved with fsolve on the two distance equations; the branch is the one
    where sign(cross(A - C, B - C)) == -W (see module docstring).
    """
    A = np.asarray(A, float)
    C = np.asarray(C, float)

    def res(B):
        return np.array([np.sqrt((B[0] - A[0]) ** 2 + (B[1] - A[1]) ** 2) - L_AB,
                         np.sqrt((B[0] - C[0]) ** 2 + (B[1] - C[1]) ** 2) - L_CB])

    d = A - C
    u = d / np.hypot(*d)
    n = np.array([-u[1], u[0]])           # +90 deg from C->A
    want = -W
    guess = C + L_CB * (0.3 * u + want * 0.95 * n)
    B = _solve(res, guess)
    if np.sign(cross(A - C, B - C)) != want:
        # reflect across line CA and polish again
        w = B - C
        w_ref = 2.0 * np.dot(w, u) * u - w
        B = _solve(res, C + w_ref)
    if np.sign(cross(A - C, B - C)) != want:
        raise ValueError("RRR dyad: requested branch not found")
    return B


# ---------------------------------------------------------------------------
# Mechanism A (DOMAIN.md section 4)
# ---------------------------------------------------------------------------

A_DATA = dict(
    P1=np.array([0.0, 0.0]), P4=np.array([26.0, 98.7]),
    P6=np.array([105.3, 58.4]), P8=np.array([46.0, 533.0]),
    L12=14.9, L23=105.0, L43=31.0, L35=61.0, L65=13.0, L57=423.0,
    L87=115.0, L89=136.8, U789=-84.0 * DEG, phiM0=181.84 * DEG,
    omega1=-97.2,
)
A_LINKS = ["1_2", "2_3", "4_3", "3_5", "6_5", "5_7", "8_7", "8_9"]


def mech_a_positions(phi1):
    """Positions P1..P9 of mechanism A at crank angle phi1 (rad), all W = -1."""
    d = A_DATA
    P1, P4, P6, P8 = d["P1"], d["P4"], d["P6"], d["P8"]
    P2 = P1 + d["L12"] * e(phi1 + d["phiM0"])
    P3 = solve_rrr(P2, P4, d["L23"], d["L43"], W=-1)
    P5 = solve_rrr(P3, P6, d["L35"], d["L65"], W=-1)
    P7 = solve_rrr(P5, P8, d["L57"], d["L87"], W=-1)
    P9 = P8 + rot(P7 - P8, d["U789"], d["L89"])
    return {"P1": P1.copy(), "P2": P2, "P3": P3, "P4": P4.copy(), "P5": P5,
            "P6": P6.copy(), "P7": P7, "P8": P8.copy(), "P9": P9}


# ---------------------------------------------------------------------------
# Mechanism B (DOMAIN.md section 5)
# ---------------------------------------------------------------------------

B_DATA = dict(
    P1=np.array([0.0, 0.0]), P6=np.array([195.0, 226.0]),
    P7=np.array([46.0, 533.0]),
    L12=50.0, L23=272.5, L34=81.0, L45=104.5, L35=174.0, L46=104.5,
    L57=261.0, L78=136.8, U578=-25.0 * DEG, phiM0=173.0 * DEG,
    omega1=-94.4,
    guess0=(44.006 * DEG, 128.709 * DEG),
)
B_DATA["U435"] = math.acos((B_DATA["L34"] ** 2 + B_DATA["L35"] ** 2 - B_DATA["L45"] ** 2)
                           / (2.0 * B_DATA["L34"] * B_DATA["L35"]))
B_LINKS = ["1_2", "2_3", "3_4", "3_5", "4_5", "6_4", "7_5", "7_8"]

# mass data: (base point, tip point, lS mm, US rad, m kg, J kg m^2, angle link)
B_MASS = {
    "crank": ("P1", "P2", 26.21, 0.0, 0.91, 0.001189631),
    "lead_2_3": ("P2", "P3", 122.54, 0.0, 0.73, 0.008434849),
    "ternary_3_4_5": ("P3", "P4", 85.01, 15.13 * DEG, 0.91, 0.004456758),
    "lead_4_6": ("P6", "P4", 40.99, 0.0, 1.64, 0.005376871),
    "rocker_5_7_8": ("P7", "P5", 125.30, 37.56 * DEG, 1.07, 0.012826014),
}


def _b_closure_points(ab, phi1, d=B_DATA):
    a, b = ab[0], ab[1]
    P2 = d["P1"] + d["L12"] * e(phi1 + d["phiM0"])
    P3 = P2 + d["L23"] * e(a)
    P4 = P3 + d["L34"] * e(b)
    P5 = P3 + d["L35"] * e(b + d["U435"])
    return P2, P3, P4, P5


def _b_residual(ab, phi1):
    _P2, _P3, P4, P5 = _b_closure_points(ab, phi1)
    d4 = P4 - B_DATA["P6"]
    d5 = P5 - B_DATA["P7"]
    return np.array([np.sqrt(d4[0] ** 2 + d4[1] ** 2) - B_DATA["L46"],
                     np.sqrt(d5[0] ** 2 + d5[1] ** 2) - B_DATA["L57"]])


def _b_solve(phi1, guess):
    return _solve(lambda ab: _b_residual(ab, phi1), guess)


def _b_points(phi1, ab):
    d = B_DATA
    P2, P3, P4, P5 = _b_closure_points(ab, phi1)
    P8 = d["P7"] + rot(P5 - d["P7"], d["U578"], d["L78"])
    return {"P1": d["P1"].copy(), "P2": P2, "P3": P3, "P4": P4, "P5": P5,
            "P6": d["P6"].copy(), "P7": d["P7"].copy(), "P8": P8}


def _continue_b(phi_from, phi_to, ab, max_step=1.0 * DEG):
    """Continuation of the class III solution from phi_from to phi_to."""
    nsub = max(1, int(math.ceil(abs(phi_to - phi_from) / max_step - 1e-12)))
    for k in range(1, nsub + 1):
        ab = _b_solve(phi_from + (phi_to - phi_from) * k / nsub, ab)
    return ab


def mech_b_positions(phi1, guess=None):
    """Positions P1..P8 of mechanism B and the solution (a, b) in rad.

    ``guess``: (a, b) warm start in rad.  If None, the branch of DOMAIN.md
    (a = 44.006 deg, b = 128.709 deg at phi1 = 0) is used: solved at phi1 = 0
    from that guess and then continued to phi1 in substeps <= 1 deg (a plain
    solve from the phi1 = 0 guess at a far crank angle could switch branch).
    """
    if guess is None:
        ab0 = _b_solve(0.0, np.array(B_DATA["guess0"]))
        ab = _continue_b(0.0, phi1, ab0)
    else:
        ab = _b_solve(phi1, np.asarray(guess, float))
    return _b_points(phi1, ab), (float(ab[0]), float(ab[1]))


def _b_points_with_S(phi1, guess=None):
    pts, ab = mech_b_positions(phi1, guess)
    for name, (base, tip, lS, US, _m, _J) in B_MASS.items():
        pts["S_" + name] = pts[base] + rot(pts[tip] - pts[base], US, lS)
    return pts, ab


# ---------------------------------------------------------------------------
# continuation helper
# ---------------------------------------------------------------------------


def revolution(pos_fn, phis, guess=None, max_step=1.0 * DEG):
    """Evaluate ``pos_fn`` along the crank angles ``phis`` (rad).

    If ``pos_fn`` accepts a ``guess`` argument it is taken to return
    ``(points, state)``; the state of each solve warm-starts the next one and
    the path between consecutive angles is walked in substeps of at most
    ``max_step`` (1 deg).  The first angle is solved from ``guess`` (None lets
    the position function pick its default branch).  Functions without a
    ``guess`` parameter (closed branch selection, e.g. mechanism A) are simply
    called at each angle.  Returns the list of results at the requested
    angles (substeps are discarded).
    """
    phis = [float(p) for p in phis]
    takes_guess = "guess" in inspect.signature(pos_fn).parameters
    out = []
    if not takes_guess:
        return [pos_fn(p) for p in phis]
    prev_phi, state = None, guess
    for p in phis:
        if prev_phi is not None:
            nsub = max(1, int(math.ceil(abs(p - prev_phi) / max_step - 1e-12)))
            for k in range(1, nsub):
                _pts, state = pos_fn(prev_phi + (p - prev_phi) * k / nsub, guess=state)
        res = pos_fn(p, guess=state)
        state = res[1]
        out.append(res)
        prev_phi = p
    return out


# ---------------------------------------------------------------------------
# finite-difference analogs
# ---------------------------------------------------------------------------

# 8th-order central differences, offsets 1..4
_W1 = np.array([4.0 / 5.0, -1.0 / 5.0, 4.0 / 105.0, -1.0 / 280.0])
_W2C = -205.0 / 72.0
_W2 = np.array([8.0 / 5.0, -1.0 / 5.0, 8.0 / 315.0, -1.0 / 560.0])

DEFAULT_H = 0.02  # rad; truncation ~h^8, rounding ~1e-13/h^2 (see self-check)


def fd_analogs(points_at, phi1, links=(), h=DEFAULT_H):
    """Positions, first and second analogs of all points, and link angles.

    ``points_at(phi)`` returns a dict name -> np.ndarray(2).  The stencil is
    phi1 + k*h, k = -4..4.  Link angles atan2(Pb - Pa) are unwrapped about
    their value at phi1 before differencing.
    Returns dict with keys "pos", "d1", "d2" (point dicts) and "ang",
    "ang_d1", "ang_d2" (link dicts).
    """
    offs = list(range(-4, 5))
    samples = {k: points_at(phi1 + k * h) for k in offs}
    c = samples[0]
    out = {"pos": {}, "d1": {}, "d2": {}, "ang": {}, "ang_d1": {}, "ang_d2": {}}
    for name in c:
        f = {k: np.asarray(samples[k][name], float) for k in offs}
        d1 = sum(_W1[k - 1] * (f[k] - f[-k]) for k in range(1, 5)) / h
        d2 = (_W2C * f[0] + sum(_W2[k - 1] * (f[k] + f[-k]) for k in range(1, 5))) / h ** 2
        out["pos"][name] = f[0].copy()
        out["d1"][name] = d1
        out["d2"][name] = d2
    for link in links:
        a, b = link.split("_")
        pa, pb = "P" + a, "P" + b
        th0 = angle_of(c[pa], c[pb])
        th = {k: th0 + _wrap(angle_of(samples[k][pa], samples[k][pb]) - th0) for k in offs}
        out["ang"][link] = th0
        out["ang_d1"][link] = sum(_W1[k - 1] * (th[k] - th[-k]) for k in range(1, 5)) / h
        out["ang_d2"][link] = (_W2C * th[0]
                               + sum(_W2[k - 1] * (th[k] + th[-k]) for k in range(1, 5))) / h ** 2
    return out


def _chained_b_sampler(phi1, guess, h, with_S=False):
    """Mechanism B sampler for the stencil: solve at phi1 (from guess), then
    walk outward one stencil step at a time, warm-starting each solve from the
    neighbour nearer the centre."""
    fn = _b_points_with_S if with_S else mech_b_positions
    cache = {}
    pts0, ab0 = fn(phi1, guess)
    cache[0] = pts0
    for sgn in (1, -1):
        ab = ab0
        for k in range(1, 5):
            pts, ab = fn(phi1 + sgn * k * h, ab)
            cache[sgn * k] = pts

    def points_at(phi):
        k = int(round((phi - phi1) / h))
        return cache[k]

    return points_at, ab0


def mech_a_analogs(phi1, h=DEFAULT_H, links=A_LINKS):
    """FD analogs of mechanism A at phi1 (see ``fd_analogs`` for the layout)."""
    return fd_analogs(mech_a_positions, phi1, links, h)


def mech_b_analogs(phi1, guess=None, h=DEFAULT_H, links=B_LINKS, with_S=False):
    """FD analogs of mechanism B at phi1; result also has "ab" = (a, b)."""
    sampler, ab0 = _chained_b_sampler(phi1, guess, h, with_S)
    out = fd_analogs(sampler, phi1, links, h)
    out["ab"] = ab0
    return out


# ---------------------------------------------------------------------------
# Mechanism D (DOMAIN.md section 8)
# ---------------------------------------------------------------------------

D_DATA = dict(A=np.array([0.0, 0.0]), D=np.array([38.0, 0.0]),
              LAB=15.0, LBC=41.0, LDC=40.0, LDE=60.0, phiM0=0.0, omega1=60.0)


def _d_all_C(B):
    """Both intersection points C of |C-B| = LBC, |C-D| = LDC (by fsolve)."""
    Dp = D_DATA["D"]
    sols = []
    for W in (-1, 1):
        sols.append(solve_rrr(B, Dp, D_DATA["LBC"], D_DATA["LDC"], W=W))
    return sols


def _d_branch_sign():
    """sign of cross(B - D, C - D) of the open configuration: C above AD at 90 deg."""
    B = D_DATA["A"] + D_DATA["LAB"] * e(90.0 * DEG)
    Cs = _d_all_C(B)
    above = [C for C in Cs if C[1] > 0.0]
    assert len(above) == 1, "exactly one assembly must have C above AD at 90 deg"
    C = above[0]
    return int(np.sign(cross(B - D_DATA["D"], C - D_DATA["D"])))


D_BRANCH = _d_branch_sign()          # cross(B - D, C - D) sign (= -W in solve_rrr)
D_LINKS = ["1_2", "2_3", "4_3"]      # crank AB, coupler BC, rocker DC


def mech_d_positions(phi1):
    """Four-bar D: P1 = A, P2 = B, P3 = C, P4 = D, P5 = E (crank angle = phi1)."""
    d = D_DATA
    A, Dp = d["A"], d["D"]
    B = A + d["LAB"] * e(phi1 + d["phiM0"])
    C = solve_rrr(B, Dp, d["LBC"], d["LDC"], W=-D_BRANCH)
    E = Dp + (C - Dp) * (d["LDE"] / d["LDC"])
    return {"P1": A.copy(), "P2": B, "P3": C, "P4": Dp.copy(), "P5": E}


D_MASS = {  # base, tip, distance of S from base along base->tip, m, J
    "crank": ("P1", "P2", 5.0, 0.4, 2e-5),
    "coupler": ("P2", "P3", 41.0 / 2.0, 0.6, 1e-4),
    "rocker": ("P4", "P5", 25.0, 0.8, 2.5e-4),
}


def _d_points_with_S(phi1):
    pts = mech_d_positions(phi1)
    for name, (base, tip, lS, _m, _J) in D_MASS.items():
        pts["S_" + name] = pts[base] + rot(pts[tip] - pts[base], 0.0, lS)
    return pts


def mech_d_analogs(phi1, h=DEFAULT_H, links=D_LINKS):
    return fd_analogs(mech_d_positions, phi1, links, h)


# ---------------------------------------------------------------------------
# Mechanism C (DOMAIN.md section 7)
# ---------------------------------------------------------------------------

C_DATA = dict(l1=16.3, l2=44.2, P5=np.array([11.7, 35.69]), L54=55.0)
C_MASS = {  # m kg, J_S kg m^2, angle link of the body
    "S1": (0.200, 325e-6, "1_2"),
    "S2": (0.055, 70e-6, "2_3"),
    "S3": (0.100, 0.0, None),
    "S4": (0.020, 25e-6, "5_4"),   # the block turns with the coulisse
    "S5": (0.060, 50e-6, "5_4"),
}
C_LINKS = ["1_2", "2_3", "5_4"]


def mech_c_positions(phi1):
    """Mechanism C: (points dict P1..P5, P7, S1..S5, coulisse angle of P5->P4)."""
    d = C_DATA
    l1, l2 = d["l1"], d["l2"]
    P1 = np.array([0.0, 0.0])
    P2 = P1 + l1 * np.array([math.cos(phi1), math.sin(phi1)])
    P3 = np.array([0.0, l1 * math.sin(phi1) - math.sqrt(l2 ** 2 - (l1 * math.cos(phi1)) ** 2)])
    P4 = P2 + rot(P3 - P2, -90.0 * DEG, 10.0)
    P5 = d["P5"].copy()
    P7 = P5 + rot(P4 - P5, 0.0, d["L54"])
    S1 = P1 + rot(P2 - P1, 180.0 * DEG, 5.0)
    S2 = P2 + rot(P3 - P2, 30.0 * DEG, 10.0)
    S3 = P3 + np.array([0.0, 10.0])
    S4 = P4.copy()
    S5 = P5 + rot(P4 - P5, 45.0 * DEG, 15.0)
    pts = {"P1": P1, "P2": P2, "P3": P3, "P4": P4, "P5": P5, "P7": P7,
           "S1": S1, "S2": S2, "S3": S3, "S4": S4, "S5": S5}
    return pts, angle_of(P5, P4)


def mech_c_analogs(phi1, h=DEFAULT_H, links=C_LINKS):
    return fd_analogs(lambda p: mech_c_positions(p)[0], phi1, links, h)


def naive_c_lagrange_terms(phi1, M1=0.025, h=DEFAULT_H):
    """Reduced inertia J (kg m^2), (1/2) dJ/dphi, generalized force Q (N m)."""
    an = mech_c_analogs(phi1, h)
    J = 0.0
    halfdJ = 0.0
    Q = M1
    for s, (m, Js, link) in C_MASS.items():
        s1 = an["d1"][s] / 1000.0
        s2 = an["d2"][s] / 1000.0
        w1 = an["ang_d1"][link] if link else 0.0
        w2 = an["ang_d2"][link] if link else 0.0
        J += Js * w1 ** 2 + m * float(s1 @ s1)
        halfdJ += Js * w1 * w2 + m * float(s1 @ s2)
        Q += float(np.array([0.0, -m * G]) @ s1)
    return J, halfdJ, Q


# ---------------------------------------------------------------------------
# naive kinetostatics: one dense linear system
# ---------------------------------------------------------------------------


def _kinetostatics(bodies, joints, omega1, eps1, slides=(), drives=()):
    """Generic assembly.

    bodies: list of dicts with keys name, S (m), aS (m/s^2), vS (m/s), m, J,
            omega, eps, ext (list of (point m, force N)), crank (bool).
    joints: list of (name, first body or None for ground, second body,
            point (m)).  R = force of first on second.
    slides: list of (name, guide body or None for ground, slider body,
            direction angle rad): the guide pushes the slider with N along the
            direction turned +90 deg, at the slider's centre of mass, and turns
            it with the couple C; the guide takes -N and -C.  out[name] = (N, C).
    drives: list of (name, body, direction angle rad or None, point (m)): an
            input's drive from the ground on ``body``, a moment (None) or a
            force along the direction acting at ``point``.  out[name] = its value.
    """
    nb = len(bodies)
    nj = len(joints)
    ns = len(slides)
    nd = len(drives)
    nu = 2 * nj + 2 * ns + 1 + nd
    idx = {b["name"]: i for i, b in enumerate(bodies)}
    Amat = np.zeros((3 * nb, nu))
    rhs = np.zeros(3 * nb)
    F_all, M_all = {}, {}
    for b in bodies:
        i = idx[b["name"]]
        F = b["m"] * (np.array([0.0, -G]) - b["aS"])
        M = -b["J"] * b["eps"]
        for (pt, f) in b["ext"]:
            F = F + f
            M += cross(pt - b["S"], f)
        F_all[b["name"]] = F
        M_all[b["name"]] = M
        rhs[3 * i: 3 * i + 2] = -F
        rhs[3 * i + 2] = -M
        if b["crank"]:
            Amat[3 * i + 2, 2 * nj + 2 * ns] = 1.0
    for j, (_name, first, second, pt) in enumerate(joints):
        for body, sgn in ((first, -1.0), (second, 1.0)):
            if body is None:
                continue
            i = idx[body]
            r = pt - bodies[i]["S"]
            Amat[3 * i, 2 * j] += sgn
            Amat[3 * i + 1, 2 * j + 1] += sgn
            Amat[3 * i + 2, 2 * j] += -sgn * r[1]
            Amat[3 * i + 2, 2 * j + 1] += sgn * r[0]
    for k, (_name, guide, slider, theta) in enumerate(slides):
        n = np.array([-math.sin(theta), math.cos(theta)])
        at = bodies[idx[slider]]["S"]
        for body, sgn in ((guide, -1.0), (slider, 1.0)):
            if body is None:
                continue
            i = idx[body]
            r = at - bodies[i]["S"]
            Amat[3 * i, 2 * nj + 2 * k] += sgn * n[0]
            Amat[3 * i + 1, 2 * nj + 2 * k] += sgn * n[1]
            Amat[3 * i + 2, 2 * nj + 2 * k] += sgn * cross(r, n)
            Amat[3 * i + 2, 2 * nj + 2 * k + 1] += sgn
    for k, (_name, body, theta, pt) in enumerate(drives):
        i = idx[body]
        col = 2 * nj + 2 * ns + 1 + k
        if theta is None:
            Amat[3 * i + 2, col] += 1.0
        else:
            u = np.array([math.cos(theta), math.sin(theta)])
            Amat[3 * i, col] += u[0]
            Amat[3 * i + 1, col] += u[1]
            Amat[3 * i + 2, col] += cross(pt - bodies[i]["S"], u)
    x = np.linalg.solve(Amat, rhs)
    out = {name: x[2 * j: 2 * j + 2].copy() for j, (name, *_r) in enumerate(joints)}
    for k, (name, *_r) in enumerate(drives):
        out[name] = float(x[2 * nj + 2 * ns + 1 + k])
    for k, (name, *_r) in enumerate(slides):
        out[name] = x[2 * nj + 2 * k: 2 * nj + 2 * k + 2].copy()
    out["M_bal"] = float(x[2 * nj + 2 * ns])
    out["F"] = F_all
    out["M"] = M_all
    out["v_S"] = {b["name"]: b["vS"] for b in bodies}
    out["omega"] = {b["name"]: b["omega"] for b in bodies}
    out["omega1"] = omega1
    out["eps1"] = eps1
    return out


def virtual_power_residual(res):
    """M_bal*omega1 + sum(F . v_S + M*omega) and a scale for it."""
    total = res["M_bal"] * res["omega1"]
    scale = abs(total)
    for name in res["F"]:
        p1 = float(res["F"][name] @ res["v_S"][name])
        p2 = res["M"][name] * res["omega"][name]
        total += p1 + p2
        scale = max(scale, abs(p1), abs(p2))
    return total, scale


def naive_forces_b(phi1, omega1=-94.4, eps1=0.0, guess=None, h=DEFAULT_H):
    """Reactions R1..R7 (N; force of first-named body on second), M_bal (N m)
    of mechanism B at phi1, plus per-link F, M, v_S, omega.

    Joints: R1 ground->crank (P1), R2 crank->lead 2-3 (P2), R3 lead 2-3->
    ternary (P3), R4 ternary->lead 4-6 (P4), R5 ternary->rocker (P5),
    R6 ground->lead 4-6 (P6), R7 ground->rocker (P7).
    """
    an = mech_b_analogs(phi1, guess=guess, h=h, with_S=True,
                        links=["1_2", "2_3", "3_4", "6_4", "7_5"])
    link_of = {"crank": "1_2", "lead_2_3": "2_3", "ternary_3_4_5": "3_4",
               "lead_4_6": "6_4", "rocker_5_7_8": "7_5"}
    bodies = []
    for name, (_b, _t, _lS, _US, m, J) in B_MASS.items():
        s = "S_" + name
        lk = link_of[name]
        bodies.append(dict(
            name=name, m=m, J=J, ext=[], crank=(name == "crank"),
            S=an["pos"][s] / 1000.0,
            vS=an["d1"][s] / 1000.0 * omega1,
            aS=(an["d2"][s] * omega1 ** 2 + an["d1"][s] * eps1) / 1000.0,
            omega=an["ang_d1"][lk] * omega1,
            eps=an["ang_d2"][lk] * omega1 ** 2 + an["ang_d1"][lk] * eps1,
        ))
    P = {k: an["pos"][k] / 1000.0 for k in ("P1", "P2", "P3", "P4", "P5", "P6", "P7")}
    joints = [
        ("R1", None, "crank", P["P1"]),
        ("R2", "crank", "lead_2_3", P["P2"]),
        ("R3", "lead_2_3", "ternary_3_4_5", P["P3"]),
        ("R4", "ternary_3_4_5", "lead_4_6", P["P4"]),
        ("R5", "ternary_3_4_5", "rocker_5_7_8", P["P5"]),
        ("R6", None, "lead_4_6", P["P6"]),
        ("R7", None, "rocker_5_7_8", P["P7"]),
    ]
    out = _kinetostatics(bodies, joints, omega1, eps1)
    out["ab"] = an["ab"]
    return out


def naive_c_equilibrium(lo_deg=260.0, hi_deg=275.0):
    """The take-up's stable equilibrium (deg): Q = 0 without drive, by brentq on
    the finite-difference generalized force (DOMAIN.md section 10: 268.77 deg)."""
    from scipy.optimize import brentq
    q = lambda phi: naive_c_lagrange_terms(phi, M1=0.0)[2]  # noqa: E731
    return math.degrees(brentq(q, math.radians(lo_deg), math.radians(hi_deg), xtol=1e-14))


C_BODIES = {"S1": "crank", "S2": "rod", "S3": "needle bar", "S4": "block", "S5": "coulisse"}


def naive_forces_c(phi1, omega1=125.0, eps1=0.0, h=DEFAULT_H):
    """Reactions R1..R5 (N; force of first-named body on second), the slides'
    (N, C) and M_bal of the take-up C (DOMAIN.md section 7, no external load):
    R1 ground->crank (P1), R2 crank->rod (P2), R3 rod->needle bar (P3),
    R4 rod->block (P4), R5 ground->coulisse (P5); slide[needle bar] the frame's
    vertical guide on the needle bar, slide[block] the coulisse on the block
    (along P5->P4; the block turns with the coulisse)."""
    an = mech_c_analogs(phi1, h)
    bodies = []
    for s, (m, J, lk) in C_MASS.items():
        bodies.append(dict(
            name=C_BODIES[s], m=m, J=J, ext=[], crank=(s == "S1"),
            S=an["pos"][s] / 1000.0,
            vS=an["d1"][s] / 1000.0 * omega1,
            aS=(an["d2"][s] * omega1 ** 2 + an["d1"][s] * eps1) / 1000.0,
            omega=an["ang_d1"][lk] * omega1 if lk else 0.0,
            eps=an["ang_d2"][lk] * omega1 ** 2 + an["ang_d1"][lk] * eps1 if lk else 0.0,
        ))
    P = {k: an["pos"][k] / 1000.0 for k in ("P1", "P2", "P3", "P4", "P5")}
    joints = [
        ("R1", None, "crank", P["P1"]),
        ("R2", "crank", "rod", P["P2"]),
        ("R3", "rod", "needle bar", P["P3"]),
        ("R4", "rod", "block", P["P4"]),
        ("R5", None, "coulisse", P["P5"]),
    ]
    slides = [("slide[needle bar]", None, "needle bar", 90.0 * DEG),
              ("slide[block]", "coulisse", "block", an["ang"]["5_4"])]
    return _kinetostatics(bodies, joints, omega1, eps1, slides)


def naive_forces_d(phi1, omega1=60.0, eps1=0.0, h=DEFAULT_H):
    """Reactions R1..R4 (N; force of first-named body on second) and M_bal of
    the four-bar D.  R1 ground->crank (A), R2 crank->coupler (B),
    R3 coupler->rocker (C), R4 ground->rocker (D).  Load at E on the rocker:
    (0, -150*(1 + 0.2*sin(2*phi1))) N."""
    an = fd_analogs(_d_points_with_S, phi1, D_LINKS, h)
    link_of = {"crank": "1_2", "coupler": "2_3", "rocker": "4_3"}
    E = an["pos"]["P5"] / 1000.0
    fE = np.array([0.0, -150.0 * (1.0 + 0.2 * math.sin(2.0 * phi1))])
    bodies = []
    for name, (_b, _t, _lS, m, J) in D_MASS.items():
        s = "S_" + name
        lk = link_of[name]
        bodies.append(dict(
            name=name, m=m, J=J, crank=(name == "crank"),
            ext=[(E, fE)] if name == "rocker" else [],
            S=an["pos"][s] / 1000.0,
            vS=an["d1"][s] / 1000.0 * omega1,
            aS=(an["d2"][s] * omega1 ** 2 + an["d1"][s] * eps1) / 1000.0,
            omega=an["ang_d1"][lk] * omega1,
            eps=an["ang_d2"][lk] * omega1 ** 2 + an["ang_d1"][lk] * eps1,
        ))
    P = {k: an["pos"][k] / 1000.0 for k in ("P1", "P2", "P3", "P4")}
    joints = [
        ("R1", None, "crank", P["P1"]),
        ("R2", "crank", "coupler", P["P2"]),
        ("R3", "coupler", "rocker", P["P3"]),
        ("R4", None, "rocker", P["P4"]),
    ]
    return _kinetostatics(bodies, joints, omega1, eps1)


# ---------------------------------------------------------------------------
# dwell error, margin (DOMAIN.md section 9)
# ---------------------------------------------------------------------------


def naive_dwell_error(theta, delta_deg=150.0):
    """Brute force: w = round(Delta*n/360) intervals, w+1 cyclic samples, every
    start tried.  Returns (error, best_start_index): the first start of the
    smallest window range, divided by the full range.  (Comparing the ranges,
    not the quotients: two different ranges can round to one quotient, as
    5e-324 / 2 and 0 / 2 do, and the flatter window is the dwell.)"""
    theta = [float(t) for t in theta]
    n = len(theta)
    w = int(round(delta_deg * n / 360.0))
    full = max(theta) - min(theta)
    best, best_k = math.inf, -1
    for k in range(n):
        window = [theta[(k + j) % n] for j in range(w + 1)]
        r = max(window) - min(window)
        if r < best:
            best, best_k = r, k
    return best / full, best_k


def _unwrap_list(angles):
    out = [angles[0]]
    for a in angles[1:]:
        out.append(out[-1] + _wrap(a - out[-1]))
    return out


def mech_b_rocker_angles(n=720):
    phis = [-k * 2.0 * math.pi / n for k in range(n)]
    res = revolution(mech_b_positions, phis)
    return _unwrap_list([angle_of(p["P7"], p["P5"]) for p, _ab in res]), res


def mech_a_rocker_angles(n=720):
    phis = [-k * 2.0 * math.pi / n for k in range(n)]
    res = revolution(mech_a_positions, phis)
    return _unwrap_list([angle_of(p["P8"], p["P7"]) for p in res])


def naive_mech_b_dwell(n=720, delta_deg=150.0):
    theta, _ = mech_b_rocker_angles(n)
    return naive_dwell_error(theta, delta_deg)


@functools.lru_cache(maxsize=None)
def naive_mech_b_motion(n=360, delta_deg=150.0):
    """Mechanism B's output rocker over n positions (cached: several tests ask):
    (dwell error, index of the best window's first sample, stroke in mm =
    L78 * (max theta - min theta))."""
    theta, _ = mech_b_rocker_angles(n)
    err, k = naive_dwell_error(theta, delta_deg)
    return err, k, B_DATA["L78"] * (max(theta) - min(theta))


def naive_mech_a_dwell(n=720, delta_deg=150.0):
    return naive_dwell_error(mech_a_rocker_angles(n), delta_deg)


def _b_sq_closure(ab, phi1):
    _P2, _P3, P4, P5 = _b_closure_points(ab, phi1)
    d4 = P4 - B_DATA["P6"]
    d5 = P5 - B_DATA["P7"]
    return np.array([d4[0] ** 2 + d4[1] ** 2 - B_DATA["L46"] ** 2,
                     d5[0] ** 2 + d5[1] ** 2 - B_DATA["L57"] ** 2])


def naive_mech_b_margin(n=360):
    """min over phi1_k = -k*360/n of |det J| / (4 L23 L46 L57 max(L34, L35)),
    J the complex-step Jacobian of the squared-distance closure wrt (a, b).
    Returns (margin, phi1 of the minimum in rad)."""
    d = B_DATA
    phis = [-k * 2.0 * math.pi / n for k in range(n)]
    res = revolution(mech_b_positions, phis)
    scale = 4.0 * d["L23"] * d["L46"] * d["L57"] * max(d["L34"], d["L35"])
    best, best_phi = math.inf, None
    for phi, (_p, ab) in zip(phis, res):
        jac = _complex_step_jacobian(lambda z: _b_sq_closure(z, phi), np.array(ab))
        m = abs(np.linalg.det(jac)) / scale
        if m < best:
            best, best_phi = m, phi
    return best, best_phi


def naive_mech_b_peak(n=12, omega1=-94.4, eps1=0.0):
    """Largest |R_k| over joints and phi1_k = -k*360/n: (value N, joint, phi1 deg)."""
    phis = [-k * 2.0 * math.pi / n for k in range(n)]
    res = revolution(mech_b_positions, phis)
    best = (-1.0, None, None)
    for phi, (_p, ab) in zip(phis, res):
        f = naive_forces_b(phi, omega1, eps1, guess=ab)
        for k in range(1, 8):
            r = float(np.hypot(*f[f"R{k}"]))
            if r > best[0]:
                best = (r, f"R{k}", phi / DEG)
    return best


# ---------------------------------------------------------------------------
# Mechanisms with the slider dyads PRP and RPP: 30-digit solves
# ---------------------------------------------------------------------------
# The constraint equations of the whole mechanism (crank, RRR dyad, the slider
# dyad) are solved together by a plain Newton iteration in mpmath at MP_DPS
# digits, its Jacobian by forward differences at that precision; the analogs
# are 4th-order central differences of those solutions with a step of 1e-15
# rad (truncation ~1e-60, rounding ~1e-30 at MP_DPS digits).  The float start
# comes from solve_rrr (fsolve) and a least-squares solve of the guides'
# equations, which are linear in the slider point.  A guide line i: the points
# X with (X - G_i) . n_i = e_i, n_i its direction turned +90 deg.

MP_DPS = 60


def _mp_vec(x):
    return [mpmath.mpf(x[0]), mpmath.mpf(x[1])]


def _mp_newton(residual, x0):
    """Newton on residual(x) = 0 (lists of mpf) from x0; forward-difference
    Jacobian at MP_DPS digits.  Raises if the residual does not fall below
    1e-45 (relative to the unknowns' size)."""
    x = [mpmath.mpf(float(v)) for v in x0]
    n = len(x)
    h = mpmath.mpf(10) ** (-(MP_DPS // 2))
    for _ in range(30):
        f = residual(x)
        scale = max(mpmath.mpf(1), max(abs(v) for v in x))
        if max(abs(v) for v in f) < mpmath.mpf(10) ** (-(MP_DPS - 15)) * scale:
            return x
        jac = mpmath.matrix(n, n)
        for j in range(n):
            xh = list(x)
            xh[j] += h
            fh = residual(xh)
            for i in range(n):
                jac[i, j] = (fh[i] - f[i]) / h
        dx = mpmath.lu_solve(jac, mpmath.matrix(f))
        x = [x[i] - dx[i] for i in range(n)]
    raise ValueError("mp Newton did not converge")


def _unit(v):
    r = mpmath.sqrt(v[0] ** 2 + v[1] ** 2)
    return [v[0] / r, v[1] / r]


def _turn(u, a):
    """u turned by the angle a (mp)."""
    c, s = mpmath.cos(a), mpmath.sin(a)
    return [c * u[0] - s * u[1], s * u[0] + c * u[1]]


def _off_line(X, G, u, e):
    """(X - G) . n - e, n = u turned +90 deg: zero on the guide line."""
    return (X[0] - G[0]) * (-u[1]) + (X[1] - G[1]) * u[0] - e


def _line_guess(G1, u1, e1, G2, u2, e2):
    """Float least-squares point of two guide lines (a start for Newton)."""
    n1 = np.array([-u1[1], u1[0]], float)
    n2 = np.array([-u2[1], u2[0]], float)
    rhs = np.array([e1 + n1 @ np.asarray(G1, float), e2 + n2 @ np.asarray(G2, float)])
    return np.linalg.lstsq(np.array([n1, n2]), rhs, rcond=None)[0]


class SliderChain:
    """Crank P1-P2, then a four-bar dyad P2-P3-P4 (lengths L23, L43, mode W as
    solve_rrr) when ``fourbar``, then the slider dyad at P5:

    * ``kind = "PRP"``: P5 on guide 1 (through g1 along a1 from the rocker
      P4->P3 if ``g1_rocker``, else along a1 from the crank P1->P2 if
      ``g1_crank``, else at the absolute a1; offset e1) and on guide 2 (through
      the fixed point G2 at the absolute a2, offset e2);
    * ``kind = "RPP"``: the yoke point P5 on the guide (through g1 at a1, from
      the rocker if ``g1_rocker``; offset e1) and the crank tip P2 on the slot
      through P5 at ``slot`` from the guide, offset e_s: (P2 - P5) . n_s = e_s.

    ``extra(points)`` adds points computed from the solved ones (centres of
    mass).  d: dict of the data; angles in rad, lengths in mm."""

    def __init__(self, kind, d, extra=None):
        self.kind = kind
        self.d = d
        self.extra = extra

    def _crank(self, phi):
        d = self.d
        a = phi + d["phiM0"]
        return [d["L12"] * mpmath.cos(a), d["L12"] * mpmath.sin(a)]

    def _guide1(self, P2, C):
        d = self.d
        if d.get("g1_rocker"):
            G = _mp_vec(d["P4"])
            u = _turn(_unit([C[0] - G[0], C[1] - G[1]]), d["a1"])
        elif d.get("g1_crank"):
            G = [mpmath.mpf(0), mpmath.mpf(0)]
            u = _turn(_unit(P2), d["a1"])
        else:
            G = _mp_vec(d["G1"])
            u = [mpmath.cos(d["a1"]), mpmath.sin(d["a1"])]
        return G, u

    def _split(self, x):
        if self.d.get("fourbar"):
            return [x[0], x[1]], [x[2], x[3]]
        return None, [x[0], x[1]]

    def residual(self, x, phi):
        d = self.d
        P2 = self._crank(phi)
        C, B = self._split(x)
        out = []
        if C is not None:
            P4 = _mp_vec(d["P4"])
            out += [(C[0] - P2[0]) ** 2 + (C[1] - P2[1]) ** 2 - mpmath.mpf(d["L23"]) ** 2,
                    (C[0] - P4[0]) ** 2 + (C[1] - P4[1]) ** 2 - mpmath.mpf(d["L43"]) ** 2]
        G1, u1 = self._guide1(P2, C)
        out.append(_off_line(B, G1, u1, mpmath.mpf(d["e1"])))
        if self.kind == "PRP":
            u2 = [mpmath.cos(d["a2"]), mpmath.sin(d["a2"])]
            out.append(_off_line(B, _mp_vec(d["G2"]), u2, mpmath.mpf(d["e2"])))
        else:
            us = _turn(u1, d["slot"])
            out.append(_off_line(P2, B, us, mpmath.mpf(d["e_s"])))
        return out

    def guess(self, phi):
        """Float start: solve_rrr for P3, least squares for P5."""
        d = self.d
        P2 = d["L12"] * e(phi + d["phiM0"])
        x = []
        C = None
        if d.get("fourbar"):
            C = solve_rrr(P2, np.asarray(d["P4"], float), d["L23"], d["L43"], W=d["W"])
            x += list(C)
        with mpmath.workdps(20):
            G1, u1 = self._guide1(_mp_vec(P2), _mp_vec(C) if C is not None else None)
            G1, u1 = [float(v) for v in G1], [float(v) for v in u1]
            if self.kind == "PRP":
                a2 = float(d["a2"])
                B = _line_guess(G1, u1, d["e1"], d["G2"], (math.cos(a2), math.sin(a2)), d["e2"])
            else:
                us = [float(v) for v in _turn(u1, d["slot"])]
                # P2 on the slot through B: (B - P2) . n_s = -e_s
                B = _line_guess(G1, u1, d["e1"], P2, us, -d["e_s"])
        return x + list(B)

    def points(self, x, phi):
        d = self.d
        P2 = self._crank(phi)
        C, B = self._split(x)
        pts = {"P1": [mpmath.mpf(0), mpmath.mpf(0)], "P2": P2, "P5": B}
        if C is not None:
            pts["P3"] = C
            pts["P4"] = _mp_vec(d["P4"])
        if self.extra is not None:
            pts.update(self.extra(pts, d))
        return pts


def mp_analogs(chain, phi, links=(), h="1e-15"):
    """Positions, first and second analogs (float arrays) of every point of
    ``chain`` at phi (rad): {"pos": {name: (2,)}, "d1": ..., "d2": ...}, and
    the angle of every link "a_b" (Pa -> Pb) with its analogs ("ang",
    "ang_d1", "ang_d2"), differenced the same way."""
    with mpmath.workdps(MP_DPS):
        h = mpmath.mpf(h)
        phi = mpmath.mpf(phi)
        x0 = chain.guess(float(phi))
        x0 = _mp_newton(lambda x: chain.residual(x, phi), x0)
        sols = {}
        for k in (-2, -1, 0, 1, 2):
            p = phi + k * h
            x = x0 if k == 0 else _mp_newton(lambda x: chain.residual(x, p), x0)
            sols[k] = chain.points(x, p)
        out = {"pos": {}, "d1": {}, "d2": {}}
        for name in sols[0]:
            f = {k: sols[k][name] for k in sols}
            out["pos"][name] = np.array([float(v) for v in f[0]])
            out["d1"][name] = np.array([float((f[-2][i] - 8 * f[-1][i] + 8 * f[1][i] - f[2][i])
                                              / (12 * h)) for i in range(2)])
            out["d2"][name] = np.array([float((-f[-2][i] + 16 * f[-1][i] - 30 * f[0][i]
                                               + 16 * f[1][i] - f[2][i]) / (12 * h * h))
                                        for i in range(2)])
        out.update(ang={}, ang_d1={}, ang_d2={})
        for link in links:
            a, b = ("P" + q for q in link.split("_"))
            t = {k: mpmath.atan2(sols[k][b][1] - sols[k][a][1], sols[k][b][0] - sols[k][a][0])
                 for k in sols}
            for k in t:                 # unwrap about the centre (across +-pi)
                if t[k] - t[0] > mpmath.pi:
                    t[k] -= 2 * mpmath.pi
                elif t[k] - t[0] < -mpmath.pi:
                    t[k] += 2 * mpmath.pi
            out["ang"][link] = float(t[0])
            out["ang_d1"][link] = float((t[-2] - 8 * t[-1] + 8 * t[1] - t[2]) / (12 * h))
            out["ang_d2"][link] = float((-t[-2] + 16 * t[-1] - 30 * t[0] + 16 * t[1] - t[2])
                                        / (12 * h * h))
    return out


# mechanism E: the slotted rocker and slider of studies/slotted_rocker_prp.toml
E_DATA = dict(L12=15.0, phiM0=0.0, fourbar=True, P4=(38.0, 0.0), L23=41.0, L43=40.0, W=1,
              g1_rocker=True, a1=0.0, e1=0.0, G2=(38.0, 50.0), a2=0.0, e2=0.0)
E_LINKS = ["1_2", "2_3", "4_3"]
# body: (m kg, J_S kg m^2, angle link or None, joints), centres of mass in _e_com
E_MASS = {"crank AB": (0.4, 2e-5, "1_2"), "coupler BC": (0.6, 1e-4, "2_3"),
          "rocker DC": (0.9, 3.5e-4, "4_3"), "block": (0.03, 2e-6, "4_3"),
          "slider": (0.25, 0.0, None)}


def _mp_along(base, tip, length):
    u = _unit([tip[0] - base[0], tip[1] - base[1]])
    return [base[0] + length * u[0], base[1] + length * u[1]]


def _e_com(pts, d):
    return {"S[crank AB]": _mp_along(pts["P1"], pts["P2"], 5),
            "S[coupler BC]": _mp_along(pts["P2"], pts["P3"], mpmath.mpf("20.5")),
            "S[rocker DC]": _mp_along(pts["P4"], pts["P3"], 30),
            "S[block]": list(pts["P5"]),
            "S[slider]": [pts["P5"][0], pts["P5"][1] + 8]}


def naive_forces_e(phi1, omega1=60.0, eps1=0.0, d=E_DATA):
    """Reactions R1..R5 (N; first-named body on second), the slides' (N, C)
    and M_bal of mechanism E: R1 ground->crank (P1), R2 crank->coupler (P2),
    R3 coupler->rocker (P3), R4 ground->rocker (P4), R5 block->slider (P5);
    slide[block] the rocker's slot on the block, slide[slider] the frame's
    guide on the slider.  Load on the slider at P5: (-40 (1 + 0.5 cos phi1), 0)."""
    an = mp_analogs(SliderChain("PRP", d, _e_com), phi1, links=E_LINKS)
    f5 = np.array([-40.0 * (1.0 + 0.5 * math.cos(phi1)), 0.0])
    bodies = []
    for name, (m, J, lk) in E_MASS.items():
        s = f"S[{name}]"
        bodies.append(dict(
            name=name, m=m, J=J, crank=(name == "crank AB"),
            ext=[(an["pos"]["P5"] / 1000.0, f5)] if name == "slider" else [],
            S=an["pos"][s] / 1000.0, vS=an["d1"][s] / 1000.0 * omega1,
            aS=(an["d2"][s] * omega1 ** 2 + an["d1"][s] * eps1) / 1000.0,
            omega=an["ang_d1"][lk] * omega1 if lk else 0.0,
            eps=an["ang_d2"][lk] * omega1 ** 2 + an["ang_d1"][lk] * eps1 if lk else 0.0))
    P = {k: an["pos"][k] / 1000.0 for k in ("P1", "P2", "P3", "P4", "P5")}
    joints = [("R1", None, "crank AB", P["P1"]), ("R2", "crank AB", "coupler BC", P["P2"]),
              ("R3", "coupler BC", "rocker DC", P["P3"]), ("R4", None, "rocker DC", P["P4"]),
              ("R5", "block", "slider", P["P5"])]
    slides = [("slide[block]", "rocker DC", "block", an["ang"]["4_3"] + d["a1"]),
              ("slide[slider]", None, "slider", d["a2"])]
    return _kinetostatics(bodies, joints, omega1, eps1, slides)


# mechanism F: the Scotch yoke of studies/scotch_yoke_rpp.toml
F_DATA = dict(L12=12.0, phiM0=0.0, G1=(0.0, 0.0), a1=0.0, e1=0.0, slot=math.pi / 2, e_s=0.0)
F_MASS = {"crank": (0.3, 1.5e-5, "1_2"), "block": (0.02, 1e-6, None),
          "yoke": (0.35, 0.0, None)}


def _f_com(pts, d):
    return {"S[crank]": _mp_along(pts["P1"], pts["P2"], 3), "S[block]": list(pts["P2"]),
            "S[yoke]": [pts["P5"][0] + 40, pts["P5"][1]],
            "P4": [pts["P5"][0] + 80, pts["P5"][1]]}


def naive_forces_f(phi1, omega1=100.0, eps1=0.0, d=F_DATA):
    """Reactions R1 (ground->crank, P1), R2 (crank->block, P2), the slides
    (N, C) slide[block] (the yoke's slot on the block) and slide[yoke] (the
    frame on the yoke), M_bal of the Scotch yoke; its point P3 is this chain's
    P5.  Load on the yoke at P4: (-25 sign(sin phi1), -5) N."""
    an = mp_analogs(SliderChain("RPP", d, _f_com), phi1, links=["1_2"])
    f4 = np.array([-25.0 * np.sign(math.sin(phi1)), -5.0])
    bodies = []
    for name, (m, J, lk) in F_MASS.items():
        s = f"S[{name}]"
        bodies.append(dict(
            name=name, m=m, J=J, crank=(name == "crank"),
            ext=[(an["pos"]["P4"] / 1000.0, f4)] if name == "yoke" else [],
            S=an["pos"][s] / 1000.0, vS=an["d1"][s] / 1000.0 * omega1,
            aS=(an["d2"][s] * omega1 ** 2 + an["d1"][s] * eps1) / 1000.0,
            omega=an["ang_d1"][lk] * omega1 if lk else 0.0,
            eps=an["ang_d2"][lk] * omega1 ** 2 + an["ang_d1"][lk] * eps1 if lk else 0.0))
    joints = [("R1", None, "crank", an["pos"]["P1"] / 1000.0),
              ("R2", "crank", "block", an["pos"]["P2"] / 1000.0)]
    slides = [("slide[block]", "yoke", "block", d["a1"] + d["slot"]),
              ("slide[yoke]", None, "yoke", d["a1"])]
    return _kinetostatics(bodies, joints, omega1, eps1, slides)


# ---------------------------------------------------------------------------
# Mechanisms with inputs besides the crank: 60-digit solves
# ---------------------------------------------------------------------------
# The laws are written here again in mpmath from their definitions (the rise
# and return of a harmonic or cycloidal cam; the periodic cubic spline of a
# table from its own cyclic system for the knots' second derivatives, not from
# scipy), the mechanisms' closures are solved by _mp_newton and the analogs
# are the central differences of mp_analogs.

def mp_rise_return(phi, start, travel, phase, rise, cycloidal):
    """q(phi) of a rise by ``travel`` from ``start`` over ``rise`` rad of the
    cycle from ``phase``, returning over the rest of the cycle (mp)."""
    two_pi = 2 * mpmath.pi
    u = mpmath.fmod(phi - phase, two_pi)
    if u < 0:
        u += two_pi
    x = u / rise if u < rise else (two_pi - u) / (two_pi - rise)
    if cycloidal:
        f = x - mpmath.sin(two_pi * x) / two_pi
    else:
        f = (1 - mpmath.cos(mpmath.pi * x)) / 2
    return start + travel * f


class MpPeriodicSpline:
    """The periodic cubic spline through (t_i, y_i), i < n, closed by
    (t_0 + 2 pi, y_0): second derivatives M_i from the cyclic system
    h_{i-1} M_{i-1} + 2 (h_{i-1} + h_i) M_i + h_i M_{i+1}
        = 6 ((y_{i+1} - y_i) / h_i - (y_i - y_{i-1}) / h_{i-1})."""

    def __init__(self, t, y):
        with mpmath.workdps(MP_DPS):
            t = [mpmath.mpf(v) for v in t] + [mpmath.mpf(t[0]) + 2 * mpmath.pi]
            y = [mpmath.mpf(v) for v in y] + [mpmath.mpf(y[0])]
            n = len(t) - 1
            h = [t[i + 1] - t[i] for i in range(n)]
            A = mpmath.matrix(n, n)
            b = mpmath.matrix(n, 1)
            for i in range(n):
                hp, hi = h[i - 1], h[i]
                A[i, (i - 1) % n] += hp
                A[i, i] += 2 * (hp + hi)
                A[i, (i + 1) % n] += hi
                yp = y[i - 1] if i > 0 else y[n - 1]
                b[i] = 6 * ((y[i + 1] - y[i]) / hi - (y[i] - yp) / hp)
            m = mpmath.lu_solve(A, b)
            self.t, self.y, self.h = t, y, h
            self.M = [m[i] for i in range(n)] + [m[0]]

    def __call__(self, u):
        t, y, h, M = self.t, self.y, self.h, self.M
        two_pi = 2 * mpmath.pi
        u = t[0] + mpmath.fmod(u - t[0], two_pi)
        if u < t[0]:
            u += two_pi
        i = max(k for k in range(len(h)) if t[k] <= u)
        a, b_ = t[i + 1] - u, u - t[i]
        return (M[i] * a ** 3 / (6 * h[i]) + M[i + 1] * b_ ** 3 / (6 * h[i])
                + (y[i] / h[i] - M[i] * h[i] / 6) * a + (y[i + 1] / h[i] - M[i + 1] * h[i] / 6) * b_)


class InputChain:
    """The mechanisms of studies/feed_fivebar.toml (kind "fivebar"),
    studies/cam_rocker_input.toml ("cam_rocker") and
    studies/actuator_slider_input.toml ("actuator"), read from their
    definitions in ``d`` (angles rad, lengths mm):

    * fivebar: crank P1-P2 (L12), second crank P4-P5 (L45) at phase + ratio
      phi1, couplers P2-P3 (L23) and P5-P3 (L53) meeting above (mode W), the
      tooth P6 = P3 + L36 along P2->P3;
    * cam_rocker: rocker P4-P5 (L45) at the cycloidal law ``law`` (start,
      travel, phase, rise), P6 on the vertical line x = P7x joined to P5 by
      L56, above;
    * actuator: block P5 = P4 + s(phi1) (1, 0), s the spline through ``table``
      ((deg, mm) pairs); P3 joined to P5 by L53 and to P6 by L63 (mode W); the
      eye P7 = P3 + L37 along P6->P3."""

    def __init__(self, kind, d, extra=None):
        self.kind = kind
        self.d = d
        self.extra = extra
        if kind == "actuator":
            self.spline = MpPeriodicSpline([c * mpmath.pi / 180 for c, _ in d["table"]],
                                           [v for _, v in d["table"]])

    def driven(self, phi):
        """The points the crank and the input fix at phi, and the input's q."""
        d = self.d
        P2 = [d["L12"] * mpmath.cos(phi), d["L12"] * mpmath.sin(phi)]
        if self.kind == "fivebar":
            q = d["phase"] + d["ratio"] * phi
            P5 = [d["P4"][0] + d["L45"] * mpmath.cos(q), d["P4"][1] + d["L45"] * mpmath.sin(q)]
        elif self.kind == "cam_rocker":
            q = mp_rise_return(phi, *d["law"], cycloidal=True)
            P5 = [d["P4"][0] + d["L45"] * mpmath.cos(q), d["P4"][1] + d["L45"] * mpmath.sin(q)]
        else:
            q = self.spline(phi)
            P5 = [d["P4"][0] + q, mpmath.mpf(d["P4"][1])]
        return P2, P5, q

    def residual(self, x, phi):
        d = self.d
        P2, P5, _ = self.driven(phi)
        X = [x[0], x[1]]
        if self.kind == "fivebar":
            return [(X[0] - P2[0]) ** 2 + (X[1] - P2[1]) ** 2 - mpmath.mpf(d["L23"]) ** 2,
                    (X[0] - P5[0]) ** 2 + (X[1] - P5[1]) ** 2 - mpmath.mpf(d["L53"]) ** 2]
        if self.kind == "cam_rocker":
            return [X[0] - d["P7"][0],
                    (X[0] - P5[0]) ** 2 + (X[1] - P5[1]) ** 2 - mpmath.mpf(d["L56"]) ** 2]
        return [(X[0] - P5[0]) ** 2 + (X[1] - P5[1]) ** 2 - mpmath.mpf(d["L53"]) ** 2,
                (X[0] - d["P6"][0]) ** 2 + (X[1] - d["P6"][1]) ** 2 - mpmath.mpf(d["L63"]) ** 2]

    def guess(self, phi):
        d = self.d
        with mpmath.workdps(20):
            P2, P5, _ = self.driven(mpmath.mpf(phi))
            P2, P5 = np.array([float(v) for v in P2]), np.array([float(v) for v in P5])
        if self.kind == "fivebar":
            return list(solve_rrr(P2, P5, d["L23"], d["L53"], W=d["W"]))
        if self.kind == "cam_rocker":
            dx = d["P7"][0] - P5[0]
            return [d["P7"][0], P5[1] + math.sqrt(d["L56"] ** 2 - dx * dx)]
        return list(solve_rrr(P5, np.asarray(d["P6"], float), d["L53"], d["L63"], W=d["W"]))

    def points(self, x, phi):
        d = self.d
        P2, P5, q = self.driven(phi)
        X = [x[0], x[1]]
        pts = {"P1": [mpmath.mpf(0), mpmath.mpf(0)], "P2": P2, "P4": _mp_vec(d["P4"]),
               "P5": P5, "Q": [q, mpmath.mpf(0)]}
        if self.kind == "fivebar":
            pts["P3"] = X
            pts["P6"] = _mp_along(P2, X, mpmath.mpf(d["L23"]) + d["L36"])
        elif self.kind == "cam_rocker":
            pts["P6"] = X
        else:
            pts["P3"] = X
            pts["P6"] = _mp_vec(d["P6"])
            pts["P7"] = _mp_along(pts["P6"], X, mpmath.mpf(d["L63"]) + d["L37"])
        if self.extra is not None:
            pts.update(self.extra(pts, d))
        return pts


FIVEBAR_DATA = dict(L12=8.0, P4=(42.0, 0.0), L45=9.0, ratio=1, phase=math.pi / 2, L23=36.0,
                    L53=32.0, W=1, L36=15.0)
CAM_ROCKER_DATA = dict(L12=10.0, P4=(30.0, 0.0), L45=35.0, P7=(80.0, 0.0), L56=45.0,
                       law=(30 * DEG, 40 * DEG, 0.0, 150 * DEG))
ACTUATOR_DATA = dict(L12=10.0, P4=(0.0, -40.0), P6=(45.0, 0.0), L53=40.0, L63=30.0, W=-1,
                     L37=25.0, table=list(zip(range(0, 360, 30),
                                              (0.0, 0.0, 3.0, 12.0, 21.0, 24.0, 24.0, 24.0,
                                               19.0, 9.0, 2.0, 0.0))))


def _fivebar_com(pts, d):
    return {"S[main crank]": _mp_along(pts["P1"], pts["P2"], 2),
            "S[second crank]": _mp_along(pts["P4"], pts["P5"], 2),
            "S[feed bar]": _mp_along(pts["P2"], pts["P3"], 30),
            "S[link]": _mp_along(pts["P5"], pts["P3"], 16)}


def naive_forces_fivebar(phi1, omega1=100.0, eps1=0.0, d=FIVEBAR_DATA):
    """Reactions R1..R5 (R1 ground->main crank at P1, R2 main crank->feed bar
    at P2, R3 feed bar->link at P3, R4 ground->second crank at P4, R5 second
    crank->link at P5), the second crank's drive moment and M_bal of the main
    crank alone, with the second crank's q' for its share.  Load at P6 on the
    feed bar: (-20 (1 + cos phi1), 0) N."""
    an = mp_analogs(InputChain("fivebar", d, _fivebar_com), phi1,
                    links=["1_2", "4_5", "2_3", "5_3"])
    mass = {"main crank": (0.15, 1.5e-5, "1_2"), "second crank": (0.15, 1.5e-5, "4_5"),
            "feed bar": (0.12, 4e-5, "2_3"), "link": (0.05, 5e-6, "5_3")}
    f6 = np.array([-20.0 * (1.0 + math.cos(phi1)), 0.0])
    bodies = _bodies(an, mass, "main crank", omega1, eps1,
                     {"feed bar": [(an["pos"]["P6"] / 1000.0, f6)]})
    P = {k: an["pos"][k] / 1000.0 for k in ("P1", "P2", "P3", "P4", "P5")}
    joints = [("R1", None, "main crank", P["P1"]), ("R2", "main crank", "feed bar", P["P2"]),
              ("R3", "feed bar", "link", P["P3"]), ("R4", None, "second crank", P["P4"]),
              ("R5", "second crank", "link", P["P5"])]
    out = _kinetostatics(bodies, joints, omega1, eps1,
                         drives=[("second crank", "second crank", None, P["P4"])])
    out["q1"] = {"second crank": float(an["d1"]["Q"][0])}
    return out


def _bodies(an, mass, crank, omega1, eps1, ext):
    out = []
    for name, (m, J, lk) in mass.items():
        s = f"S[{name}]"
        out.append(dict(
            name=name, m=m, J=J, crank=(name == crank), ext=ext.get(name, []),
            S=an["pos"][s] / 1000.0, vS=an["d1"][s] / 1000.0 * omega1,
            aS=(an["d2"][s] * omega1 ** 2 + an["d1"][s] * eps1) / 1000.0,
            omega=an["ang_d1"][lk] * omega1 if lk else 0.0,
            eps=an["ang_d2"][lk] * omega1 ** 2 + an["ang_d1"][lk] * eps1 if lk else 0.0))
    return out


def _actuator_com(pts, d):
    return {"S[main shaft]": list(pts["P1"]), "S[block]": list(pts["P5"]),
            "S[link]": _mp_along(pts["P5"], pts["P3"], 20),
            "S[lever]": _mp_along(pts["P6"], pts["P3"], 25)}


def naive_forces_actuator(phi1, omega1=40.0, eps1=0.0, d=ACTUATOR_DATA):
    """Reactions R1 (ground->main shaft, P1), R3 (link->lever, P3), R5
    (block->link, P5), R6 (ground->lever, P6), the block's slide (N, C), the
    actuator's drive force (N, along +x) with its q' (m/rad) and the main
    shaft's own M_bal.  Load at P7 on the lever: (0, -8) N."""
    an = mp_analogs(InputChain("actuator", d, _actuator_com), phi1,
                    links=["1_2", "5_3", "6_3"])
    mass = {"main shaft": (0.5, 2e-4, "1_2"), "block": (0.15, 0.0, None),
            "link": (0.06, 1e-5, "5_3"), "lever": (0.1, 2.5e-5, "6_3")}
    bodies = _bodies(an, mass, "main shaft", omega1, eps1,
                     {"lever": [(an["pos"]["P7"] / 1000.0, np.array([0.0, -8.0]))]})
    P = {k: an["pos"][k] / 1000.0 for k in ("P1", "P3", "P5", "P6")}
    joints = [("R1", None, "main shaft", P["P1"]), ("R3", "link", "lever", P["P3"]),
              ("R5", "block", "link", P["P5"]), ("R6", None, "lever", P["P6"])]
    out = _kinetostatics(bodies, joints, omega1, eps1,
                         slides=[("slide[block]", None, "block", 0.0)],
                         drives=[("actuator", "block", 0.0, P["P5"])])
    out["q1"] = {"actuator": float(an["d1"]["Q"][0]) / 1000.0}
    return out


# ---------------------------------------------------------------------------
# the class III group with a slider in place of lead 5-7
# (studies/ov7_class3_slider.toml)
# ---------------------------------------------------------------------------
# Unknowns: the points P3, P4, P5 themselves (and the guide rocker's tip P9
# where the guide turns), never the angles a, b of the kernel; equations: the
# plain squared distances of lead 2-3, the ternary triangle's three sides and
# lead 4-6, and P5 on the block's line, (P5 - G) . n = e (n: the guide's
# direction turned +90 deg).  The branch is the one continued from the study's
# start (a0, b0) in float steps of at most 1 deg (fsolve), each refused if the
# Jacobian's determinant changes sign or a point moves more than 10 mm (another
# branch), then polished at MP_DPS digits.

SLIDER_DATA = dict(
    P1=(0.0, 0.0), P6=(195.0, 226.0), G=(46.0, 533.0), L12=50.0, phiM0=173.0 * DEG,
    L23=272.5, L34=81.0, L45=104.5, L35=174.0, L46=104.5, ga=171.0 * DEG, e=261.0,
    start=(44.0 * DEG, 128.8 * DEG), phi_start=0.0, orientation=1,
    # a guide that turns: None, or (P10, L29, L109, W): the rocker P10-P9 of the RRR
    # dyad P2-P9-P10 (solve_rrr's mode W), the guide's direction that of P10->P9 + ga
    rocker=None)
SLIDER_LINKS = ["1_2", "2_3", "3_4", "6_4"]
# body: (base, tip, lS mm, US rad, m kg, J_S kg m^2, angle link or None)
SLIDER_MASS = {
    "crank 1-2": ("P1", "P2", 26.21, 0.0, 0.91, 0.001189631, "1_2"),
    "lead 2-3": ("P2", "P3", 122.54, 0.0, 0.73, 0.008434849, "2_3"),
    "ternary 3-4-5": ("P3", "P4", 85.01, 15.13 * DEG, 0.91, 0.004456758, "3_4"),
    "lead 4-6": ("P6", "P4", 40.99, 0.0, 1.64, 0.005376871, "6_4"),
    "block": ("P5", None, 20.0, 261.0 * DEG, 0.6, 0.0, None),
}
SLIDER_LOAD = (19.754, -3.129)        # N on the block at P5 (a return spring)


class Class3SliderChain:
    """Crank P1-P2, optionally the guide's rocker P9 (RRR from P2 about P10),
    then the class III group with a slider: the residuals of ``mp_analogs``'s
    chain protocol, and a float continuation for its start (``guess``: call it
    at crank angles in the order of a walk).  ``extra(points, d)`` adds points
    (centres of mass)."""

    MAX_MOVE = 10.0           # mm: the most a point moves in one step of the walk

    def __init__(self, d, extra=None, max_step=DEG):
        self.d = d
        self.extra = extra
        self.max_step = max_step
        self._at = None       # (phi, x) of the last float solution

    def _equations(self, x, phi, num, cos, sin, sqrt):
        d = self.d
        P2 = [num(d["L12"]) * cos(phi + num(d["phiM0"])), num(d["L12"]) * sin(phi + num(d["phiM0"]))]
        P3, P4, P5 = x[0:2], x[2:4], x[4:6]
        P6 = [num(d["P6"][0]), num(d["P6"][1])]
        G = [num(d["G"][0]), num(d["G"][1])]

        def sq(p, q):
            return (p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2

        L = {k: num(d[k]) for k in ("L23", "L34", "L45", "L35", "L46")}
        out = [sq(P3, P2) - L["L23"] ** 2, sq(P4, P3) - L["L34"] ** 2,
               sq(P5, P3) - L["L35"] ** 2, sq(P5, P4) - L["L45"] ** 2,
               sq(P4, P6) - L["L46"] ** 2]
        ga = num(d["ga"])
        if d["rocker"] is None:
            u = [cos(ga), sin(ga)]
        else:
            P10, L29, L109, _W = d["rocker"]
            P9, P10 = x[6:8], [num(P10[0]), num(P10[1])]
            out += [sq(P9, P2) - num(L29) ** 2, sq(P9, P10) - num(L109) ** 2]
            r = sqrt(sq(P9, P10))
            v = [(P9[0] - P10[0]) / r, (P9[1] - P10[1]) / r]
            u = [cos(ga) * v[0] - sin(ga) * v[1], sin(ga) * v[0] + cos(ga) * v[1]]
        out.append((P5[0] - G[0]) * (-u[1]) + (P5[1] - G[1]) * u[0] - num(d["e"]))
        return out

    def residual(self, x, phi):
        return self._equations(x, phi, mpmath.mpf, mpmath.cos, mpmath.sin, mpmath.sqrt)

    def _float(self, x, phi):
        return np.array(self._equations(list(x), phi, float, np.cos, np.sin, np.sqrt))

    def _start(self):
        """The float solution at phi_start from the declared (a0, b0)."""
        d = self.d
        phi = d["phi_start"]
        P2 = d["L12"] * e(phi + d["phiM0"])
        a0, b0 = d["start"]
        u = d["orientation"] * math.acos((d["L34"] ** 2 + d["L35"] ** 2 - d["L45"] ** 2)
                                         / (2.0 * d["L34"] * d["L35"]))
        P3 = P2 + d["L23"] * e(a0)
        x = list(P3) + list(P3 + d["L34"] * e(b0)) + list(P3 + d["L35"] * e(b0 + u))
        if d["rocker"] is not None:
            P10, L29, L109, W = d["rocker"]
            x += list(solve_rrr(P2, np.asarray(P10, float), L29, L109, W=W))
        return phi, _solve(lambda z: self._float(z, phi), np.array(x))

    def _det(self, x, phi):
        return np.linalg.det(_complex_step_jacobian(lambda z: self._float(z, phi), x))

    def guess(self, phi):
        """The float solution at ``phi``, walked from the last one in steps of
        at most ``max_step``; ValueError where a step finds no solution or
        another branch (the walk stays at its last solution)."""
        at, x = self._at if self._at is not None else self._start()
        n = max(1, int(math.ceil(abs(phi - at) / self.max_step - 1e-12)))
        sign = np.sign(self._det(x, at))
        for k in range(1, n + 1):
            p = at + (phi - at) * k / n
            y = _solve(lambda z: self._float(z, p), x)
            if np.sign(self._det(y, p)) != sign or np.abs(y - x).max() > self.MAX_MOVE:
                raise ValueError(f"another branch at {p!r} rad")
            x = y
            self._at = (p, x)
        return list(x)

    def points(self, x, phi):
        d = self.d
        P2 = [d["L12"] * mpmath.cos(phi + d["phiM0"]), d["L12"] * mpmath.sin(phi + d["phiM0"])]
        pts = {"P1": _mp_vec(d["P1"]), "P2": P2, "P3": x[0:2], "P4": x[2:4], "P5": x[4:6],
               "P6": _mp_vec(d["P6"])}
        if d["rocker"] is not None:
            pts["P9"] = x[6:8]
        if self.extra is not None:
            pts.update(self.extra(pts, d))
        return pts

    def fold(self, phi_guess, x_guess):
        """A crank angle where the group folds (the 6x6 Jacobian of its point
        equations, analytic, is singular) and its points, by Newton at MP_DPS
        digits on the closure and det = 0 from the float guesses.  Fixed guide
        only."""
        d = self.d
        assert d["rocker"] is None

        def jac(x, phi):
            P2 = [d["L12"] * mpmath.cos(phi + d["phiM0"]), d["L12"] * mpmath.sin(phi + d["phiM0"])]
            P3, P4, P5 = x[0:2], x[2:4], x[4:6]
            P6 = _mp_vec(d["P6"])
            n = [-mpmath.sin(d["ga"]), mpmath.cos(d["ga"])]
            J = mpmath.matrix(6, 6)
            rows = [(0, P3, P2, None), (2, P4, P3, 0), (4, P5, P3, 0), (4, P5, P4, 2),
                    (2, P4, P6, None)]
            for i, (c, p, q, cq) in enumerate(rows):
                for k in range(2):
                    J[i, c + k] = 2 * (p[k] - q[k])
                    if cq is not None:
                        J[i, cq + k] = -2 * (p[k] - q[k])
            J[5, 4], J[5, 5] = n[0], n[1]
            return J

        def residual(z):
            x, phi = z[:6], z[6]
            return self.residual(x, phi) + [mpmath.det(jac(x, phi)) * mpmath.mpf(10) ** -12]

        with mpmath.workdps(MP_DPS):
            z = _mp_newton(residual, list(x_guess) + [phi_guess])
            return z[6], z[:6]


def _mp_com(pts, base, tip, lS, US):
    """base + rot(base->tip, US, lS); a translating body (tip None): base + lS e(US)."""
    P = pts[base]
    u = [mpmath.cos(US), mpmath.sin(US)] if tip is None else \
        _turn(_unit([pts[tip][0] - P[0], pts[tip][1] - P[1]]), US)
    return [P[0] + lS * u[0], P[1] + lS * u[1]]


def _slider_com(pts, d):
    return {f"S[{name}]": _mp_com(pts, base, tip, mpmath.mpf(lS), mpmath.mpf(US))
            for name, (base, tip, lS, US, *_r) in SLIDER_MASS.items()}


def naive_forces_slider(chain, phi1, omega1, eps1):
    """Reactions R1..R6 (N; first-named body on second), the block's slide
    (N, C) and M_bal of studies/ov7_class3_slider.toml at phi1, on ``chain``'s
    60-digit kinematics (a Class3SliderChain with extra=_slider_com; call it
    in the order of a walk): R1 ground->crank (P1), R2 crank->lead 2-3 (P2), R3
    lead->ternary (P3), R4 ternary->lead 4-6 (P4), R5 ternary->block (P5), R6
    ground->lead 4-6 (P6); slide[block] the frame's guide on the block."""
    an = mp_analogs(chain, phi1, links=SLIDER_LINKS)
    bodies = []
    for name, (_b, _t, _l, _u, m, J, lk) in SLIDER_MASS.items():
        s = f"S[{name}]"
        bodies.append(dict(
            name=name, m=m, J=J, crank=(name == "crank 1-2"),
            ext=[(an["pos"]["P5"] / 1000.0, np.array(SLIDER_LOAD))] if name == "block" else [],
            S=an["pos"][s] / 1000.0, vS=an["d1"][s] / 1000.0 * omega1,
            aS=(an["d2"][s] * omega1 ** 2 + an["d1"][s] * eps1) / 1000.0,
            omega=an["ang_d1"][lk] * omega1 if lk else 0.0,
            eps=an["ang_d2"][lk] * omega1 ** 2 + an["ang_d1"][lk] * eps1 if lk else 0.0))
    P = {k: an["pos"][k] / 1000.0 for k in ("P1", "P2", "P3", "P4", "P5", "P6")}
    joints = [("R1", None, "crank 1-2", P["P1"]), ("R2", "crank 1-2", "lead 2-3", P["P2"]),
              ("R3", "lead 2-3", "ternary 3-4-5", P["P3"]),
              ("R4", "ternary 3-4-5", "lead 4-6", P["P4"]),
              ("R5", "ternary 3-4-5", "block", P["P5"]), ("R6", None, "lead 4-6", P["P6"])]
    slides = [("slide[block]", None, "block", chain.d["ga"])]
    return _kinetostatics(bodies, joints, omega1, eps1, slides)


# ---------------------------------------------------------------------------
# kinetostatics with Coulomb friction in the revolute joints (issue 52)
# ---------------------------------------------------------------------------


def naive_friction_newton(bodies, joints, f, radius, omega1, tol=1e-14, max_iter=60):
    """The whole nonlinear force system of ``_kinetostatics``'s ``bodies`` and
    ``joints`` (no slides) with a Coulomb friction moment f r_j |R_j| at every
    joint j against the rotation of its second body relative to its first
    (``radius``: per joint, m; the bodies' ``omega`` gives the senses), solved
    by a plain dense Newton iteration from zero with the complex-step Jacobian
    of the residual.  Returns {joint: R, "M_bal": ..., joint + " friction":
    the friction moment on the second body}."""
    nb, nj = len(bodies), len(joints)
    idx = {b["name"]: i for i, b in enumerate(bodies)}
    omega = {b["name"]: b["omega"] for b in bodies}
    sense = []
    for _name, first, second, _pt in joints:
        w = omega[second] - (omega[first] if first is not None else 0.0)
        sense.append(float(np.sign(w)))

    def loads(b):
        F = b["m"] * (np.array([0.0, -G]) - b["aS"])
        M = -b["J"] * b["eps"]
        for (pt, fe) in b["ext"]:
            F = F + fe
            M += cross(pt - b["S"], fe)
        return F, M

    def residual(x):
        res = [None] * (3 * nb)
        for b in bodies:
            i = idx[b["name"]]
            F, M = loads(b)
            res[3 * i], res[3 * i + 1], res[3 * i + 2] = F[0], F[1], M
            if b["crank"]:
                res[3 * i + 2] = res[3 * i + 2] + x[2 * nj]
        for j, (_name, first, second, pt) in enumerate(joints):
            R = np.array([x[2 * j], x[2 * j + 1]])
            mf = -sense[j] * f * radius[j] * np.sqrt(R[0] ** 2 + R[1] ** 2)
            for body, sgn in ((first, -1.0), (second, 1.0)):
                if body is None:
                    continue
                i = idx[body]
                r = pt - bodies[i]["S"]
                res[3 * i] = res[3 * i] + sgn * R[0]
                res[3 * i + 1] = res[3 * i + 1] + sgn * R[1]
                res[3 * i + 2] = res[3 * i + 2] + sgn * (cross(r, R) + mf)
        return np.array(res)

    x = np.zeros(2 * nj + 1)
    for _ in range(max_iter):
        step = np.linalg.solve(_complex_step_jacobian(residual, x), -np.real(residual(x)))
        x = x + step
        if np.abs(step).max() <= tol * np.abs(x).max():
            break
    else:
        raise ValueError("the friction Newton iteration did not converge")
    out = {"M_bal": float(x[2 * nj])}
    for j, (name, *_r) in enumerate(joints):
        R = x[2 * j: 2 * j + 2]
        out[name] = R.copy()
        out[name + " friction"] = -sense[j] * f * radius[j] * math.hypot(R[0], R[1])
    return out
