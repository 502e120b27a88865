"""Baselines for the throughput table: what the project's compiled kernels
compute, written again without numba, once in plain NumPy (vectorized over
candidates) and once in pure Python (loops, ``math``, lists).

The code is independent of ``pipeline.kernels``: it reads numbers from the
project's parameter rows (``fourbar_params`` and ``class3_rows`` pick the
columns by name) and nothing else, and solves the equations of DOMAIN.md
sections 2, 3, 5, 6, 8 and 9 on its own:

* four-bar (mechanism D): closed form, circle intersection with the RRR
  convention of section 2 (W = +1 is the open configuration);
* class III group (mechanism B): Newton on (a, b) with the analytic 2x2
  Jacobian, step limited to 0.5 rad, continuation along the revolution
  (secant predictor from the last step; steps of at most 2 deg, a step whose
  Newton fails or that jumps branch is halved, down to 1e-5 of that), then
  the exact first and second analogs from the same Jacobian applied to the
  differentiated closure equations.  The NumPy walk solves every candidate
  at once; the few that still need halved steps in an interval (at most
  ``STRAGGLERS``) finish it in the scalar code, where NumPy's per-call cost
  on tiny arrays would dominate;
* sweep (section 9): positions over the revolution (failure = impossible
  ternary triangle, Newton not converging, branch jump, singular position, or
  a revolution that does not close on its start), singularity margin, rocker
  swing -> stroke, dwell error by the sliding-window definition; then, for the
  candidates meeting the stroke and margin constraints only, the analogs and
  the kinetostatics of section 6 as one dense 15x15 linear system per
  position (numpy.linalg.solve batched over candidates and positions in the
  NumPy version, Gaussian elimination in lists in the pure-Python one) ->
  peak joint reaction.

The numeric settings are the project's defaults (Newton residual 1e-12 of the
longer lead, 50 iterations, 0.5 rad step limit, singular below 1e-9, jump
above 0.1 rad, closure to 1e-7 rad, 2 deg continuation steps halved down to
1e-5 of that) so that both sides accept and reject the same candidates.  Status codes are numbered like the project's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

OK, NO_ASSEMBLY, NEWTON_MAXITER, SINGULAR, BRANCH_JUMP, BAD_GEOMETRY = 0, 1, 2, 3, 4, 5

NEWTON_TOL = 1e-12      # closure residual as a distance, relative to the longer lead
NEWTON_ITERS = 50
NEWTON_STEP = 0.5       # rad, largest Newton step
SINGULAR_TOL = 1e-9     # normalised |det J| below this: a toggle position
JUMP_TOL = 0.1          # rad, largest Newton correction of a predicted step
CLOSE_TOL = 1e-7        # rad, the revolution must close on its start
MAX_STEP = math.radians(2.0)    # largest continuation step, rad
MIN_STEP = MAX_STEP * 1e-5      # a failing step is halved down to this
STRAGGLERS = 16         # NumPy walk: this few candidates still stepping go on in scalar code
MM = 1e-3
TWO_PI = 2.0 * math.pi

# mechanism B's moving bodies (DOMAIN.md section 5), in the order of the
# equations: name, base point of the centre of mass, the link the body turns with
BODIES_B = ("crank 1-2", "lead 2-3", "ternary 3-4-5", "lead 4-6", "rocker 5-7-8")
# joints: (point, body exerting the reaction (-1 ground), body receiving it)
JOINTS_B = (("P1", -1, 0), ("P2", 0, 1), ("P3", 1, 2), ("P4", 2, 3), ("P5", 2, 4),
            ("P6", -1, 3), ("P7", -1, 4))
POINTS_B = ("P2", "P3", "P4", "P5", "P8")


# ============================================================== inputs
def fourbar_params(plan, pars):
    """Baseline inputs (n, 5) = (crank AB, coupler BC, rocker DC, ground AD,
    arm DE) from parameter rows of mechanism D's plan; A = (0, 0), D = (AD, 0),
    phiM0 = 0 and E on DC extended are checked, not assumed."""
    col = lambda name: np.asarray(pars)[:, plan.param(name)]
    for name in ("P1.x", "P1.y", "P4.y", "crank.phiM0", "Attach[2].angle"):
        if np.any(col(name) != 0.0):
            raise ValueError(f"four-bar baseline: expects {name} = 0")
    return np.ascontiguousarray(np.stack([col("crank.length"), col("RRR[1].L_AB"),
                                          col("RRR[1].L_CB"), col("P4.x"),
                                          col("Attach[2].length")], axis=1))


def class3_rows(plan, pars):
    """Baseline inputs for mechanism B: a dict of named columns (n,) taken from
    parameter rows of the project's plan (with the mass data when the plan has
    bodies).  Angles in rad, lengths mm, masses kg, J_S kg*m^2."""
    pars = np.asarray(pars, dtype=np.float64)
    col = lambda name: np.ascontiguousarray(pars[:, plan.param(name)])
    out = {k: col(n) for k, n in (
        ("P1x", "P1.x"), ("P1y", "P1.y"), ("P6x", "P6.x"), ("P6y", "P6.y"), ("P7x", "P7.x"),
        ("P7y", "P7.y"), ("L12", "crank.length"), ("phiM0", "crank.phiM0"),
        ("L23", "triad.L23"), ("L34", "triad.L34"), ("L45", "triad.L45"), ("L35", "triad.L35"),
        ("L46", "triad.L46"), ("L57", "triad.L57"), ("orientation", "triad.orientation"),
        ("a0", "triad.a0"), ("b0", "triad.b0"), ("phi_start", "triad.phi_start"),
        ("U578", "output arm.angle"), ("L78", "output arm.length"))}
    if plan.body_names:
        for i, body in enumerate(BODIES_B):
            out[f"m{i}"] = col(f"{body}.mass")
            out[f"J{i}"] = col(f"{body}.J_S")
            out[f"lS{i}"] = col(f"S[{body}].length")
            out[f"US{i}"] = col(f"S[{body}].angle")
    return out


@dataclass(frozen=True)
class SweepSetup:
    """The sweep's constants (DOMAIN.md section 9) the baselines need."""
    dwell_w: int                  # window length in intervals
    stroke_radius: float          # L78, mm
    stroke_bounds: tuple          # (lo, hi) mm
    margin_min: float
    omega1: float                 # rad/s
    eps1: float = 0.0
    gravity: float = 9.81
    forces: bool = True           # run the force stage (peak reaction)


