"""40-digit references for tolerance sensitivities: the output rocker's swing
and dwell error of the four-bar D and of mechanism B over the crank-angle
grid, in mpmath, as plain functions of their dimensions (a dict), and their
central differences.

Independent of the package: the four-bar by the circle intersection in
closed form, mechanism B by Newton's method on its two loop-closure equations
with the analytic Jacobian, continued position by position from the branch of
DOMAIN.md section 5 (a = 44.006 deg, b = 128.709 deg at phi1 = 0).  The dwell
error is DOMAIN.md section 9's: the smallest range of the rocker angle over a
window of round(150 n / 360) intervals (cyclic) divided by the range over the
revolution; the stroke is the working point's radius times the swing.
"""

from __future__ import annotations

import mpmath as mp

DPS = 40
STEP = "1e-12"       # of the central difference, in mm or deg


def fourbar_dims():
    """Four-bar D (DOMAIN.md section 8) as studies/warp_feed_fourbar.toml
    gives it: mm and deg."""
    return {"P1.x": 0, "P1.y": 0, "P4.x": 38, "P4.y": 0, "crank.length": 15,
            "crank.phiM0": 0, "RRR[1].L_AB": 41, "RRR[1].L_CB": 40, "Attach[2].angle": 0,
            "Attach[2].length": 60}


def mech_b_dims():
    """Mechanism B (DOMAIN.md section 5) as studies/ov7_synthesis.toml gives it."""
    return {"P1.x": 0, "P1.y": 0, "P6.x": 195, "P6.y": 226, "P7.x": 46, "P7.y": 533,
            "crank.length": 50, "crank.phiM0": 173, "triad.L23": 272.5, "triad.L34": 81,
            "triad.L45": 104.5, "triad.L35": 174, "triad.L46": 104.5, "triad.L57": 261,
            "output arm.angle": -25, "output arm.length": 136.8}


def _rad(deg):
    return mp.mpf(deg) * mp.pi / 180


def _grid(n, rot):
    return [rot * 2 * mp.pi * k / n for k in range(n)]


def fourbar_angles(d, n=360):
    """Rocker angle atan2(C - D) at phi1 = 2 pi k / n (rot = +1), open
    configuration (C above AD at phi1 = 90 deg: cross(B - D, C - D) < 0 there)."""
    A = (mp.mpf(d["P1.x"]), mp.mpf(d["P1.y"]))
    D = (mp.mpf(d["P4.x"]), mp.mpf(d["P4.y"]))
    l1, l2, l3 = (mp.mpf(d[k]) for k in ("crank.length", "RRR[1].L_AB", "RRR[1].L_CB"))
    out = []
    for phi in _grid(n, 1):
        g = phi + _rad(d["crank.phiM0"])
        B = (A[0] + l1 * mp.cos(g), A[1] + l1 * mp.sin(g))
        dx, dy = B[0] - D[0], B[1] - D[1]
        r = mp.sqrt(dx * dx + dy * dy)
        # C on the circle about D (radius l3) and about B (radius l2)
        a = (l3 * l3 - l2 * l2 + r * r) / (2 * r)
        h = mp.sqrt(l3 * l3 - a * a)
        mx, my = D[0] + a * dx / r, D[1] + a * dy / r
        C = (mx + h * dy / r, my - h * dx / r)          # cross(B - D, C - D) = -h r < 0
        out.append(mp.atan2(C[1] - D[1], C[0] - D[0]))
    return out


def _b_closure(d, phi, a, b):
    g = phi + _rad(d["crank.phiM0"])
    u435 = mp.acos((d["triad.L34"] ** 2 + d["triad.L35"] ** 2 - d["triad.L45"] ** 2)
                   / (2 * d["triad.L34"] * d["triad.L35"]))
    P2 = (d["P1.x"] + d["crank.length"] * mp.cos(g), d["P1.y"] + d["crank.length"] * mp.sin(g))
    P3 = (P2[0] + d["triad.L23"] * mp.cos(a), P2[1] + d["triad.L23"] * mp.sin(a))
    P4 = (P3[0] + d["triad.L34"] * mp.cos(b), P3[1] + d["triad.L34"] * mp.sin(b))
    P5 = (P3[0] + d["triad.L35"] * mp.cos(b + u435), P3[1] + d["triad.L35"] * mp.sin(b + u435))
    return P3, P4, P5, u435


