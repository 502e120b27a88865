"""Kinetostatics: joint reactions and the balancing moment, per crank position.

Unknowns: (Rx, Ry) of every revolute joint, (N, C) of every prismatic pair
(normal force and couple), and the balancing moment M_bal on the crank.
Equations: force and moment equilibrium of every moving link, with gravity,
inertia forces -m a_S, inertia moments -J_S eps and external loads.  One
small dense system per position, solved by Gaussian elimination with partial
pivoting in preallocated work arrays (no allocation, no exceptions).

Conventions: revolute joint j between bodies p = jb[j, 0] (-1: ground) and
q = jb[j, 1]; R_j is the force p exerts on q.  Prismatic pair s: the guide
p = sb[s, 0] exerts N n + couple C on the slider q = sb[s, 1], acting at the
slider's centre of mass; n = guide direction turned +90 deg.  Lengths in the
position arrays are mm; forces N, moments N*m.
"""

import math

import numpy as np
from numba import njit

from .config import JIT, JIT_ALLOC
from .geometry import angle_analogs

MM = 1e-3


@njit(**JIT)
def gauss_solve(a, b, n):
    """Solve a[:n, :n] x = b[:n] in place (x returned in b).  False if singular."""
    for c in range(n):
        p = c
        best = abs(a[c, c])
        for r in range(c + 1, n):
            v = abs(a[r, c])
            if v > best:
                best = v
                p = r
        if not (best > 0.0):
            return False
        if p != c:
            for k in range(c, n):
                t = a[c, k]
                a[c, k] = a[p, k]
                a[p, k] = t
            t = b[c]
            b[c] = b[p]
            b[p] = t
        inv = 1.0 / a[c, c]
        for r in range(c + 1, n):
            f = a[r, c] * inv
            if f != 0.0:
                for k in range(c + 1, n):
                    a[r, k] -= f * a[c, k]
                b[r] -= f * b[c]
    for c in range(n - 1, -1, -1):
        s = b[c]
        for k in range(c + 1, n):
            s -= a[c, k] * b[k]
        b[c] = s / a[c, c]
    return True


@njit(**JIT_ALLOC)
def force_work(nb, nj, ns):
    """Work arrays of ``kinetostatics`` for nb bodies, nj joints, ns slides:
    (work_a, work_b, loads_out, r_out, slide_out); allocate once per candidate.
    A generated ``forces_at`` takes ns = slides + inputs: an input's drive has
    a row of slide_out after the slides' (``pipeline.compiler.force_equations``)."""
    return (np.empty((3 * nb, 3 * nb)), np.empty(3 * nb), np.empty((nb, 3)), np.empty((nj, 2)),
            np.empty((ns, 2)))


@njit(**JIT)
def body_motion(pos, d1, d2, turn_a, turn_b, omega1, eps1):
    """Angular velocity and acceleration of a body turning with link a->b (0 if a < 0)."""
    if turn_a < 0:
        return 0.0, 0.0
    _, th1, th2 = angle_analogs(pos[turn_b, 0] - pos[turn_a, 0], pos[turn_b, 1] - pos[turn_a, 1],
                                d1[turn_b, 0] - d1[turn_a, 0], d1[turn_b, 1] - d1[turn_a, 1],
                                d2[turn_b, 0] - d2[turn_a, 0], d2[turn_b, 1] - d2[turn_a, 1])
    return th1 * omega1, th2 * omega1 * omega1 + th1 * eps1


@njit(**JIT)
def applied_loads(pos, d1, d2, omega1, eps1, gravity, par, body_com, body_turn, body_mass_off,
                  load_body, load_point, loads_k, out):
    """Applied plus inertia loads of every body reduced to its centre of mass:
    out[i] = (Fx, Fy, M) in N, N*m.  External forces at a point P add the
    moment (P - S) x F."""
    for i in range(body_com.shape[0]):
        s = body_com[i]
        m = par[body_mass_off[i]]
        j = par[body_mass_off[i] + 1]
        ax = (d2[s, 0] * omega1 * omega1 + d1[s, 0] * eps1) * MM
        ay = (d2[s, 1] * omega1 * omega1 + d1[s, 1] * eps1) * MM
        _, eps = body_motion(pos, d1, d2, body_turn[i, 0], body_turn[i, 1], omega1, eps1)
        out[i, 0] = -m * ax
        out[i, 1] = -m * gravity - m * ay
        out[i, 2] = -j * eps
    for k in range(load_body.shape[0]):
        i = load_body[k]
        fx = loads_k[k, 0]
        fy = loads_k[k, 1]
        out[i, 0] += fx
        out[i, 1] += fy
        out[i, 2] += loads_k[k, 2]
        p = load_point[k]
        if p >= 0:
            s = body_com[i]
            out[i, 2] += ((pos[p, 0] - pos[s, 0]) * fy - (pos[p, 1] - pos[s, 1]) * fx) * MM


