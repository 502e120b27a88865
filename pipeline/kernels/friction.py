"""Kinetostatics with Coulomb friction in the joints, per crank position.

The frictionless system of ``kernels.forces.assemble_forces``, A x = b, with
the friction loads added to the bodies: G(x) = A x - b + L(x) = 0.

* Revolute joint j between bodies p and q (R_j: the force of p on q): a
  moment f_r r_j |R_j| on q against the rotation of q relative to p, and its
  opposite on p (r_j the pin's radius, m).
* Prismatic pair k (the guide p, the slider q): a force f_s |N_f| on q along
  the slide's direction u, against the sliding of q relative to p, on the
  line of the guide through the slider's centre of mass S, and its opposite
  on p at S; |N_f| = |N|, or max(|N|, 2000 |C| / l) for a block of length l
  [mm] bearing on its guide at its two ends (``model.friction``).

The direction of each friction load is the kinematics' (the sign of the
relative velocity analog times omega1): L is then piecewise linear in the
normal forces and smooth in |R|, and Newton's method from the frictionless
solution converges in a few steps.  At a relative speed of exactly zero the
friction is zero (the joint sticks).

Self-locking: the friction-inclusive system is solvable for any load only
while det(dG/dx) has the sign of det(A) (at f = 0 their ratio is 1; it falls
to 0 as the drive needed grows without bound).  A position where the ratio
is not positive, or where Newton does not converge, is FRICTION_LOCK, with
the joint or slide (index nj + k) whose friction alone takes the ratio
lowest.
"""

import math

from numba import njit

from .calls import unliteral
from .config import FRICTION_LOCK, JIT, OK
from .forces import MM, assemble_forces, body_motion, gauss_solve, slide_direction


@njit(inline='always', **JIT)
def _relative_turn(pos, d1, d2, body_turn, joint_bodies, j):
    """(first, second) analog of the turn of revolute joint j's second body
    against its first (a body that does not turn, or the ground: 0)."""
    w1 = 0.0
    w2 = 0.0
    for side in range(2):
        b = joint_bodies[j, side]
        if b >= 0:
            wb1, wb2 = body_motion(pos, d1, d2, body_turn[b, 0], body_turn[b, 1], 1.0, 0.0)
            w1 += wb1 if side == 1 else -wb1
            w2 += wb2 if side == 1 else -wb2
    return w1, w2


@njit(**JIT)
def relative_speeds(pos, d1, d2, body_com, body_turn, joint_bodies, slide_bodies, slide_dir,
                    slide_angle, out):
    """The relative speed analogs: out[j] (rad/rad) of body q against body p
    at revolute joint j; out[nj + k] (mm/rad) the sliding of the slider's
    centre of mass S along the slide's direction u against the guide's point
    at S (v_G + omega_G x (S - G), G the guide's centre of mass)."""
    nj = joint_bodies.shape[0]
    for j in range(nj):
        out[j] = _relative_turn(pos, d1, d2, body_turn, joint_bodies, j)[0]
    for k in range(slide_bodies.shape[0]):
        s = body_com[slide_bodies[k, 1]]
        vx = d1[s, 0]
        vy = d1[s, 1]
        g = slide_bodies[k, 0]
        if g >= 0:
            c = body_com[g]
            wg, _ = body_motion(pos, d1, d2, body_turn[g, 0], body_turn[g, 1], 1.0, 0.0)
            vx -= d1[c, 0] - wg * (pos[s, 1] - pos[c, 1])
            vy -= d1[c, 1] + wg * (pos[s, 0] - pos[c, 0])
        th = slide_direction(pos, slide_dir, slide_angle, k)
        out[nj + k] = vx * math.cos(th) + vy * math.sin(th)