def _b_solve(d, phi, a, b):
    """Newton on |P4 - P6|^2 = L46^2, |P5 - P7|^2 = L57^2 in (a, b)."""
    for _ in range(60):
        P3, P4, P5, u = _b_closure(d, phi, a, b)
        e4 = (P4[0] - d["P6.x"], P4[1] - d["P6.y"])
        e5 = (P5[0] - d["P7.x"], P5[1] - d["P7.y"])
        f1 = e4[0] ** 2 + e4[1] ** 2 - d["triad.L46"] ** 2
        f2 = e5[0] ** 2 + e5[1] ** 2 - d["triad.L57"] ** 2
        # d P3/da = L23 (-sin a, cos a); d P4/db = L34 (-sin b, cos b); d P5/db likewise
        da3 = (-d["triad.L23"] * mp.sin(a), d["triad.L23"] * mp.cos(a))
        db4 = (-d["triad.L34"] * mp.sin(b), d["triad.L34"] * mp.cos(b))
        db5 = (-d["triad.L35"] * mp.sin(b + u), d["triad.L35"] * mp.cos(b + u))
        j11 = 2 * (e4[0] * da3[0] + e4[1] * da3[1])
        j12 = 2 * (e4[0] * db4[0] + e4[1] * db4[1])
        j21 = 2 * (e5[0] * da3[0] + e5[1] * da3[1])
        j22 = 2 * (e5[0] * db5[0] + e5[1] * db5[1])
        det = j11 * j22 - j12 * j21
        sa = (f1 * j22 - f2 * j12) / det
        sb = (j11 * f2 - j21 * f1) / det
        a, b = a - sa, b - sb
        if abs(sa) + abs(sb) < mp.mpf(10) ** (-(DPS - 5)):
            return a, b
    raise ValueError("mp Newton did not converge")


def mech_b_angles(d, n=360):
    """Rocker angle atan2(P5 - P7) at phi1 = -2 pi k / n (rot = -1)."""
    d = {k: mp.mpf(v) for k, v in d.items()}
    a, b = _b_solve(d, mp.mpf(0), _rad("44.006"), _rad("128.709"))
    out = []
    for phi in _grid(n, -1):
        a, b = _b_solve(d, phi, a, b)
        _, _, P5, _ = _b_closure(d, phi, a, b)
        out.append(mp.atan2(P5[1] - d["P7.y"], P5[0] - d["P7.x"]))
    return out


def _unwrap(th):
    out = [th[0]]
    for t in th[1:]:
        step = t - out[-1]
        step -= 2 * mp.pi * mp.nint(step / (2 * mp.pi))
        out.append(out[-1] + step)
    return out


def motion(angles, radius, dwell_deg=150):
    """(stroke mm, dwell error) of rocker angles over the grid.  The extreme
    samples and the best window are found in floats, their values taken at
    full precision (a step of 1e-12 does not change which they are)."""
    th = _unwrap(angles)
    f = [float(t) for t in th]
    n = len(th)
    w = int(round(dwell_deg * n / 360))
    full = th[max(range(n), key=f.__getitem__)] - th[min(range(n), key=f.__getitem__)]
    best_k = min(range(n), key=lambda k: max(f[(k + j) % n] for j in range(w + 1))
                 - min(f[(k + j) % n] for j in range(w + 1)))
    window = [(best_k + j) % n for j in range(w + 1)]
    hi = max(window, key=f.__getitem__)
    lo = min(window, key=f.__getitem__)
    return radius * full, (th[hi] - th[lo]) / full


def central_difference(fn, dims, key, radius_key):
    """(d stroke / d dims[key], d dwell error / d dims[key]) at 40 digits: the
    radius is dims[radius_key] (the working point's arm)."""
    with mp.workdps(DPS):
        h = mp.mpf(STEP)
        vals = []
        for s in (1, -1):
            d = {k: mp.mpf(str(v)) for k, v in dims.items()}
            d[key] += s * h
            vals.append(motion(fn(d), d[radius_key]))
        return tuple(float((p - m) / (2 * h)) for p, m in zip(vals[0], vals[1]))