def _closing_angle(phis):
    """The end of the revolution the grid ``phis`` samples (start + rot * 2 pi)."""
    return float(phis[0]) + (TWO_PI if phis[-1] >= phis[0] else -TWO_PI)


# ============================================================== four-bar, NumPy
def fourbar_positions_numpy(params, phis, w=1):
    """Positions of B, C, E for every candidate and crank angle: array
    (n_candidates, n_phi, 3, 2), NaN where the dyad cannot be assembled.

    B = A + AB e(phi); C from the circles |C - B| = BC, |C - D| = DC: with
    r = B - D, U = arccos((|r|^2 + DC^2 - BC^2) / (2 |r| DC)), the direction
    D->C is that of r turned by -w U; E = D + DE e(angle of D->C).
    """
    p = np.asarray(params, dtype=np.float64)
    phis = np.asarray(phis, dtype=np.float64)[None, :]
    l1, l2, l3, l0, le = (p[:, k, None] for k in range(5))
    bx = l1 * np.cos(phis)
    by = l1 * np.sin(phis)
    rx = bx - l0
    ry = by
    d2 = rx * rx + ry * ry
    with np.errstate(invalid="ignore", divide="ignore"):
        u = np.arccos((d2 + l3 * l3 - l2 * l2) / (2.0 * np.sqrt(d2) * l3))
    th = np.arctan2(ry, rx) - w * u
    c = np.cos(th)
    s = np.sin(th)
    out = np.empty((p.shape[0], phis.shape[1], 3, 2))
    out[:, :, 0, 0] = bx
    out[:, :, 0, 1] = by
    out[:, :, 1, 0] = l0 + l3 * c
    out[:, :, 1, 1] = l3 * s
    out[:, :, 2, 0] = l0 + le * c
    out[:, :, 2, 1] = le * s
    return out


# ============================================================== four-bar, pure Python
def fourbar_positions_python(params, phis, w=1):
    """The same as ``fourbar_positions_numpy`` with loops and ``math``:
    a list (candidates) of lists (positions) of ((Bx, By), (Cx, Cy), (Ex, Ey))."""
    rows = params.tolist() if hasattr(params, "tolist") else list(params)
    angles = [float(f) for f in phis]
    nan = math.nan
    out = []
    for l1, l2, l3, l0, le in rows:
        rev = []
        for phi in angles:
            bx = l1 * math.cos(phi)
            by = l1 * math.sin(phi)
            rx = bx - l0
            ry = by
            d2 = rx * rx + ry * ry
            arg = (d2 + l3 * l3 - l2 * l2) / (2.0 * math.sqrt(d2) * l3) if d2 > 0.0 else nan
            if not -1.0 <= arg <= 1.0:
                rev.append(((bx, by), (nan, nan), (nan, nan)))
                continue
            th = math.atan2(ry, rx) - w * math.acos(arg)
            c = math.cos(th)
            s = math.sin(th)
            rev.append(((bx, by), (l0 + l3 * c, l3 * s), (l0 + le * c, le * s)))
        out.append(rev)
    return out


# ============================================================== class III, NumPy
def _ternary_numpy(r):
    """U435 (signed by the orientation), NaN where the ternary triangle cannot exist."""
    l34, l45, l35 = r["L34"], r["L45"], r["L35"]
    ok = ((l34 > 0) & (l45 > 0) & (l35 > 0) & (l45 < l34 + l35) & (l34 < l45 + l35)
          & (l35 < l34 + l45) & (r["L23"] > 0) & (r["L46"] > 0) & (r["L57"] > 0))
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.clip((l34 * l34 + l35 * l35 - l45 * l45) / (2.0 * l34 * l35), -1.0, 1.0)
    return np.where(ok, r["orientation"] * np.arccos(c), np.nan)


def _residuals_numpy(r, u, p2x, p2y, a, b):
    """F1, F2 (squared-distance closure) and dF/d(a, b) for all candidates."""
    ca, sa = np.cos(a), np.sin(a)
    cb, sb = np.cos(b), np.sin(b)
    cc, sc = np.cos(b + u), np.sin(b + u)
    x3 = p2x + r["L23"] * ca
    y3 = p2y + r["L23"] * sa
    x4 = x3 + r["L34"] * cb - r["P6x"]
    y4 = y3 + r["L34"] * sb - r["P6y"]
    x5 = x3 + r["L35"] * cc - r["P7x"]
    y5 = y3 + r["L35"] * sc - r["P7y"]
    f1 = x4 * x4 + y4 * y4 - r["L46"] ** 2
    f2 = x5 * x5 + y5 * y5 - r["L57"] ** 2
    g11 = 2.0 * r["L23"] * (y4 * ca - x4 * sa)
    g12 = 2.0 * r["L34"] * (y4 * cb - x4 * sb)
    g21 = 2.0 * r["L23"] * (y5 * ca - x5 * sa)
    g22 = 2.0 * r["L35"] * (y5 * cc - x5 * sc)
    return f1, f2, g11, g12, g21, g22


def _newton_numpy(r, u, p2x, p2y, a, b, tol):
    """Damped Newton for every candidate at once (those still iterating are
    gathered into smaller arrays as the others converge); returns
    (converged, a, b, det J at the solution)."""
    n = a.shape[0]
    a = a.copy()
    b = b.copy()
    conv = np.zeros(n, bool)
    det_out = np.full(n, np.nan)
    idx = np.arange(n)
    rs, us, px, py, tl = r, u, p2x, p2y, tol
    for it in range(NEWTON_ITERS + 1):
        f1, f2, g11, g12, g21, g22 = _residuals_numpy(rs, us, px, py, a[idx], b[idx])
        det = g11 * g22 - g12 * g21
        res = np.maximum(np.abs(f1) / (2.0 * rs["L46"]), np.abs(f2) / (2.0 * rs["L57"]))
        done = res <= tl
        conv[idx[done]] = True
        det_out[idx[done]] = det[done]
        if it == NEWTON_ITERS:
            break
        go = ~done & np.isfinite(det) & (det != 0.0)
        if not go.any():
            break
        da = (f1 * g22 - g12 * f2) / det
        db = (g11 * f2 - f1 * g21) / det
        step = np.maximum(np.abs(da), np.abs(db))
        fac = np.where(step > NEWTON_STEP, NEWTON_STEP / step, 1.0)
        a[idx] -= np.where(go, fac * da, 0.0)
        b[idx] -= np.where(go, fac * db, 0.0)
        if not go.all():
            idx = idx[go]
            rs = {k: rs[k][go] for k in ("P6x", "P6y", "P7x", "P7y", "L23", "L34", "L35", "L46",
                                          "L57")}
            us, px, py, tl = us[go], px[go], py[go], tl[go]
    return conv, a, b, det_out