@njit(**JIT)
def relative_speed_slopes(pos, d1, d2, body_com, body_turn, joint_bodies, slide_bodies,
                          slide_dir, slide_angle, out):
    """The derivatives by the crank angle of ``relative_speeds``' analogs (from
    the second analogs): out[j] (rad/rad^2) at revolute joint j, out[nj + k]
    (mm/rad^2) of slide k (the guide's turn and the direction's included)."""
    nj = joint_bodies.shape[0]
    for j in range(nj):
        out[j] = _relative_turn(pos, d1, d2, body_turn, joint_bodies, j)[1]
    for k in range(slide_bodies.shape[0]):
        s = body_com[slide_bodies[k, 1]]
        ax = d1[s, 0]                   # a = S' - G' - w_G perp(S - G): the relative velocity
        ay = d1[s, 1]
        bx = d2[s, 0]                   # a'
        by = d2[s, 1]
        g = slide_bodies[k, 0]
        if g >= 0:
            c = body_com[g]
            wg, wg2 = body_motion(pos, d1, d2, body_turn[g, 0], body_turn[g, 1], 1.0, 0.0)
            rx = pos[s, 0] - pos[c, 0]
            ry = pos[s, 1] - pos[c, 1]
            vx = d1[s, 0] - d1[c, 0]
            vy = d1[s, 1] - d1[c, 1]
            ax = vx + wg * ry
            ay = vy - wg * rx
            bx = d2[s, 0] - d2[c, 0] + wg2 * ry + wg * vy
            by = d2[s, 1] - d2[c, 1] - wg2 * rx - wg * vx
        th = slide_direction(pos, slide_dir, slide_angle, k)
        turn = 0.0                      # the direction's own angle analog
        if slide_dir[k, 0] >= 0:
            turn, _ = body_motion(pos, d1, d2, slide_dir[k, 0], slide_dir[k, 1], 1.0, 0.0)
        ux = math.cos(th)
        uy = math.sin(th)
        out[nj + k] = bx * ux + by * uy + turn * (ay * ux - ax * uy)


@njit(**JIT)
def _sense(analog, omega1):
    """The direction of a relative motion: +1, -1, or 0 at rest."""
    v = analog * omega1
    return 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)


@njit(**JIT)
def slide_branch(n, c, block):
    """A slide's branch of |N_f| (``model.friction``) at its normal force N and
    couple C: sign(N) (1 where N = 0) on |N|, 2 sign(C) on the edge loads
    2000 |C| / l.  ``add_friction`` holds a crank motion's regime to it where
    ``sense`` carries it after the joints and slides (a slide's friction has a
    kink where N changes its sign or the branch changes: a switch of its own)."""
    if block > 0.0 and 2000.0 * abs(c) / block > abs(n):
        return 2.0 if c > 0.0 else -2.0
    return -1.0 if n < 0.0 else 1.0


@njit(**JIT)
def add_friction(x, only, pos, body_com, joint_bodies, slide_bodies, slide_dir, slide_angle,
                 f_rev, radius, f_slide, block, sense, jac, res, friction_out):
    """Add the friction loads at the unknowns ``x`` to the residual ``res`` and
    their derivatives to ``jac`` (every joint and slide, or the element
    ``only`` alone where it is >= 0); friction_out[e]: the friction moment
    [N*m] on a joint's second body, the friction force [N] along u on a
    slider."""
    nj = joint_bodies.shape[0]
    for j in range(nj):
        if only >= 0 and only != j:
            continue
        rx = x[2 * j]
        ry = x[2 * j + 1]
        mag = math.hypot(rx, ry)
        c = -sense[j] * f_rev * radius[j]          # the moment on q is c |R|
        friction_out[j] = c * mag
        dx = c * rx / mag if mag > 0.0 else 0.0
        dy = c * ry / mag if mag > 0.0 else 0.0
        for side in range(2):
            b = joint_bodies[j, side]
            if b < 0:
                continue
            sgn = 1.0 if side == 1 else -1.0
            res[3 * b + 2] += sgn * c * mag
            jac[3 * b + 2, 2 * j] += sgn * dx
            jac[3 * b + 2, 2 * j + 1] += sgn * dy
    for k in range(slide_bodies.shape[0]):
        e = nj + k
        if only >= 0 and only != e:
            continue
        cn = 2 * nj + 2 * k
        n = x[cn]
        cc = x[cn + 1]
        # a slide's branch (``slide_branch``): as given where sense holds one (a crank
        # motion's regime), else its own at x
        ns = slide_bodies.shape[0]
        code = sense[e + ns] if sense.shape[0] > e + ns else 0.0
        own = code == 0.0
        if own:
            code = slide_branch(n, cc, block[k])
        if abs(code) == 1.0:        # |N| = code N (continued past N = 0 where given)
            mag = code * n
            dn = 0.0 if own and n == 0.0 else code
            dc = 0.0
        else:                       # wedged, the edge loads: |N_f| = 2000 (code / 2) C / l
            mag = 0.5 * code * 2000.0 * cc / block[k]
            dn = 0.0
            dc = 0.5 * code * 2000.0 / block[k]
        c = -sense[e] * f_slide                    # the force on the slider: c |N_f| u
        friction_out[e] = c * mag
        th = slide_direction(pos, slide_dir, slide_angle, k)
        ux = math.cos(th)
        uy = math.sin(th)
        s = body_com[slide_bodies[k, 1]]
        for side in range(2):
            b = slide_bodies[k, side]
            if b < 0:
                continue
            sgn = 1.0 if side == 1 else -1.0
            lx = (pos[s, 0] - pos[body_com[b], 0]) * MM
            ly = (pos[s, 1] - pos[body_com[b], 1]) * MM
            arm = lx * uy - ly * ux                # (S - S_b) x u
            for r, coef in ((3 * b, ux), (3 * b + 1, uy), (3 * b + 2, arm)):
                res[r] += sgn * c * coef * mag
                jac[r, cn] += sgn * c * coef * dn
                jac[r, cn + 1] += sgn * c * coef * dc