@njit(**JIT)
def equilibrium_residual(pos, d1, d2, m_bal, loads, body_com, body_turn):
    """The virtual-power residual of one position's kinetostatics, relative:
    |M_bal + sum over bodies (F . S' + M phi')| / the largest |term| (M_bal,
    each body's F . S' and M phi'), with (F, M) = ``loads`` (the applied and
    inertia loads at each centre of mass, N and N*m, as ``applied_loads``
    writes them), S' the centre's velocity analog (mm, so * MM) and phi' the
    body's angle analog (0 for a body that does not turn).  This is
    M_bal omega1 + sum (F . v_S + M omega) over the largest power term, every
    term divided by omega1: the same ratio, and defined at omega1 = 0 too.
    0 where every term is exactly 0 (the sum is then exactly 0: nothing is
    loaded or nothing moves); NaN if any term is."""
    total = m_bal
    scale = abs(m_bal)
    for i in range(body_com.shape[0]):
        s = body_com[i]
        pf = (loads[i, 0] * d1[s, 0] + loads[i, 1] * d1[s, 1]) * MM
        w, _ = body_motion(pos, d1, d2, body_turn[i, 0], body_turn[i, 1], 1.0, 0.0)
        pm = loads[i, 2] * w
        total += pf + pm
        scale = max(scale, abs(pf), abs(pm))
    if not math.isfinite(total):
        return math.nan
    return abs(total) / scale if scale > 0.0 else 0.0


@njit(**JIT)
def shaking(pos, d1, d2, omega1, eps1, par, body_com, body_turn, body_mass_off, ref):
    """The shaking force and moment at one position: what the moving bodies'
    inertia puts on the frame, gravity and external loads apart.  Returns
    (Fx, Fy, M): F = sum over bodies of -m a_S [N], the rate of change of the
    total momentum sum m v_S with its sign turned; M = sum of -J_S eps + (S - O)
    x (-m a_S) [N*m] about the fixed point O = pos[ref] (the crank's pivot), the
    rate of change of the angular momentum about O, sum J_S omega + (S - O) x
    m v_S, with its sign turned.  a_S = S'' omega1^2 + S' eps1 (mm analogs, so
    * MM), eps the body's angular acceleration (0 for a body that does not turn)."""
    fx = 0.0
    fy = 0.0
    mz = 0.0
    ox = pos[ref, 0]
    oy = pos[ref, 1]
    for i in range(body_com.shape[0]):
        s = body_com[i]
        m = par[body_mass_off[i]]
        j = par[body_mass_off[i] + 1]
        gx = -m * (d2[s, 0] * omega1 * omega1 + d1[s, 0] * eps1) * MM
        gy = -m * (d2[s, 1] * omega1 * omega1 + d1[s, 1] * eps1) * MM
        _, eps = body_motion(pos, d1, d2, body_turn[i, 0], body_turn[i, 1], omega1, eps1)
        fx += gx
        fy += gy
        mz += -j * eps + ((pos[s, 0] - ox) * gy - (pos[s, 1] - oy) * gx) * MM
    return fx, fy, mz


@njit(**JIT)
def _add_force(a, row_body, col, fx_coef, fy_coef, lever_x, lever_y):
    """Unknown force (fx_coef, fy_coef) * x[col] on a body at lever (P - S) [m]."""
    r = 3 * row_body
    a[r, col] += fx_coef
    a[r + 1, col] += fy_coef
    a[r + 2, col] += lever_x * fy_coef - lever_y * fx_coef


@njit(**JIT)
def slide_direction(pos, slide_dir, slide_angle, k):
    """The angle [rad] of slide ``k``'s direction u (its guide link's angle plus
    the slide's angle, or the slide's fixed angle)."""
    if slide_dir[k, 0] >= 0:
        a = slide_dir[k, 0]
        b = slide_dir[k, 1]
        return math.atan2(pos[b, 1] - pos[a, 1], pos[b, 0] - pos[a, 0]) + slide_angle[k]
    return slide_angle[k]