def _wrap_numpy(x):
    return x - TWO_PI * np.floor((x + math.pi) / TWO_PI)


# the columns the continuation reads (subsets of candidates are gathered from these)
_WALK_KEYS = ("P1x", "P1y", "P6x", "P6y", "P7x", "P7y", "L12", "phiM0", "L23", "L34", "L35",
              "L46", "L57")


def _try_step_numpy(r, u, tol, scale, st, idx, target):
    """One predictor-corrector step of the candidates ``idx`` from their
    current crank angle to ``target`` (secant predictor, Newton corrector,
    branch checks).  Returns (outcome codes, a, b, slopes, det sign, margin)
    without touching the state ``st``."""
    a, b, sla, slb, sgn = (st[k][idx] for k in ("a", "b", "sla", "slb", "sgn"))
    dphi = target - st["phi"][idx]
    ap = a + sla * dphi
    bp = b + slb * dphi
    ang = target + r["phiM0"]
    p2x = r["P1x"] + r["L12"] * np.cos(ang)
    p2y = r["P1y"] + r["L12"] * np.sin(ang)
    conv, an, bn, det = _newton_numpy(r, u, p2x, p2y, ap, bp, tol)
    out = np.where(conv, OK, NEWTON_MAXITER).astype(np.int8)
    sg = np.sign(det)
    jump = conv & (sgn != 0.0) & ((sg != sgn) | (np.abs(_wrap_numpy(an - ap)) > JUMP_TOL)
                                  | (np.abs(_wrap_numpy(bn - bp)) > JUMP_TOL))
    out[jump] = BRANCH_JUMP
    margin = np.abs(det) / scale
    out[(out == OK) & ~(margin >= SINGULAR_TOL)] = SINGULAR
    moved = dphi != 0.0
    sla = np.where(moved, _wrap_numpy(an - a) / np.where(moved, dphi, 1.0), sla)
    slb = np.where(moved, _wrap_numpy(bn - b) / np.where(moved, dphi, 1.0), slb)
    return out, an, bn, sla, slb, sg, margin


def _advance_numpy(r, u, tol, scale, st, phi_to, live):
    """Continuation of the ``live`` candidates from their current angle to
    ``phi_to``: steps of at most MAX_STEP, a step whose Newton fails or that
    jumps branch is retried at half the size down to MIN_STEP (each
    candidate has its own step), a successful one lets the step grow again.
    Updates ``st`` in place; returns (status, margin at phi_to)."""
    n = u.shape[0]
    status = np.full(n, OK, np.int8)
    margin = np.full(n, np.nan)
    idx = np.flatnonzero(live)
    h_cap = np.minimum(np.abs(phi_to - st["phi"][idx]), MAX_STEP)
    h = h_cap.copy()
    while idx.size:
        if idx.size <= STRAGGLERS:   # a few candidates left: the scalar code is faster
            for i, hi, ci in zip(idx.tolist(), h.tolist(), h_cap.tolist()):
                c = {k: float(r[k][i]) for k in _WALK_KEYS}
                state = tuple(float(st[k][i]) for k in ("a", "b", "sla", "slb", "sgn", "phi"))
                s, state, mg = _advance_python(c, float(u[i]), float(tol[i]), float(scale[i]),
                                               state, phi_to, hi, ci)
                status[i] = s
                margin[i] = mg if s == OK else np.nan
                for key, v in zip(("a", "b", "sla", "slb", "sgn", "phi"), state):
                    st[key][i] = v
            break
        sub = idx.size < n
        rs = {k: r[k][idx] for k in _WALK_KEYS} if sub else r
        phi = st["phi"][idx]
        final = np.abs(phi_to - phi) <= h
        target = np.where(final, phi_to, phi + np.sign(phi_to - phi) * h)
        out, an, bn, sla, slb, sg, mg = _try_step_numpy(
            rs, u[idx], tol[idx], scale[idx], st, idx, target)
        good = out == OK
        j = idx[good]
        for key, v in (("a", an), ("b", bn), ("sla", sla), ("slb", slb), ("sgn", sg),
                       ("phi", target)):
            st[key][j] = v[good]
        margin[idx[good & final]] = mg[good & final]
        retry = ~good & ((out == NEWTON_MAXITER) | (out == BRANCH_JUMP)) & (h > MIN_STEP)
        fail = ~good & ~retry
        status[idx[fail]] = out[fail]
        h = np.where(good, np.minimum(2.0 * h, h_cap), 0.5 * h)
        keep = (good & ~final) | retry
        idx, h, h_cap = idx[keep], h[keep], h_cap[keep]
    return status, margin