@njit(**JIT)
def determinant(a, n):
    """det(a[:n, :n]) by elimination with partial pivoting (``a`` destroyed)."""
    det = 1.0
    for c in range(n):
        p = c
        best = abs(a[c, c])
        for r in range(c + 1, n):
            if abs(a[r, c]) > best:
                best = abs(a[r, c])
                p = r
        if not (best > 0.0):
            return 0.0
        if p != c:
            det = -det
            for k in range(c, n):
                t = a[c, k]
                a[c, k] = a[p, k]
                a[p, k] = t
        det *= a[c, c]
        inv = 1.0 / a[c, c]
        for r in range(c + 1, n):
            f = a[r, c] * inv
            if f != 0.0:
                for k in range(c + 1, n):
                    a[r, k] -= f * a[c, k]
    return det


@njit(**JIT)
def _residual(a0, b0, x, n, jac, res):
    """res = A x - b, jac = A."""
    for r in range(n):
        s = -b0[r]
        for c in range(n):
            s += a0[r, c] * x[c]
            jac[r, c] = a0[r, c]
        res[r] = s


@njit(**JIT)
def _lock_ratio(a0, x, n, only, pos, body_com, joint_bodies, slide_bodies, slide_dir,
                slide_angle, f_rev, radius, f_slide, block, sense, jac, res, friction_out,
                det_a):
    """det(dG/dx) / det(A) at ``x`` with the friction of every element (only
    = -1) or of one element alone."""
    for r in range(n):
        res[r] = 0.0
        for c in range(n):
            jac[r, c] = a0[r, c]
    add_friction(x, only, pos, body_com, joint_bodies, slide_bodies, slide_dir, slide_angle,
                 f_rev, radius, f_slide, block, sense, jac, res, friction_out)
    return determinant(jac, n) / det_a