@njit(**JIT)
def assemble_forces(pos, d1, d2, omega1, eps1, gravity, par, body_com, body_turn, body_mass_off,
                    joint_point, joint_bodies, slide_bodies, slide_dir, slide_angle, crank_body,
                    load_body, load_point, loads_k, work_a, work_b, loads_out):
    """The kinetostatic system of one position, work_a[:n, :n] x = work_b[:n]
    (n = 3 bodies): the columns (Rx, Ry) per joint, (N, C) per slide, then
    M_bal; the rows the x, y force and the moment balance of every body about
    its centre of mass (work_b: minus its applied and inertia loads, which
    loads_out keeps).  Returns the column of M_bal (the system is square
    where it is n - 1)."""
    nb = body_com.shape[0]
    nj = joint_point.shape[0]
    ns = slide_bodies.shape[0]
    n = 3 * nb
    for r in range(n):
        work_b[r] = 0.0
        for c in range(n):
            work_a[r, c] = 0.0
    applied_loads(pos, d1, d2, omega1, eps1, gravity, par, body_com, body_turn, body_mass_off,
                  load_body, load_point, loads_k, loads_out)
    for i in range(nb):
        work_b[3 * i] = -loads_out[i, 0]
        work_b[3 * i + 1] = -loads_out[i, 1]
        work_b[3 * i + 2] = -loads_out[i, 2]
    for j in range(nj):
        p = joint_point[j]
        for side in range(2):
            b = joint_bodies[j, side]
            if b < 0:
                continue
            sgn = 1.0 if side == 1 else -1.0
            s = body_com[b]
            lx = (pos[p, 0] - pos[s, 0]) * MM
            ly = (pos[p, 1] - pos[s, 1]) * MM
            _add_force(work_a, b, 2 * j, sgn, 0.0, lx, ly)
            _add_force(work_a, b, 2 * j + 1, 0.0, sgn, lx, ly)
    for k in range(ns):
        q = slide_bodies[k, 1]
        sq = body_com[q]
        th = slide_direction(pos, slide_dir, slide_angle, k)
        nx = -math.sin(th)
        ny = math.cos(th)
        col = 2 * nj + 2 * k
        for side in range(2):
            b = slide_bodies[k, side]
            if b < 0:
                continue
            sgn = 1.0 if side == 1 else -1.0
            lx = (pos[sq, 0] - pos[body_com[b], 0]) * MM
            ly = (pos[sq, 1] - pos[body_com[b], 1]) * MM
            _add_force(work_a, b, col, sgn * nx, sgn * ny, lx, ly)
            work_a[3 * b + 2, col + 1] += sgn
    col_m = 2 * nj + 2 * ns
    if crank_body >= 0 and col_m < n:
        work_a[3 * crank_body + 2, col_m] = 1.0
    return col_m


@njit(**JIT)
def kinetostatics(pos, d1, d2, omega1, eps1, gravity, par, body_com, body_turn, body_mass_off,
                  joint_point, joint_bodies, slide_bodies, slide_dir, slide_angle, crank_body,
                  load_body, load_point, loads_k, work_a, work_b, loads_out, r_out, slide_out):
    """Reactions at one position.  Writes r_out (n_joints, 2) [N], slide_out
    (n_slides, 2) = (N [N], C [N*m]), loads_out (n_bodies, 3); returns M_bal
    [N*m] (NaN, with NaN reactions, if the system is singular or the
    kinematics is NaN)."""
    nj = joint_point.shape[0]
    ns = slide_bodies.shape[0]
    n = 3 * body_com.shape[0]
    col_m = assemble_forces(pos, d1, d2, omega1, eps1, gravity, par, body_com, body_turn,
                            body_mass_off, joint_point, joint_bodies, slide_bodies, slide_dir,
                            slide_angle, crank_body, load_body, load_point, loads_k, work_a,
                            work_b, loads_out)
    ok = col_m + 1 == n and gauss_solve(work_a, work_b, n)
    for j in range(nj):
        r_out[j, 0] = work_b[2 * j] if ok else math.nan
        r_out[j, 1] = work_b[2 * j + 1] if ok else math.nan
    for k in range(ns):
        slide_out[k, 0] = work_b[2 * nj + 2 * k] if ok else math.nan
        slide_out[k, 1] = work_b[2 * nj + 2 * k + 1] if ok else math.nan
    return work_b[col_m] if ok else math.nan