def class3_walk_numpy(r, phis, close=True):
    """Continuation of the class III group over the crank angles ``phis`` for
    every candidate at once, from (a0, b0) at phi_start.  Returns (status
    (n,), U435 (n,), a, b, margin (n, n_phi)); a failed candidate is NaN."""
    n = r["L23"].shape[0]
    m = len(phis)
    u = _ternary_numpy(r)
    status = np.where(np.isfinite(u), OK, BAD_GEOMETRY).astype(np.int8)
    tol = NEWTON_TOL * np.maximum(r["L46"], r["L57"])
    scale = 4.0 * r["L23"] * r["L46"] * r["L57"] * np.maximum(r["L34"], r["L35"])
    st = {"a": r["a0"].astype(np.float64), "b": r["b0"].astype(np.float64),
          "sla": np.zeros(n), "slb": np.zeros(n), "sgn": np.zeros(n),
          "phi": r["phi_start"].astype(np.float64)}
    A = np.full((n, m), np.nan)
    B = np.full((n, m), np.nan)
    M = np.full((n, m), np.nan)
    targets = [float(f) for f in phis] + ([_closing_angle(phis)] if close else [])
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for k, phi in enumerate(targets):
            live = status == OK
            s, margin = _advance_numpy(r, u, tol, scale, st, phi, live)
            status = np.where(live, s, status)
            live = status == OK
            if k < m:
                A[:, k] = st["a"]
                B[:, k] = st["b"]
                M[:, k] = margin
            else:
                off = live & ((np.abs(_wrap_numpy(st["a"] - A[:, 0])) > CLOSE_TOL)
                              | (np.abs(_wrap_numpy(st["b"] - B[:, 0])) > CLOSE_TOL))
                status[off] = BRANCH_JUMP
    bad = status != OK
    A[bad] = np.nan
    B[bad] = np.nan
    M[bad] = np.nan
    return status, u, A, B, M


def _angle_analogs_numpy(x, y, x1, y1, x2, y2):
    """Angle of (x, y) and its first and second analogs."""
    q = x * x + y * y
    c1 = x * y1 - y * x1
    c2 = x * y2 - y * x2
    return np.arctan2(y, x), c1 / q, c2 / q - 2.0 * (x * x1 + y * y1) * c1 / (q * q)


def _triad_analogs(p2, trig, L23, L34, L35, p6x, p6y, p7x, p7y):
    """P3, P4, P5 as (x, y, x', y', x'', y'') and the analogs (a', a''), (b', b'')
    of the class III angles, from P2 (with its analogs) and the solved angles'
    (cos a, sin a, cos b, sin b, cos(b+U), sin(b+U)).  Plain arithmetic, so the
    NumPy baseline passes arrays and the pure-Python baseline passes floats."""
    ca, sa, cb, sb, cc, sc = trig
    x3 = p2[0] + L23 * ca
    y3 = p2[1] + L23 * sa
    x4 = x3 + L34 * cb
    y4 = y3 + L34 * sb
    x5 = x3 + L35 * cc
    y5 = y3 + L35 * sc
    r4x, r4y = x4 - p6x, y4 - p6y
    r5x, r5y = x5 - p7x, y5 - p7y
    # d/dphi of |r4|^2 / 2 = 0 and |r5|^2 / 2 = 0: the Jacobian of the closure
    g11 = L23 * (r4y * ca - r4x * sa)
    g12 = L34 * (r4y * cb - r4x * sb)
    g21 = L23 * (r5y * ca - r5x * sa)
    g22 = L35 * (r5y * cc - r5x * sc)
    det = g11 * g22 - g12 * g21
    h1 = -(r4x * p2[2] + r4y * p2[3])
    h2 = -(r5x * p2[2] + r5y * p2[3])
    a1 = (h1 * g22 - g12 * h2) / det
    b1 = (g11 * h2 - h1 * g21) / det
    x3d, y3d = p2[2] - L23 * a1 * sa, p2[3] + L23 * a1 * ca
    x4d, y4d = x3d - L34 * b1 * sb, y3d + L34 * b1 * cb
    x5d, y5d = x3d - L35 * b1 * sc, y3d + L35 * b1 * cc
    # second: r4 . P4'' + |P4'|^2 = 0, P4'' = P2'' + L23 (a'' n(a) - a'^2 e(a)) + ...
    kx3 = p2[4] - L23 * a1 * a1 * ca
    ky3 = p2[5] - L23 * a1 * a1 * sa
    kx4, ky4 = kx3 - L34 * b1 * b1 * cb, ky3 - L34 * b1 * b1 * sb
    kx5, ky5 = kx3 - L35 * b1 * b1 * cc, ky3 - L35 * b1 * b1 * sc
    h1 = -(x4d * x4d + y4d * y4d) - (r4x * kx4 + r4y * ky4)
    h2 = -(x5d * x5d + y5d * y5d) - (r5x * kx5 + r5y * ky5)
    a2 = (h1 * g22 - g12 * h2) / det
    b2 = (g11 * h2 - h1 * g21) / det
    x3dd, y3dd = kx3 - L23 * a2 * sa, ky3 + L23 * a2 * ca
    p3 = (x3, y3, x3d, y3d, x3dd, y3dd)
    p4 = (x4, y4, x4d, y4d, x3dd - L34 * (b2 * sb + b1 * b1 * cb),
          y3dd + L34 * (b2 * cb - b1 * b1 * sb))
    p5 = (x5, y5, x5d, y5d, x3dd - L35 * (b2 * sc + b1 * b1 * cc),
          y3dd + L35 * (b2 * cc - b1 * b1 * sc))
    return p3, p4, p5, (a1, a2), (b1, b2), (r4x, r4y), (r5x, r5y)


def _kinematics_numpy(r, u, phis, A, B):
    """Points, link angles and their analogs at every (candidate, position),
    from the solved angles A, B (n, m) of the class III group.  Returns a dict:
    point -> (x, y, x', y', x'', y''); link -> (angle, angle', angle'')."""
    col = lambda k: r[k][:, None]
    ang = np.asarray(phis)[None, :] + col("phiM0")
    L12, L23, L34, L35 = col("L12"), col("L23"), col("L34"), col("L35")
    uu = u[:, None]
    ce, se = np.cos(ang), np.sin(ang)
    ca, sa = np.cos(A), np.sin(A)
    cb, sb = np.cos(B), np.sin(B)
    cc, sc = np.cos(B + uu), np.sin(B + uu)
    p2 = (col("P1x") + L12 * ce, col("P1y") + L12 * se, -L12 * se, L12 * ce, -L12 * ce, -L12 * se)
    p3, p4, p5, (a1, a2), (b1, b2), (r4x, r4y), (r5x, r5y) = _triad_analogs(
        p2, (ca, sa, cb, sb, cc, sc), L23, L34, L35, col("P6x"), col("P6y"), col("P7x"),
        col("P7y"))
    rock = _angle_analogs_numpy(r5x, r5y, p5[2], p5[3], p5[4], p5[5])
    lead = _angle_analogs_numpy(r4x, r4y, p4[2], p4[3], p4[4], p4[5])
    t = rock[0] + col("U578")
    ct, st = np.cos(t), np.sin(t)
    L78 = col("L78")
    p8 = (col("P7x") + L78 * ct, col("P7y") + L78 * st,
          -L78 * rock[1] * st, L78 * rock[1] * ct,
          -L78 * (rock[2] * st + rock[1] ** 2 * ct), L78 * (rock[2] * ct - rock[1] ** 2 * st))
    one = np.ones_like(ang)
    return {"P2": p2, "P3": p3, "P4": p4, "P5": p5, "P8": p8,
            "crank": (ang, one, 0.0 * one), "lead 2-3": (A, a1, a2), "ternary": (B, b1, b2),
            "lead 4-6": lead, "rocker": rock}