@njit(**JIT)
def friction_forces(pos, d1, d2, omega1, eps1, gravity, par, body_com, body_turn, body_mass_off,
                    joint_point, joint_bodies, slide_bodies, slide_dir, slide_angle, crank_body,
                    load_body, load_point, loads_k, f_rev, radius, f_slide, block, rel_tol,
                    max_iter, a0, b0, jac, res, x, sense, loads_out, r_out, slide_out,
                    friction_out, speed_out, found, keep_sense):
    """Reactions with friction at one position (``kernels.forces.kinetostatics``'s
    r_out, slide_out and loads_out), per joint and slide the friction load
    (``add_friction``) and the relative speed analog (``relative_speeds``).
    found[0:4] = (status, M_bal [N*m], the locking element or -1, Newton's
    iterations).  Newton stops where its step is at most ``rel_tol`` times the
    largest unknown, or the residual of every equation at most ``rel_tol``
    times the sum of its terms' magnitudes (the friction's terms are then
    within it too).  NaN with OK where the frictionless system has no
    solution (NaN kinematics or a singular system: as without friction);
    NaN with FRICTION_LOCK where the friction locks or does not converge.
    Work arrays: a0, jac (n, n), b0, res, x (n), sense (joints + slides):
    the direction of each friction load, from the relative motion (the sign
    of its speed analog times omega1), or as given (``keep_sense``: a crank
    motion's regime, ``kernels.dynamics``)."""
    nj = joint_point.shape[0]
    ns = slide_bodies.shape[0]
    ne = nj + ns
    n = 3 * body_com.shape[0]
    for j in range(nj):
        r_out[j, 0] = r_out[j, 1] = math.nan
    for k in range(ns):
        slide_out[k, 0] = slide_out[k, 1] = math.nan
    found[0] = OK
    found[1] = math.nan
    found[2] = -1.0
    found[3] = 0.0
    relative_speeds(pos, d1, d2, body_com, body_turn, joint_bodies, slide_bodies, slide_dir,
                    slide_angle, speed_out)
    for e in range(ne):
        friction_out[e] = math.nan
        if not keep_sense:
            sense[e] = _sense(speed_out[e], omega1)
    if not keep_sense:
        for k in range(ne, sense.shape[0]):     # the slides' branches: their own, found below
            sense[k] = 0.0
    col_m = assemble_forces(pos, d1, d2, omega1, eps1, gravity, par, body_com, body_turn,
                            body_mass_off, joint_point, joint_bodies, slide_bodies, slide_dir,
                            slide_angle, crank_body, load_body, load_point, loads_k, a0, b0,
                            loads_out)
    if col_m + 1 != n:
        return
    for r in range(n):          # the frictionless solution: Newton's start
        x[r] = b0[r]
        for c in range(n):
            jac[r, c] = a0[r, c]
    if not gauss_solve(jac, x, n):
        return
    converged = False
    for it in range(1, max_iter + 1):
        _residual(a0, b0, x, n, jac, res)
        add_friction(x, -1, pos, body_com, joint_bodies, slide_bodies, slide_dir, slide_angle,
                     f_rev, radius, f_slide, block, sense, jac, res, friction_out)
        for r in range(n):
            res[r] = -res[r]
        found[3] = it
        if not gauss_solve(jac, res, n):
            break
        step = 0.0
        size = 0.0
        for r in range(n):
            x[r] += res[r]
            step = max(step, abs(res[r]))
            size = max(size, abs(x[r]))
        if not math.isfinite(step + size):
            break
        if step <= rel_tol * size:
            converged = True
            break
        # near a lock the system is ill-conditioned and the steps stall at its
        # rounding: converged where the residual is within rel_tol of its terms
        _residual(a0, b0, x, n, jac, res)
        add_friction(x, -1, pos, body_com, joint_bodies, slide_bodies, slide_dir, slide_angle,
                     f_rev, radius, f_slide, block, sense, jac, res, friction_out)
        worst = 0.0
        for r in range(n):
            terms = abs(b0[r])
            for c in range(n):
                terms += abs(a0[r, c] * x[c])
            worst = max(worst, abs(res[r]) / terms if terms > 0.0 else abs(res[r]))
        if worst <= rel_tol:
            converged = True
            break
    # the friction loads at the solution (and det(dG/dx) there)
    for r in range(n):
        for c in range(n):
            jac[r, c] = a0[r, c]
    det_a = determinant(jac, n)
    ratio = math.nan
    if converged:
        ratio = _lock_ratio(a0, x, n, -1, pos, body_com, joint_bodies, slide_bodies, slide_dir,
                            slide_angle, f_rev, radius, f_slide, block, sense, jac, res,
                            friction_out, det_a)
    if not (ratio > 0.0):
        # the element whose friction alone takes the ratio lowest
        worst = math.inf
        for e in range(ne):
            if sense[e] == 0.0:
                continue
            r_e = _lock_ratio(a0, x, n, e, pos, body_com, joint_bodies, slide_bodies,
                              slide_dir, slide_angle, f_rev, radius, f_slide, block, sense, jac,
                              res, friction_out, det_a)
            if r_e < worst:
                worst = r_e
                found[2] = e
        for e in range(ne):
            friction_out[e] = math.nan
        found[0] = FRICTION_LOCK
        return
    for j in range(nj):
        r_out[j, 0] = x[2 * j]
        r_out[j, 1] = x[2 * j + 1]
    for k in range(ns):
        slide_out[k, 0] = x[2 * nj + 2 * k]
        slide_out[k, 1] = x[2 * nj + 2 * k + 1]
        if not keep_sense and sense.shape[0] > ne + k:
            sense[ne + k] = slide_branch(slide_out[k, 0], slide_out[k, 1], block[k])
    found[1] = x[col_m]