def _stack_points(kin, names):
    """(n, m, n_points, 2) arrays of positions, first and second analogs."""
    out = []
    for lo in (0, 2, 4):
        out.append(np.stack([np.stack([kin[p][lo], kin[p][lo + 1]], axis=-1) for p in names],
                            axis=2))
    return out


def class3_kinematics_numpy(rows, phis, close=False):
    """Full kinematics of mechanism B for every candidate (``class3_rows``) over
    the crank angles ``phis``: (status (n,), pos, d1, d2) with the last three
    (n, n_phi, 5, 2) for the points P2, P3, P4, P5, P8 (mm, mm/rad, mm/rad^2).
    ``close`` also requires the revolution to close on its start."""
    r = dict(rows)
    status, u, A, B, _ = class3_walk_numpy(r, phis, close)
    with np.errstate(invalid="ignore", divide="ignore"):
        kin = _kinematics_numpy(r, u, phis, A, B)
    pos, d1, d2 = _stack_points(kin, POINTS_B)
    return status, pos, d1, d2


# ============================================================== sweep, NumPy
def _window_ranges_numpy(theta, w):
    """max - min of every cyclic window of w + 1 samples, for every start:
    sliding extrema by doubling (log2(w) passes over the array)."""
    ext = np.concatenate([theta, theta[:, :w]], axis=1)
    length = w + 1
    hi = lo = ext
    span = 1
    while 2 * span <= length:
        hi = np.maximum(hi[:, :-span], hi[:, span:])
        lo = np.minimum(lo[:, :-span], lo[:, span:])
        span *= 2
    n = theta.shape[1]
    shift = length - span
    hi = np.maximum(hi[:, :n], hi[:, shift:shift + n])
    lo = np.minimum(lo[:, :n], lo[:, shift:shift + n])
    return hi - lo


def dwell_numpy(theta, w):
    """(dwell error, full swing) per row of theta (n, m): the smallest window
    range over the full range; NaN if the rocker does not move or w is out of range."""
    full = theta.max(axis=1) - theta.min(axis=1)
    n = theta.shape[1]
    if not 1 <= w < n:
        return np.full(theta.shape[0], np.nan), full
    with np.errstate(invalid="ignore", divide="ignore"):
        err = _window_ranges_numpy(theta, w).min(axis=1) / full
    return np.where(full > 0.0, err, np.nan), full


def _force_template():
    """Constant part of the equilibrium matrix: unit force coefficients of every
    reaction on the bodies it acts on, and M_bal on the crank."""
    n = 3 * len(BODIES_B)
    t = np.zeros((n, n))
    for j, (_, p, q) in enumerate(JOINTS_B):
        for body, sgn in ((q, 1.0), (p, -1.0)):
            if body >= 0:
                t[3 * body, 2 * j] = sgn
                t[3 * body + 1, 2 * j + 1] = sgn
    t[2, 2 * len(JOINTS_B)] = 1.0
    return t


# per body of BODIES_B: the base point of its centre of mass and the link it turns with
# (S = base + rot(link vector, US, lS), DOMAIN.md section 5)
BODY_FRAMES = (("P1", "crank"), ("P2", "lead 2-3"), ("P3", "ternary"), ("P6", "lead 4-6"),
               ("P7", "rocker"))


def _point_numpy(r, kin, name, sel):
    if name in kin:
        return kin[name]
    x = r[name + "x"][sel][:, None]
    y = r[name + "y"][sel][:, None]
    z = 0.0 * x
    return (x, y, z, z, z, z)


def peak_reaction_numpy(r, kin, sel, setup, batch=16384):
    """Largest |R| over joints and positions for the candidates ``sel`` (kin
    computed for those candidates only)."""
    w2 = setup.omega1 ** 2
    e1 = setup.eps1
    ns, m = kin["P2"][0].shape
    nb = len(BODIES_B)
    S = []        # centres of mass (x, y) per body, (ns, m)
    rhs = np.empty((ns, m, 3 * nb))
    for i, (base, link) in enumerate(BODY_FRAMES):
        bp = _point_numpy(r, kin, base, sel)
        th, th1, th2 = kin[link]
        lS = r[f"lS{i}"][sel][:, None]
        t = th + r[f"US{i}"][sel][:, None]
        c, s = np.cos(t), np.sin(t)
        sx, sy = bp[0] + lS * c, bp[1] + lS * s
        s1x, s1y = bp[2] - lS * th1 * s, bp[3] + lS * th1 * c
        s2x = bp[4] - lS * (th2 * s + th1 * th1 * c)
        s2y = bp[5] + lS * (th2 * c - th1 * th1 * s)
        mass = r[f"m{i}"][sel][:, None]
        J = r[f"J{i}"][sel][:, None]
        # applied + inertia loads at S; the equations are reactions = -loads
        rhs[:, :, 3 * i] = mass * (s2x * w2 + s1x * e1) * MM
        rhs[:, :, 3 * i + 1] = mass * setup.gravity + mass * (s2y * w2 + s1y * e1) * MM
        rhs[:, :, 3 * i + 2] = J * (th2 * w2 + th1 * e1)
        S.append((sx, sy))
    template = _force_template()
    lever = []    # (row, col of Rx, sign, lx, ly) for each joint-body incidence
    for j, (pname, p, q) in enumerate(JOINTS_B):
        pt = _point_numpy(r, kin, pname, sel)
        for body, sgn in ((q, 1.0), (p, -1.0)):
            if body >= 0:
                lx = np.broadcast_to((pt[0] - S[body][0]) * MM, (ns, m))
                ly = np.broadcast_to((pt[1] - S[body][1]) * MM, (ns, m))
                lever.append((3 * body + 2, 2 * j, sgn, lx.reshape(-1), ly.reshape(-1)))
    rhs = rhs.reshape(ns * m, 3 * nb)
    nj = len(JOINTS_B)
    peak = np.full(ns * m, np.nan)
    for lo in range(0, ns * m, batch):
        hi = min(lo + batch, ns * m)
        a = np.broadcast_to(template, (hi - lo,) + template.shape).copy()
        for row, c, sgn, lx, ly in lever:
            a[:, row, c] = -sgn * ly[lo:hi]
            a[:, row, c + 1] = sgn * lx[lo:hi]
        x = np.linalg.solve(a, rhs[lo:hi, :, None])[:, :, 0]
        peak[lo:hi] = np.hypot(x[:, 0:2 * nj:2], x[:, 1:2 * nj:2]).max(axis=1)
    return peak.reshape(ns, m).max(axis=1)


def sweep_numpy(rows, phis, setup: SweepSetup):
    """Sweep metrics of every candidate, vectorized over candidates.

    Stage 1 (all): positions by continuation over the revolution (and on to
    its closing angle), singularity margin = min over positions of
    |det J| / (4 L23 L46 L57 max(L34, L35)), rocker angle theta about P7 ->
    stroke = L78 * swing and the dwell error.  Stage 2 (status OK, stroke
    within bounds, margin >= margin_min): analogs from the stored angles of
    stage 1 and the force analysis -> peak reaction.  Returns a dict of
    (n,) arrays: status, stroke, dwell_error, margin, peak_reaction, forces_done.
    """
    r = dict(rows)
    phis = np.asarray(phis, dtype=np.float64)
    status, u, A, B, M = class3_walk_numpy(r, phis, close=True)
    ok = status == OK
    ang = phis[None, :] + r["phiM0"][:, None]
    with np.errstate(invalid="ignore"):
        x3 = r["P1x"][:, None] + r["L12"][:, None] * np.cos(ang) + r["L23"][:, None] * np.cos(A)
        y3 = r["P1y"][:, None] + r["L12"][:, None] * np.sin(ang) + r["L23"][:, None] * np.sin(A)
        c = B + u[:, None]
        rx = x3 + r["L35"][:, None] * np.cos(c) - r["P7x"][:, None]
        ry = y3 + r["L35"][:, None] * np.sin(c) - r["P7y"][:, None]
        theta = np.arctan2(rx[:, :1] * ry - ry[:, :1] * rx, rx[:, :1] * rx + ry[:, :1] * ry)
    n = len(status)
    dwell = np.full(n, np.nan)
    swing = np.full(n, np.nan)
    if ok.any():
        dwell[ok], swing[ok] = dwell_numpy(theta[ok], setup.dwell_w)
    stroke = setup.stroke_radius * swing
    margin = np.where(ok, np.min(np.where(ok[:, None], M, np.inf), axis=1), np.nan)
    peak = np.full(n, np.nan)
    lo, hi = setup.stroke_bounds
    with np.errstate(invalid="ignore"):
        sel = ok & (stroke >= lo) & (stroke <= hi) & (margin >= setup.margin_min)
    sel &= setup.forces
    if sel.any():
        rs = {k: v[sel] for k, v in r.items()}
        with np.errstate(invalid="ignore", divide="ignore"):
            kin = _kinematics_numpy(rs, u[sel], phis, A[sel], B[sel])
            peak[sel] = peak_reaction_numpy(r, kin, sel, setup)
    return {"status": status, "stroke": stroke, "dwell_error": dwell, "margin": margin,
            "peak_reaction": peak, "forces_done": sel}


# ============================================================== class III, pure Python
def _wrap(x):
    return x - TWO_PI * math.floor((x + math.pi) / TWO_PI)


def _candidates(rows):
    """rows (dict of columns) -> a list of per-candidate dicts of Python floats."""
    cols = {k: np.asarray(v).tolist() for k, v in rows.items()}
    n = len(next(iter(cols.values())))
    return [{k: v[i] for k, v in cols.items()} for i in range(n)]


def _ternary_python(c):
    l34, l45, l35 = c["L34"], c["L45"], c["L35"]
    if not (l34 > 0 and l45 > 0 and l35 > 0 and c["L23"] > 0 and c["L46"] > 0 and c["L57"] > 0):
        return math.nan
    if not (l45 < l34 + l35 and l34 < l45 + l35 and l35 < l34 + l45):
        return math.nan
    x = (l34 * l34 + l35 * l35 - l45 * l45) / (2.0 * l34 * l35)
    return c["orientation"] * math.acos(min(1.0, max(-1.0, x)))


def _newton_python(c, u, p2x, p2y, a, b, tol):
    """Damped Newton for one candidate: (converged, a, b, det J)."""
    l23, l34, l35, l46, l57 = c["L23"], c["L34"], c["L35"], c["L46"], c["L57"]
    p6x, p6y, p7x, p7y = c["P6x"], c["P6y"], c["P7x"], c["P7y"]
    for it in range(NEWTON_ITERS + 1):
        ca, sa = math.cos(a), math.sin(a)
        cb, sb = math.cos(b), math.sin(b)
        cc, sc = math.cos(b + u), math.sin(b + u)
        x3 = p2x + l23 * ca
        y3 = p2y + l23 * sa
        x4 = x3 + l34 * cb - p6x
        y4 = y3 + l34 * sb - p6y
        x5 = x3 + l35 * cc - p7x
        y5 = y3 + l35 * sc - p7y
        f1 = x4 * x4 + y4 * y4 - l46 * l46
        f2 = x5 * x5 + y5 * y5 - l57 * l57
        g11 = 2.0 * l23 * (y4 * ca - x4 * sa)
        g12 = 2.0 * l34 * (y4 * cb - x4 * sb)
        g21 = 2.0 * l23 * (y5 * ca - x5 * sa)
        g22 = 2.0 * l35 * (y5 * cc - x5 * sc)
        det = g11 * g22 - g12 * g21
        if max(abs(f1) / (2.0 * l46), abs(f2) / (2.0 * l57)) <= tol:
            return True, a, b, det
        if it == NEWTON_ITERS or not (det != 0.0 and math.isfinite(det)):
            return False, a, b, det
        da = (f1 * g22 - g12 * f2) / det
        db = (g11 * f2 - f1 * g21) / det
        step = max(abs(da), abs(db))
        if not math.isfinite(step):
            return False, a, b, det
        if step > NEWTON_STEP:
            da *= NEWTON_STEP / step
            db *= NEWTON_STEP / step
        a -= da
        b -= db
    return False, a, b, math.nan