@njit(**JIT)
def friction_revolution(phis, pos, d1, d2, omega1, eps1, gravity, par, body_com, body_turn,
                        body_mass_off, joint_point, joint_bodies, slide_bodies, slide_dir,
                        slide_angle, crank_body, load_body, load_point, loads, f_rev, radius,
                        f_slide, block, pin_area, rel_tol, max_iter, a0, b0, jac, res, x, sense,
                        loads_out, r_out, slide_out, friction_out, speed_out, found, out):
    """A sweep candidate's friction metrics over the revolution's positions
    (``friction_forces`` at each, the definitions of ``solve.friction``):
    out[0:9] = (status, mean loss [W], peak p*v over the revolute joints
    [MPa*m/s], peak |R| [N], its joint, its crank angle [rad], peak |M_bal|
    [N*m], the first locked position (-1: none), its locking element).  The
    peaks are the largest of the positions (NaN and inf take them, as the
    sweep's own); ``pin_area``: d l per joint [mm^2].  Stops at the first
    position that locks (FRICTION_LOCK)."""
    n = pos.shape[0]
    nj = joint_point.shape[0]
    ne = nj + slide_bodies.shape[0]
    out[0] = OK
    for i in range(1, 9):
        out[i] = math.nan
    out[7] = -1.0
    out[8] = -1.0
    total = 0.0
    peak_pv = -1.0
    peak_r = -1.0
    peak_j = -1.0
    peak_phi = math.nan
    peak_m = -1.0
    for k in range(n):
        friction_forces(pos[k], d1[k], d2[k], omega1, eps1, gravity, par, body_com, body_turn,
                        body_mass_off, joint_point, joint_bodies, slide_bodies, slide_dir,
                        slide_angle, crank_body, load_body, load_point, loads[k], f_rev, radius,
                        f_slide, block, rel_tol, max_iter, a0, b0, jac, res, x, sense,
                        loads_out, r_out, slide_out, friction_out, speed_out, found,
                        unliteral(False))
        if found[0] != OK:
            out[0] = found[0]
            out[7] = k
            out[8] = found[2]
            return
        for e in range(ne):
            unit = 1.0 if e < nj else 1e-3          # mm/rad -> m/rad on a slide
            total += -friction_out[e] * speed_out[e] * unit * omega1
        for j in range(nj):
            r = math.hypot(r_out[j, 0], r_out[j, 1])
            if r > peak_r or not math.isfinite(r):
                peak_r = r
                peak_j = j
                peak_phi = phis[k]
            pv = (r / pin_area[j]) * (abs(speed_out[j] * omega1) * radius[j])
            if pv > peak_pv or not math.isfinite(pv):
                peak_pv = pv
        m = abs(found[1])
        if m > peak_m or not math.isfinite(m):
            peak_m = m
    out[1] = total / n + 0.0
    out[2] = peak_pv if nj > 0 else math.nan
    out[3] = peak_r if nj > 0 else math.nan
    out[4] = peak_j if nj > 0 else math.nan
    out[5] = peak_phi
    out[6] = peak_m