def _try_step_python(c, u, tol, scale, state, target):
    """One predictor-corrector step of one candidate; (outcome, new state, margin)."""
    a, b, sla, slb, sgn, phi = state
    dphi = target - phi
    ap = a + sla * dphi
    bp = b + slb * dphi
    ang = target + c["phiM0"]
    conv, an, bn, det = _newton_python(c, u, c["P1x"] + c["L12"] * math.cos(ang),
                                       c["P1y"] + c["L12"] * math.sin(ang), ap, bp, tol)
    if not conv:
        return NEWTON_MAXITER, state, math.nan
    sg = 1.0 if det > 0.0 else (-1.0 if det < 0.0 else 0.0)
    if sgn != 0.0 and (sg != sgn or abs(_wrap(an - ap)) > JUMP_TOL
                       or abs(_wrap(bn - bp)) > JUMP_TOL):
        return BRANCH_JUMP, state, math.nan
    margin = abs(det) / scale
    if not margin >= SINGULAR_TOL:
        return SINGULAR, state, margin
    if dphi != 0.0:
        sla = _wrap(an - a) / dphi
        slb = _wrap(bn - b) / dphi
    return OK, (an, bn, sla, slb, sg, target), margin


def _advance_python(c, u, tol, scale, state, phi_to, h=None, h_cap=None):
    """Continuation of one candidate to ``phi_to`` with step halving on a
    failed or jumping step (see ``_advance_numpy``); (status, state, margin).
    ``h``, ``h_cap``: the current and largest step, when taking over a walk."""
    if h_cap is None:
        h_cap = min(abs(phi_to - state[5]), MAX_STEP)
        h = h_cap
    while True:
        phi = state[5]
        final = abs(phi_to - phi) <= h
        target = phi_to if final else phi + math.copysign(h, phi_to - phi)
        out, new, margin = _try_step_python(c, u, tol, scale, state, target)
        if out == OK:
            state = new
            if final:
                return OK, state, margin
            h = min(2.0 * h, h_cap)
        elif (out == NEWTON_MAXITER or out == BRANCH_JUMP) and h > MIN_STEP:
            h *= 0.5
        else:
            return out, state, margin


def class3_walk_python(c, phis, close=True):
    """Continuation for one candidate (dict of floats): (status, U435, a list,
    b list, margin list); the lists stop at a failure."""
    u = _ternary_python(c)
    if not math.isfinite(u):
        return BAD_GEOMETRY, u, [], [], []
    tol = NEWTON_TOL * max(c["L46"], c["L57"])
    scale = 4.0 * c["L23"] * c["L46"] * c["L57"] * max(c["L34"], c["L35"])
    state = (c["a0"], c["b0"], 0.0, 0.0, 0.0, c["phi_start"])
    A, B, M = [], [], []
    targets = list(phis) + ([_closing_angle(phis)] if close else [])
    for k, phi in enumerate(targets):
        status, state, margin = _advance_python(c, u, tol, scale, state, phi)
        if status != OK:
            return status, u, A, B, M
        if k < len(phis):
            A.append(state[0])
            B.append(state[1])
            M.append(margin)
        elif abs(_wrap(state[0] - A[0])) > CLOSE_TOL or abs(_wrap(state[1] - B[0])) > CLOSE_TOL:
            return BRANCH_JUMP, u, A, B, M
    return OK, u, A, B, M


def _angle_analogs_python(x, y, x1, y1, x2, y2):
    q = x * x + y * y
    c1 = x * y1 - y * x1
    c2 = x * y2 - y * x2
    return math.atan2(y, x), c1 / q, c2 / q - 2.0 * (x * x1 + y * y1) * c1 / (q * q)


def _kinematics_python(c, u, phi, a, b):
    """Points and link angles with analogs at one position (same layout as
    ``_kinematics_numpy``, scalars)."""
    L12, L23, L34, L35 = c["L12"], c["L23"], c["L34"], c["L35"]
    ang = phi + c["phiM0"]
    ce, se = math.cos(ang), math.sin(ang)
    ca, sa = math.cos(a), math.sin(a)
    cb, sb = math.cos(b), math.sin(b)
    cc, sc = math.cos(b + u), math.sin(b + u)
    p2 = (c["P1x"] + L12 * ce, c["P1y"] + L12 * se, -L12 * se, L12 * ce, -L12 * ce, -L12 * se)
    p3, p4, p5, (a1, a2), (b1, b2), (r4x, r4y), (r5x, r5y) = _triad_analogs(
        p2, (ca, sa, cb, sb, cc, sc), L23, L34, L35, c["P6x"], c["P6y"], c["P7x"], c["P7y"])
    rock = _angle_analogs_python(r5x, r5y, p5[2], p5[3], p5[4], p5[5])
    lead = _angle_analogs_python(r4x, r4y, p4[2], p4[3], p4[4], p4[5])
    t = rock[0] + c["U578"]
    ct, st = math.cos(t), math.sin(t)
    L78 = c["L78"]
    p8 = (c["P7x"] + L78 * ct, c["P7y"] + L78 * st, -L78 * rock[1] * st, L78 * rock[1] * ct,
          -L78 * (rock[2] * st + rock[1] ** 2 * ct), L78 * (rock[2] * ct - rock[1] ** 2 * st))
    return {"P2": p2, "P3": p3, "P4": p4, "P5": p5, "P8": p8, "crank": (ang, 1.0, 0.0),
            "lead 2-3": (a, a1, a2), "ternary": (b, b1, b2), "lead 4-6": lead, "rocker": rock}


def class3_kinematics_python(rows, phis, close=False):
    """The same as ``class3_kinematics_numpy`` with loops: a list per candidate
    of (status, pos, d1, d2), each of the last three a list (positions) of five
    (x, y) tuples for P2, P3, P4, P5, P8 (empty lists when status is not OK)."""
    phis = [float(f) for f in phis]
    out = []
    for c in _candidates(rows):
        status, u, A, B, _ = class3_walk_python(c, phis, close)
        pos, d1, d2 = [], [], []
        if status == OK:
            for phi, a, b in zip(phis, A, B):
                kin = _kinematics_python(c, u, phi, a, b)
                pts = [kin[p] for p in POINTS_B]
                pos.append([(q[0], q[1]) for q in pts])
                d1.append([(q[2], q[3]) for q in pts])
                d2.append([(q[4], q[5]) for q in pts])
        out.append((status, pos, d1, d2))
    return out


# ============================================================== sweep, pure Python
def dwell_python(theta, w):
    """(dwell error, full swing) of one revolution of samples (a list)."""
    n = len(theta)
    full = max(theta) - min(theta)
    if not (full > 0.0) or not 1 <= w < n:
        return math.nan, full
    ext = theta + theta[:w]
    best = math.inf
    for s in range(n):
        win = ext[s:s + w + 1]
        best = min(best, max(win) - min(win))
    return best / full, full


def _gauss_python(a, b):
    """Solve a x = b (lists, modified in place) by elimination with partial pivoting."""
    n = len(b)
    for c in range(n):
        p = c
        big = abs(a[c][c])
        for r in range(c + 1, n):
            if abs(a[r][c]) > big:
                big = abs(a[r][c])
                p = r
        if not big > 0.0:
            return None
        if p != c:
            a[c], a[p] = a[p], a[c]
            b[c], b[p] = b[p], b[c]
        rc = a[c]
        piv = rc[c]
        for r in range(c + 1, n):
            rr = a[r]
            f = rr[c] / piv
            if f != 0.0:
                for k in range(c + 1, n):
                    rr[k] -= f * rc[k]
                b[r] -= f * b[c]
    x = [0.0] * n
    for c in range(n - 1, -1, -1):
        rc = a[c]
        s = b[c]
        for k in range(c + 1, n):
            s -= rc[k] * x[k]
        x[c] = s / rc[c]
    return x


def _reactions_python(c, kin, setup):
    """|R| of every joint at one position: the 15x15 equilibrium system."""
    w2 = setup.omega1 ** 2
    e1 = setup.eps1
    nb = len(BODIES_B)
    n = 3 * nb
    a = [[0.0] * n for _ in range(n)]
    b = [0.0] * n
    S = []
    zero = (0.0, 0.0, 0.0, 0.0)
    for i, (base, link) in enumerate(BODY_FRAMES):
        bp = kin[base] if base in kin else (c[base + "x"], c[base + "y"]) + zero
        th, th1, th2 = kin[link]
        lS = c[f"lS{i}"]
        t = th + c[f"US{i}"]
        ct, st = math.cos(t), math.sin(t)
        S.append((bp[0] + lS * ct, bp[1] + lS * st))
        s1x, s1y = bp[2] - lS * th1 * st, bp[3] + lS * th1 * ct
        s2x = bp[4] - lS * (th2 * st + th1 * th1 * ct)
        s2y = bp[5] + lS * (th2 * ct - th1 * th1 * st)
        m = c[f"m{i}"]
        b[3 * i] = m * (s2x * w2 + s1x * e1) * MM
        b[3 * i + 1] = m * setup.gravity + m * (s2y * w2 + s1y * e1) * MM
        b[3 * i + 2] = c[f"J{i}"] * (th2 * w2 + th1 * e1)
    for j, (pname, p, q) in enumerate(JOINTS_B):
        pt = kin[pname] if pname in kin else (c[pname + "x"], c[pname + "y"])
        for body, sgn in ((q, 1.0), (p, -1.0)):
            if body >= 0:
                lx = (pt[0] - S[body][0]) * MM
                ly = (pt[1] - S[body][1]) * MM
                a[3 * body][2 * j] = sgn
                a[3 * body + 1][2 * j + 1] = sgn
                a[3 * body + 2][2 * j] = -sgn * ly
                a[3 * body + 2][2 * j + 1] = sgn * lx
    a[2][2 * len(JOINTS_B)] = 1.0
    x = _gauss_python(a, b)
    if x is None:
        return [math.nan]
    return [math.hypot(x[2 * j], x[2 * j + 1]) for j in range(len(JOINTS_B))]


def sweep_python(rows, phis, setup: SweepSetup):
    """The same as ``sweep_numpy``, one candidate at a time with loops."""
    phis = [float(f) for f in phis]
    n = len(phis)
    lo, hi = setup.stroke_bounds
    res = {k: [] for k in ("status", "stroke", "dwell_error", "margin", "peak_reaction",
                           "forces_done")}
    for c in _candidates(rows):
        status, u, A, B, M = class3_walk_python(c, phis, close=True)
        stroke = dwell = margin = peak = math.nan
        forced = False
        if status == OK:
            theta = []
            x0 = y0 = 0.0
            for k in range(n):
                ang = phis[k] + c["phiM0"]
                x = (c["P1x"] + c["L12"] * math.cos(ang) + c["L23"] * math.cos(A[k])
                     + c["L35"] * math.cos(B[k] + u) - c["P7x"])
                y = (c["P1y"] + c["L12"] * math.sin(ang) + c["L23"] * math.sin(A[k])
                     + c["L35"] * math.sin(B[k] + u) - c["P7y"])
                if k == 0:
                    x0, y0 = x, y
                theta.append(math.atan2(x0 * y - y0 * x, x0 * x + y0 * y))
            dwell, swing = dwell_python(theta, setup.dwell_w)
            stroke = setup.stroke_radius * swing
            margin = min(M)
            forced = setup.forces and lo <= stroke <= hi and margin >= setup.margin_min
            if forced:
                peak = 0.0
                for k in range(n):
                    kin = _kinematics_python(c, u, phis[k], A[k], B[k])
                    for rk in _reactions_python(c, kin, setup):
                        if not rk <= peak:
                            peak = rk
        for key, v in (("status", status), ("stroke", stroke), ("dwell_error", dwell),
                       ("margin", margin), ("peak_reaction", peak), ("forces_done", forced)):
            res[key].append(v)
    return {k: np.asarray(v) for k, v in res.items()}
