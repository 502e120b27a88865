"""Constructed mechanisms whose failure lies between two sampled crank angles,
and the independent references that say where it is (test oracle of
tests/kernels/test_between_samples.py).

Every case is built backwards: the locked range of crank angles is chosen
first (its centre at a random angle, its width w = 10**U(-2, log10 2) deg,
its entry at a random phase relative to the crank grid), the link lengths are
derived from it and rounded to float64, and then the exact boundaries are
recomputed from the rounded values in mpmath at 30 digits:

* dyads (four-bar RRR, offset slider-crank RRP, coulisse RPR): closed forms
  of the assembly condition (cosine law / distance to the guide);
* class III triads: mpmath.findroot on the fold system F1 = F2 = det J = 0 in
  (a, b, phi), started from a float fold point found on the fold curve
  F1 = det J = 0 (which does not depend on L57).

Nothing here imports ``pipeline``: a case is plain data (names of the
compiled plan's parameters and their values, the crank grid, the expected
outcome), and the brute-force scans and continuations that check the
references use their own formulas.

Conventions (DOMAIN.md section 2): crank tip A = P1 + L e(phi + phiM0) with
P1 = (0, 0); an RRR dyad puts B at C + rot(A - C, -W U, L_CB), so
sign(cross(A - C, B - C)) = -W; a class III triad as in DOMAIN.md section 5.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import mpmath
import numpy as np

DPS = 30
DEG = math.pi / 180.0
TWO_PI = 2.0 * math.pi
W_MIN_DEG, W_MAX_DEG = 0.01, 2.0          # widths of the locked ranges


# --------------------------------------------------------------------------- study texts
# One structure per group type; every case of a structure is a parameter row
# of the one compiled plan (values by parameter name).

def _study(name, fixed, crank, groups, output, kind="scene", extra=""):
    return (f'[study]\nkind = "{kind}"\nname = "{name}"\n\n[mechanism.fixed]\n{fixed}\n'
            f'[mechanism.crank]\npivot = "P1"\ntip = "P2"\n{crank}\n{groups}\n'
            f'[output]\n{output}\n{extra}')


CRANK = "length = 15.0\nphiM0 = 0.0\nomega1 = 1.0\neps1 = 0.0\nrot = 1\nphi0 = 0.0\n"

FOURBAR = _study(
    "fourbar_lock", 'P1 = [0.0, 0.0]\nP4 = [38.0, 0.0]\n', CRANK,
    '[[mechanism.groups]]\ntype = "RRR"\nname = "dyad"\nA = "P2"\nC = "P4"\nB = "P3"\n'
    'L_AB = 41.0\nL_CB = 40.0\nW = 1\n',
    'working_point = "P3"\nanalysis = "positions"\n')

SLIDER = _study(
    "slider_lock", 'P1 = [0.0, 0.0]\nP3 = [0.0, -5.0]\n', CRANK,
    '[[mechanism.groups]]\ntype = "RRP"\nname = "slider"\nA = "P2"\nB = "P4"\n'
    'guide_point = "P3"\nguide_angle = 0.0\nL_AB = 40.0\nW = 1\n',
    'working_point = "P4"\nanalysis = "positions"\n')

COULISSE = _study(
    "coulisse_lock", 'P1 = [0.0, 0.0]\nP3 = [40.0, 0.0]\n', CRANK,
    '[[mechanism.groups]]\ntype = "RPR"\nname = "coulisse"\nblock = "P2"\npivot = "P3"\n'
    'guide_end = "P4"\nguide_length = 60.0\noffset = 5.0\nW = 1\n',
    'working_point = "P4"\nanalysis = "positions"\n')

TRIAD = _study(
    "triad_lock", 'P1 = [0.0, 0.0]\nP6 = [195.0, 226.0]\nP7 = [46.0, 533.0]\n',
    "length = 50.0\nphiM0 = 173.0\nomega1 = -94.4\neps1 = 0.0\nrot = -1\nphi0 = 0.0\n",
    '[[mechanism.groups]]\ntype = "class3"\nname = "triad"\ninput = "P2"\npivot_4 = "P6"\n'
    'pivot_5 = "P7"\njoints = ["P3", "P4", "P5"]\nL23 = 272.5\nL34 = 81.0\nL45 = 104.5\n'
    'L35 = 174.0\nL46 = 104.5\nL57 = 261.0\nstart = [44.006, 128.709]\nphi_start = 0.0\n',
    'working_point = "P5"\nanalysis = "positions"\n')

STRUCTURES = {"fourbar": FOURBAR, "slider": SLIDER, "coulisse": COULISSE, "triad": TRIAD}
GROUP_OF = {"fourbar": "dyad", "slider": "slider", "coulisse": "coulisse", "triad": "triad"}
POINTS_OF = {"fourbar": ("P2", "P4", "P3"), "slider": ("P2", "P3", "P4"),
             "coulisse": ("P2", "P3", "P4"), "triad": ("P2", "P6", "P7", "P3", "P4", "P5")}


def fourbar_sweep_study(rot=-1, phi0_deg=10.0, positions=360, bounds=None):
    """A sweep study over the four-bar (output rocker P4 -> P3), for rows
    built by the four-bar constructors with the same phi0, rot and positions;
    ``bounds``: {variable: (min, max)} (L12, L_AB), as a search needs them."""
    crank = (f"length = 15.0\nphiM0 = 0.0\nomega1 = {60.0 * rot}\neps1 = 0.0\nrot = {rot}\n"
             f"phi0 = {phi0_deg!r}\n")
    bounds = {k: f", min = {lo!r}, max = {hi!r}" for k, (lo, hi) in (bounds or {}).items()}
    sweep = ('\n[sweep]\ncandidates = 100\nseed = 1\nsampler = "uniform"\n'
             f"positions = {positions}\nchunk_size = 100\nstroke_radius = 60.0\n"
             'objectives = ["dwell_error"]\nmetrics = ["dwell_error", "stroke"]\n\n'
             '[sweep.variables]\n'
             f'L12 = {{ param = "crank.length"{bounds.get("L12", "")} }}\n'
             f'L_AB = {{ param = "dyad.L_AB"{bounds.get("L_AB", "")} }}\n\n'
             "[sweep.constraints]\nstroke = [0.0, 1000.0]\n")
    return _study(
        "fourbar_lock_sweep", 'P1 = [0.0, 0.0]\nP4 = [38.0, 0.0]\n', crank,
        '[[mechanism.groups]]\ntype = "RRR"\nname = "dyad"\nA = "P2"\nC = "P4"\nB = "P3"\n'
        'L_AB = 41.0\nL_CB = 40.0\nW = 1\n',
        'working_point = "P3"\nrocker = ["P4", "P3"]\ndwell = 150.0\n', kind="sweep",
        extra=sweep)


# --------------------------------------------------------------------------- cases
@dataclass
class Case:
    kind: str                 # what was built (fourbar-stretched, slider, triad-long, ...)
    structure: str            # key of STRUCTURES
    values: dict              # plan parameter name -> value (radians for angles)
    phi0: float               # rad: first crank angle of the revolution
    rot: int                  # +1 / -1
    n: int                    # positions per revolution
    expect: str               # "ok", "lock" (cannot assemble on a range) or "singular"
    boundary: float = math.nan  # rad, exact, the first failure met from phi0 in the
    #                             direction of travel, as phi0 + rot * t with 0 < t < 2 pi
    lock: tuple = ()          # (lo, hi) rad: both ends of the locked range (lo < hi), mpmath
    width_deg: float = math.nan
    extra: dict = field(default_factory=dict)

    @property
    def group(self):
        return GROUP_OF[self.structure]

    def phis(self):
        k = np.arange(self.n, dtype=np.float64)
        return self.phi0 + self.rot * TWO_PI * k / self.n

    @property
    def close_at(self):
        return self.phi0 + self.rot * TWO_PI


def _u(rng, lo, hi):
    return float(rng.uniform(lo, hi))


def random_width_deg(rng):
    return 10.0 ** _u(rng, math.log10(W_MIN_DEG), math.log10(W_MAX_DEG))


def wrap(x):
    """Angle to (-pi, pi]."""
    return x - TWO_PI * math.floor((x + math.pi) / TWO_PI)


def _entry(lo, hi, phi0, rot):
    """The boundary of the range (lo, hi) (mod 2 pi) met first from phi0 in the
    direction rot, as phi0 + rot * t (0 < t < 2 pi), in mpmath; and t."""
    with mpmath.workdps(DPS):
        b = lo if rot > 0 else hi
        t = (rot * (b - mpmath.mpf(phi0))) % (2 * mpmath.pi)
        return phi0 + rot * t, t


def _place(rng, phi0, rot, w):
    """Centre of a locked range of width w (rad) whose entry lies at a random
    distance t from phi0 along the travel (not closer than 0.05 deg to either
    end of the revolution)."""
    t = _u(rng, 0.05 * DEG, TWO_PI - w - 0.05 * DEG)
    return phi0 + rot * (t + 0.5 * w)


def _finish(case, lo, hi):
    """Store the exact range and its entry boundary (floats from mpmath)."""
    with mpmath.workdps(DPS):
        lo, hi = mpmath.mpf(lo), mpmath.mpf(hi)
        b, t = _entry(lo, hi, case.phi0, case.rot)
        case.lock = (float(lo), float(hi))
        case.width_deg = float((hi - lo) * 180 / mpmath.pi)
        case.boundary = float(b)
        case.extra["t"] = float(t)
        if not (0 < t and t + (hi - lo) < 2 * mpmath.pi):
            raise AssertionError("the lock is not inside the revolution")
    return case


# ---- four-bars (RRR) ---------------------------------------------------------
def _fourbar_values(L, cx, cy, m, lab, lcb, W):
    return {"P1.x": 0.0, "P1.y": 0.0, "P4.x": float(cx), "P4.y": float(cy),
            "crank.length": float(L), "crank.phiM0": float(m), "dyad.L_AB": float(lab),
            "dyad.L_CB": float(lcb), "dyad.W": float(W)}


def fourbar_exact_lock(v):
    """Exact locked range (lo, hi) of a four-bar (mpmath, 30 digits): the RRR
    assembles iff |L_AB - L_CB| <= |A - C| <= L_AB + L_CB, with
    |A - C|^2 = L^2 + d^2 - 2 L d cos(phi + phiM0 - psi).  None if the
    four-bar assembles everywhere.  Returns (lo, hi, which) with which =
    'stretched' or 'folded'; assumes at most one of the two bounds is crossed."""
    with mpmath.workdps(DPS):
        mp = mpmath.mpf
        L, cx, cy, m = mp(v["crank.length"]), mp(v["P4.x"]), mp(v["P4.y"]), mp(v["crank.phiM0"])
        lab, lcb = mp(v["dyad.L_AB"]), mp(v["dyad.L_CB"])
        d = mpmath.sqrt(cx ** 2 + cy ** 2)
        psi = mpmath.atan2(cy, cx)
        S, D = lab + lcb, abs(lab - lcb)
        out = []
        c = (L ** 2 + d ** 2 - S ** 2) / (2 * L * d)      # locked where cos(th - psi) < c
        if c > -1:
            u = mpmath.acos(min(c, mp(1)))
            out.append((psi - m + u, psi - m + 2 * mpmath.pi - u, "stretched"))
        c = (L ** 2 + d ** 2 - D ** 2) / (2 * L * d)      # locked where cos(th - psi) > c
        if c < 1:
            u = mpmath.acos(max(c, mp(-1)))
            out.append((psi - m - u, psi - m + u, "folded"))
        if len(out) > 1:
            raise AssertionError("both bounds crossed: not a single lock")
        return out[0] if out else None


def fourbar_lock(rng, phi0, rot, n, which, w_deg=None):
    """A four-bar that cannot pass a range of width w: 'stretched' (coupler +
    rocker a hair shorter than the largest crank-tip distance) or 'folded'
    (|coupler - rocker| a hair longer than the smallest)."""
    w_deg = random_width_deg(rng) if w_deg is None else w_deg
    w = w_deg * DEG
    L = _u(rng, 5.0, 40.0)
    d = L * _u(rng, 1.5, 4.0)
    psi = _u(rng, -math.pi, math.pi)
    cx, cy = d * math.cos(psi), d * math.sin(psi)
    phic = _place(rng, phi0, rot, w)
    if which == "stretched":
        S = math.sqrt(L * L + d * d + 2 * L * d * math.cos(0.5 * w))
        D = _u(rng, -0.6, 0.6) * (d - L)
        m = wrap(psi + math.pi - phic)
    else:
        D = math.sqrt(L * L + d * d - 2 * L * d * math.cos(0.5 * w))
        D *= 1 if rng.random() < 0.5 else -1
        S = (d + L) * _u(rng, 1.15, 1.6)
        m = wrap(psi - phic)
    lab, lcb = 0.5 * (S + D), 0.5 * (S - D)
    W = 1 if rng.random() < 0.5 else -1
    case = Case(f"fourbar-{which}", "fourbar", _fourbar_values(L, cx, cy, m, lab, lcb, W),
                phi0, rot, n, "lock")
    lo, hi, got = fourbar_exact_lock(case.values)
    assert got == which
    return _finish(case, lo, hi)


def fourbar_healthy(rng, phi0, rot, n):
    """A crank-rocker whose transmission angle stays within [15, 165] deg."""
    while True:
        L = _u(rng, 5.0, 30.0)
        d = L * _u(rng, 1.8, 4.0)
        lab = d * _u(rng, 0.5, 2.0)
        lcb = d * _u(rng, 0.5, 2.0)
        cos_mu = [(lab ** 2 + lcb ** 2 - r ** 2) / (2 * lab * lcb) for r in (d - L, d + L)]
        if max(abs(c) for c in cos_mu) <= math.cos(15 * DEG):
            break
    psi = _u(rng, -math.pi, math.pi)
    m = _u(rng, -math.pi, math.pi)
    W = 1 if rng.random() < 0.5 else -1
    v = _fourbar_values(L, d * math.cos(psi), d * math.sin(psi), m, lab, lcb, W)
    assert fourbar_exact_lock(v) is None
    return Case("fourbar-healthy", "fourbar", v, phi0, rot, n, "ok")


def parallelogram(rng, phi0, rot, n):
    """Crank L, coupler d, rocker L, ground d along +x (exact in float64):
    started on the parallelogram branch, it reaches a collinear (toggle)
    position where the branch it is on meets the antiparallelogram."""
    L = _u(rng, 5.0, 40.0)
    d = L * (_u(rng, 1.5, 4.0) if rng.random() < 0.5 else _u(rng, 0.25, 0.67))
    while True:
        m = _u(rng, -math.pi, math.pi)
        if abs(math.sin(phi0 + m)) > math.sin(0.5 * DEG):
            break
    # parallelogram: B = C + (A - P1); cross(A - C, B - C) = -d L sin(th) = -W |...|
    W = 1 if math.sin(phi0 + m) > 0 else -1
    v = _fourbar_values(L, d, 0.0, m, d, L, W)
    case = Case("parallelogram", "fourbar", v, phi0, rot, n, "singular")
    with mpmath.workdps(DPS):
        # collinear where phi + phiM0 = k pi; the first after phi0 along the travel
        t = (rot * (-mpmath.mpf(m) - mpmath.mpf(phi0))) % mpmath.pi
        case.boundary = float(phi0 + rot * t)
        case.extra["t"] = float(t)
    return case


# ---- offset slider-crank (RRP on a fixed guide) ---------------------------------
def _slider_values(L, m, gx, gy, alpha, lab, W):
    return {"P1.x": 0.0, "P1.y": 0.0, "P3.x": float(gx), "P3.y": float(gy),
            "crank.length": float(L), "crank.phiM0": float(m), "slider.L_AB": float(lab),
            "slider.guide_angle": float(alpha), "slider.W": float(W)}


def slider_exact_lock(v):
    """Exact locked range of the slider-crank: the crank tip's signed distance
    from the guide line h = n.(A - G) = h0 + L sin(phi + phiM0 - alpha) must
    stay within [-L_AB, L_AB].  Assumes at most one side is crossed."""
    with mpmath.workdps(DPS):
        mp = mpmath.mpf
        L, m, gx, gy = mp(v["crank.length"]), mp(v["crank.phiM0"]), mp(v["P3.x"]), mp(v["P3.y"])
        al, lab = mp(v["slider.guide_angle"]), mp(v["slider.L_AB"])
        h0 = mpmath.sin(al) * gx - mpmath.cos(al) * gy      # n.(P1 - G), n = (-sin, cos)
        if abs(h0) + L <= lab:
            return None
        if L - abs(h0) > lab:
            raise AssertionError("both sides crossed")
        s = mpmath.asin((lab - abs(h0)) / L)
        if h0 > 0:       # locked where sin(th - alpha) > (lab - h0) / L
            return al + s - m, al + mpmath.pi - s - m
        return al - mpmath.pi + s - m, al - s - m


def slider_lock(rng, phi0, rot, n, w_deg=None):
    w_deg = random_width_deg(rng) if w_deg is None else w_deg
    w = w_deg * DEG
    L = _u(rng, 5.0, 40.0)
    h0 = L * _u(rng, 0.3, 1.5) * (1 if rng.random() < 0.5 else -1)
    al = _u(rng, -math.pi, math.pi)
    u, nn = (math.cos(al), math.sin(al)), (-math.sin(al), math.cos(al))
    tg = _u(rng, -2 * L, 2 * L)
    gx, gy = -h0 * nn[0] + tg * u[0], -h0 * nn[1] + tg * u[1]
    lab = abs(h0) + L * math.cos(0.5 * w)
    phic = _place(rng, phi0, rot, w)
    m = wrap(al + math.copysign(0.5 * math.pi, h0) - phic)
    W = 1 if rng.random() < 0.5 else -1
    case = Case("slider", "slider", _slider_values(L, m, gx, gy, al, lab, W), phi0, rot, n,
                "lock")
    lo, hi = slider_exact_lock(case.values)
    return _finish(case, lo, hi)


def slider_healthy(rng, phi0, rot, n):
    L = _u(rng, 5.0, 40.0)
    h0 = L * _u(rng, 0.0, 1.5) * (1 if rng.random() < 0.5 else -1)
    al = _u(rng, -math.pi, math.pi)
    u, nn = (math.cos(al), math.sin(al)), (-math.sin(al), math.cos(al))
    tg = _u(rng, -2 * L, 2 * L)
    lab = (abs(h0) + L) * _u(rng, 1.12, 2.0)       # |h| <= 0.9 L_AB: the rod clears
    v = _slider_values(L, _u(rng, -math.pi, math.pi), -h0 * nn[0] + tg * u[0],
                       -h0 * nn[1] + tg * u[1], al, lab, 1 if rng.random() < 0.5 else -1)
    assert slider_exact_lock(v) is None
    return Case("slider-healthy", "slider", v, phi0, rot, n, "ok")


# ---- coulisse (RPR) -------------------------------------------------------------
def _coulisse_values(L, m, cx, cy, e, gl, W):
    return {"P1.x": 0.0, "P1.y": 0.0, "P3.x": float(cx), "P3.y": float(cy),
            "crank.length": float(L), "crank.phiM0": float(m), "coulisse.offset": float(e),
            "coulisse.guide_length": float(gl), "coulisse.W": float(W)}


def coulisse_exact_lock(v):
    """Exact locked range of the coulisse: the block (crank tip A) must stay at
    least |offset| from the guide pivot C: |A - C|^2 = L^2 + d^2 -
    2 L d cos(phi + phiM0 - psi) >= e^2."""
    with mpmath.workdps(DPS):
        mp = mpmath.mpf
        L, m, cx, cy = mp(v["crank.length"]), mp(v["crank.phiM0"]), mp(v["P3.x"]), mp(v["P3.y"])
        e = mp(v["coulisse.offset"])
        d = mpmath.sqrt(cx ** 2 + cy ** 2)
        psi = mpmath.atan2(cy, cx)
        c = (L ** 2 + d ** 2 - e ** 2) / (2 * L * d)
        if c >= 1:
            return None
        u = mpmath.acos(c)
        return psi - m - u, psi - m + u


def coulisse_lock(rng, phi0, rot, n, w_deg=None):
    w_deg = random_width_deg(rng) if w_deg is None else w_deg
    w = w_deg * DEG
    L = _u(rng, 5.0, 40.0)
    d = L * _u(rng, 1.3, 3.0)
    psi = _u(rng, -math.pi, math.pi)
    e = math.sqrt(L * L + d * d - 2 * L * d * math.cos(0.5 * w)) * (1 if rng.random() < 0.5 else -1)
    phic = _place(rng, phi0, rot, w)
    m = wrap(psi - phic)
    case = Case("coulisse", "coulisse",
                _coulisse_values(L, m, d * math.cos(psi), d * math.sin(psi), e,
                                 _u(rng, 20.0, 100.0), 1 if rng.random() < 0.5 else -1),
                phi0, rot, n, "lock")
    lo, hi = coulisse_exact_lock(case.values)
    return _finish(case, lo, hi)


def coulisse_healthy(rng, phi0, rot, n):
    L = _u(rng, 5.0, 40.0)
    d = L * _u(rng, 1.3, 3.0)
    psi = _u(rng, -math.pi, math.pi)
    e = (d - L) * _u(rng, 0.0, 0.9) * (1 if rng.random() < 0.5 else -1)
    v = _coulisse_values(L, _u(rng, -math.pi, math.pi), d * math.cos(psi), d * math.sin(psi),
                         e, _u(rng, 20.0, 100.0), 1 if rng.random() < 0.5 else -1)
    assert coulisse_exact_lock(v) is None
    return Case("coulisse-healthy", "coulisse", v, phi0, rot, n, "ok")


# --------------------------------------------------------------------------- dyad scans
def dyad_assembly_scan(case, phis):
    """Brute force, numpy: (assembles, margin) of the case's dyad at the crank
    angles ``phis`` from the plain geometric condition (distances from the
    crank tip's coordinates; no cosine law).  margin: |sin| of the
    transmission angle (four-bar), |cos| of the rod-guide angle (slider),
    sqrt(|A-C|^2 - e^2)/|A-C| (coulisse)."""
    v = case.values
    th = phis + v["crank.phiM0"]
    ax, ay = v["crank.length"] * np.cos(th), v["crank.length"] * np.sin(th)
    if case.structure == "fourbar":
        r = np.hypot(ax - v["P4.x"], ay - v["P4.y"])
        lab, lcb = v["dyad.L_AB"], v["dyad.L_CB"]
        ok = (r <= lab + lcb) & (r >= abs(lab - lcb))
        cos_mu = np.clip((lab ** 2 + lcb ** 2 - r ** 2) / (2 * lab * lcb), -1, 1)
        return ok, np.sqrt(1 - cos_mu ** 2)
    if case.structure == "slider":
        al = v["slider.guide_angle"]
        h = -math.sin(al) * (ax - v["P3.x"]) + math.cos(al) * (ay - v["P3.y"])
        lab = v["slider.L_AB"]
        return np.abs(h) <= lab, np.sqrt(np.clip(1 - (h / lab) ** 2, 0, 1))
    if case.structure == "coulisse":
        r = np.hypot(ax - v["P3.x"], ay - v["P3.y"])
        e = abs(v["coulisse.offset"])
        return r >= e, np.sqrt(np.clip(r ** 2 - e ** 2, 0, None)) / r
    raise ValueError(case.structure)


def parallelogram_sign_scan(case, phis):
    """Brute force: sign of cross(A - C, B - C) on the parallelogram branch
    B = C + (A - P1); it is -W where the kernel's W branch is the parallelogram."""
    v = case.values
    th = phis + v["crank.phiM0"]
    ax, ay = v["crank.length"] * np.cos(th), v["crank.length"] * np.sin(th)
    ux, uy = ax - v["P4.x"], ay - v["P4.y"]
    return np.sign(ux * ay - uy * ax)


def dyad_assembles_mp(case, phi):
    """The dyad's assembly condition at one crank angle in mpmath (30 digits),
    from the crank tip's coordinates; for a parallelogram, the sign of
    cross(A - C, B - C) on its parallelogram branch."""
    v = case.values
    with mpmath.workdps(DPS):
        mp = mpmath.mpf
        th = mp(phi) + mp(v["crank.phiM0"])
        ax, ay = mp(v["crank.length"]) * mpmath.cos(th), mp(v["crank.length"]) * mpmath.sin(th)
        if case.expect == "singular":
            ux, uy = ax - mp(v["P4.x"]), ay - mp(v["P4.y"])
            return mpmath.sign(ux * ay - uy * ax)
        if case.structure == "fourbar":
            r = mpmath.hypot(ax - mp(v["P4.x"]), ay - mp(v["P4.y"]))
            lab, lcb = mp(v["dyad.L_AB"]), mp(v["dyad.L_CB"])
            return abs(lab - lcb) <= r <= lab + lcb
        if case.structure == "slider":
            al = mp(v["slider.guide_angle"])
            h = -mpmath.sin(al) * (ax - mp(v["P3.x"])) + mpmath.cos(al) * (ay - mp(v["P3.y"]))
            return abs(h) <= mp(v["slider.L_AB"])
        r = mpmath.hypot(ax - mp(v["P3.x"]), ay - mp(v["P3.y"]))
        return r >= abs(mp(v["coulisse.offset"]))


def _runs(mask):
    """Start and end indices (inclusive) of the runs of True in a 1-d mask."""
    m = np.concatenate([[False], mask, [False]]).astype(np.int8)
    d = np.diff(m)
    return np.flatnonzero(d == 1), np.flatnonzero(d == -1) - 1


def check_dyad_case(case, n_full=100_000, n_local=2001):
    """Brute-force check of a dyad case against its mpmath references; returns
    a list of problems (empty when the case is what it claims to be).

    * full revolution from phi0, n_full angles: a lock case fails on exactly
      one run of angles, containing its mpmath range; a healthy case
      assembles everywhere with margin > sin 15 deg (four-bar) / 0.3;
    * around each mpmath boundary, n_local angles over 3 w: the scan changes
      from assembling to not assembling between the two angles that bracket
      the boundary (to the scan's resolution);
    * a parallelogram's branch orientation first flips at its boundary;
    * in mpmath, 1e-9 rad (6e-8 deg) before the boundary the dyad assembles
      (the parallelogram is on the kernel's W branch) and 1e-9 rad after it
      does not (the W branch is the antiparallelogram)."""
    probs = []
    full = case.phi0 + case.rot * TWO_PI * np.arange(n_full) / n_full
    res = TWO_PI / n_full
    # at 1e-9 rad (6e-8 deg) either side of the boundary, in mpmath
    before = dyad_assembles_mp(case, case.boundary - case.rot * 1e-9)
    after = dyad_assembles_mp(case, case.boundary + case.rot * 1e-9)
    if case.expect == "singular":
        if not (before == -case.values["dyad.W"] and after == case.values["dyad.W"]):
            probs.append("mpmath: the orientation does not flip at the boundary")
    elif case.expect == "lock" and not (before and not after):
        probs.append("mpmath: not assembling 1e-9 rad before / locked 1e-9 rad after")
    if case.expect == "singular":
        s = parallelogram_sign_scan(case, full)
        W = case.values["dyad.W"]
        if s[0] != -W:
            probs.append("does not start on the parallelogram branch")
        k = int(np.argmax(s != s[0]))
        if abs(wrap(full[k] - case.boundary)) > res or abs(wrap(full[k - 1] - case.boundary)) > res:
            probs.append(f"first flip at {full[k]} not at {case.boundary}")
        loc = case.boundary + case.rot * np.linspace(-1e-6, 1e-6, 2001)
        s = parallelogram_sign_scan(case, loc)
        k = int(np.argmax(s != s[0]))
        if not (0 < k and abs(loc[k] - case.boundary) <= 2e-9):
            probs.append("local flip not at the boundary")
        return probs
    ok, margin = dyad_assembly_scan(case, full)
    if case.expect == "ok":
        floor = math.sin(15 * DEG) if case.structure == "fourbar" else 0.3
        if not ok.all() or margin.min() < floor:
            probs.append(f"healthy case fails or has margin {margin.min():.3g}")
        return probs
    if not ok[0]:
        probs.append("does not assemble at phi0")
    starts, ends = _runs(~ok)
    if len(starts) != 1 and case.width_deg > 360.0 / n_full:
        probs.append(f"{len(starts)} locked runs in the full scan")
    if len(starts) >= 1:
        first = full[starts[0]]
        if abs(wrap(first - case.boundary)) > res:
            probs.append(f"full scan enters the lock at {first}, mpmath {case.boundary}")
    lo, hi = case.lock
    w = hi - lo
    for b, inside in ((lo, +1), (hi, -1)):
        loc = b + np.linspace(-1.5 * w, 1.5 * w, n_local)
        ok_l, _ = dyad_assembly_scan(case, loc)
        step = loc[1] - loc[0]
        # exactly one change of state within one step of b
        change = np.flatnonzero(ok_l[1:] != ok_l[:-1])
        near = [j for j in change if loc[j] - step <= b <= loc[j + 1] + step]
        if len(near) != 1:
            probs.append(f"local scan: {len(near)} state changes at the boundary {b}")
            continue
        j = near[0]
        if inside > 0 and not (ok_l[j] and not ok_l[j + 1]):
            probs.append("lower boundary: not assembling -> locked")
        if inside < 0 and not (not ok_l[j] and ok_l[j + 1]):
            probs.append("upper boundary: not locked -> assembling")
    # the width: between the two boundaries the dyad never assembles
    mid = np.linspace(lo, hi, 1001)[1:-1]
    if dyad_assembly_scan(case, mid)[0].any():
        probs.append("assembles inside the mpmath range")
    return probs


# --------------------------------------------------------------------------- class III
B_GEOM = dict(L12=50.0, m=173.0 * DEG, P6=(195.0, 226.0), P7=(46.0, 533.0), L23=272.5,
              L34=81.0, L45=104.5, L35=174.0, L46=104.5, L57=261.0)
B_START = (44.006 * DEG, 128.709 * DEG)     # mechanism B's branch at phi1 = 0


@dataclass
class Triad:
    """Geometry of a crank + class III triad (floats, as in the parameter row)."""
    L12: float
    m: float
    p6: tuple
    p7: tuple
    L23: float
    L34: float
    L45: float
    L35: float
    L46: float
    L57: float

    def __post_init__(self):
        # the ternary link's angle at vertex 3 (orientation +1)
        self.U = math.acos((self.L34 ** 2 + self.L35 ** 2 - self.L45 ** 2)
                           / (2 * self.L34 * self.L35))

    @property
    def scale(self):
        """Normalisation of det J: the margin is |det J| / scale (DOMAIN.md section 9)."""
        return 4 * self.L23 * self.L46 * self.L57 * max(self.L34, self.L35)

    def values(self, a0, b0, phi_start):
        return {"P1.x": 0.0, "P1.y": 0.0, "P6.x": self.p6[0], "P6.y": self.p6[1],
                "P7.x": self.p7[0], "P7.y": self.p7[1], "crank.length": self.L12,
                "crank.phiM0": self.m, "triad.L23": self.L23, "triad.L34": self.L34,
                "triad.L45": self.L45, "triad.L35": self.L35, "triad.L46": self.L46,
                "triad.L57": self.L57, "triad.orientation": 1.0, "triad.a0": float(a0),
                "triad.b0": float(b0), "triad.phi_start": float(phi_start)}


def triad_from_values(v):
    return Triad(v["crank.length"], v["crank.phiM0"], (v["P6.x"], v["P6.y"]),
                 (v["P7.x"], v["P7.y"]), v["triad.L23"], v["triad.L34"], v["triad.L45"],
                 v["triad.L35"], v["triad.L46"], v["triad.L57"])


def triad_eval(g: Triad, phi, a, b, L57=None):
    """F1, F2 (squared-distance closure), the Jacobian d(F1, F2)/d(a, b) and
    dF/dphi, with math floats or numpy arrays."""
    L57 = g.L57 if L57 is None else L57
    lib = np if isinstance(a, np.ndarray) or isinstance(phi, np.ndarray) else math
    th = phi + g.m
    ct, st = lib.cos(th), lib.sin(th)
    ca, sa, cb, sb = lib.cos(a), lib.sin(a), lib.cos(b), lib.sin(b)
    cc, sc = lib.cos(b + g.U), lib.sin(b + g.U)
    p3x = g.L12 * ct + g.L23 * ca
    p3y = g.L12 * st + g.L23 * sa
    r4x, r4y = p3x + g.L34 * cb - g.p6[0], p3y + g.L34 * sb - g.p6[1]
    r5x, r5y = p3x + g.L35 * cc - g.p7[0], p3y + g.L35 * sc - g.p7[1]
    f1 = r4x * r4x + r4y * r4y - g.L46 ** 2
    f2 = r5x * r5x + r5y * r5y - L57 ** 2
    j11 = 2 * g.L23 * (r4y * ca - r4x * sa)
    j12 = 2 * g.L34 * (r4y * cb - r4x * sb)
    j21 = 2 * g.L23 * (r5y * ca - r5x * sa)
    j22 = 2 * g.L35 * (r5y * cc - r5x * sc)
    # d P2 / dphi = L12 (-sin th, cos th)
    f1p = 2 * g.L12 * (r4y * ct - r4x * st)
    f2p = 2 * g.L12 * (r5y * ct - r5x * st)
    return f1, f2, j11, j12, j21, j22, f1p, f2p


def triad_p5_distance(g: Triad, phi, a, b):
    th = phi + g.m
    x = g.L12 * math.cos(th) + g.L23 * math.cos(a) + g.L35 * math.cos(b + g.U) - g.p7[0]
    y = g.L12 * math.sin(th) + g.L23 * math.sin(a) + g.L35 * math.sin(b + g.U) - g.p7[1]
    return math.hypot(x, y)


def triad_newton(g, phi, a, b, tol=1e-12, maxiter=30):
    """Plain Newton on F1 = F2 = 0 from (a, b); (a, b, det) or None."""
    for _ in range(maxiter):
        f1, f2, j11, j12, j21, j22, _, _ = triad_eval(g, phi, a, b)
        det = j11 * j22 - j12 * j21
        if max(abs(f1) / (2 * g.L46), abs(f2) / (2 * g.L57)) <= tol * max(g.L46, g.L57):
            return a, b, det
        if det == 0 or not math.isfinite(det):
            return None
        a -= (f1 * j22 - j12 * f2) / det
        b -= (j11 * f2 - f1 * j21) / det
    return None


def triad_walk(g, phi_from, phi_to, a, b, max_step=0.5 * DEG, max_change=0.02,
               min_step=1e-12, record=False):
    """Continuation of the triad from (a, b) at phi_from to phi_to: tangent
    predictor, Newton corrector, steps bounded so that a and b change by at
    most ``max_change`` rad per step; a step whose Newton fails, whose det J
    changes sign or whose correction is large is halved.  Returns a dict:
    ok, a, b, det sign, the smallest margin on the way, the steps; with
    ``record`` the (phi, a, b) of every step."""
    direction = 1.0 if phi_to >= phi_from else -1.0
    phi = phi_from
    sol = triad_newton(g, phi, a, b)
    if sol is None:
        return {"ok": False, "why": "no solution at the start", "phi": phi}
    a, b, det = sol
    sign = math.copysign(1.0, det)
    margin = abs(det) / g.scale
    steps = 0
    path = [(phi, a, b)] if record else None
    h = max_step
    while direction * (phi_to - phi) > 0:
        f1, f2, j11, j12, j21, j22, f1p, f2p = triad_eval(g, phi, a, b)
        det = j11 * j22 - j12 * j21
        ta = -(f1p * j22 - j12 * f2p) / det          # da/dphi, db/dphi
        tb = -(j11 * f2p - f1p * j21) / det
        h = min(max_step, 2 * h, max_change / max(abs(ta), abs(tb), 1e-300))
        while True:
            hh = min(h, direction * (phi_to - phi))
            pn = phi + direction * hh
            sol = triad_newton(g, pn, a + ta * direction * hh, b + tb * direction * hh)
            if sol is not None:
                an, bn, dn = sol
                corr = max(abs(an - a - ta * direction * hh), abs(bn - b - tb * direction * hh))
                if math.copysign(1.0, dn) == sign and corr <= max_change and \
                        max(abs(an - a), abs(bn - b)) <= 2 * max_change:
                    break
            h = 0.5 * hh
            if h < min_step:
                return {"ok": False, "why": "step underflow", "phi": phi, "a": a, "b": b,
                        "margin": margin, "steps": steps}
        phi, a, b = pn, an, bn
        margin = min(margin, abs(dn) / g.scale)
        steps += 1
        if record:
            path.append((phi, a, b))
    return {"ok": True, "a": a, "b": b, "sign": sign, "margin": margin, "steps": steps,
            "phi": phi, "path": path}


def _fold_point(g, phi, a, b, tol=1e-14):
    """Float Newton on the fold curve G = (F1, det J) = 0 at fixed phi (finite-
    difference Jacobian); (a, b) or None."""
    def G(x, y):
        f1, _, j11, j12, j21, j22, _, _ = triad_eval(g, phi, x, y)
        return f1 / (2 * g.L46 ** 2), (j11 * j22 - j12 * j21) / g.scale

    h = 1e-7
    for _ in range(60):
        g1, g2 = G(a, b)
        a1, a2 = G(a + h, b)
        b1, b2 = G(a, b + h)
        m11, m12, m21, m22 = (a1 - g1) / h, (b1 - g1) / h, (a2 - g2) / h, (b2 - g2) / h
        det = m11 * m22 - m12 * m21
        if det == 0 or not math.isfinite(det):
            return None
        da = (g1 * m22 - m12 * g2) / det
        db = (m11 * g2 - g1 * m21) / det
        a -= da
        b -= db
        if max(abs(da), abs(db)) < tol:
            return a, b
    return None


class _FoldCurve:
    """The stationary point of |P5 - P7| along the chain P2-P3-P4-P6 (the
    triad without lead 5-7) followed in phi: M(phi) = |P5 - P7| there."""

    def __init__(self, g, phi, a, b):
        self.g = g
        self.last = (phi, a, b)

    def at(self, phi):
        p0, a, b = self.last
        sol = _fold_point(self.g, phi, a, b)
        if sol is None or max(abs(sol[0] - a), abs(sol[1] - b)) > 0.2 + 2 * abs(phi - p0):
            raise ValueError("lost the fold curve")
        self.last = (phi, sol[0], sol[1])
        return sol

    def M(self, phi):
        a, b = self.at(phi)
        return triad_p5_distance(self.g, phi, a, b)


def chain_distance_grid(g, phis, n_a=1440):
    """Brute force over the chain (lead 5-7 removed): for each crank angle and
    each of n_a angles a of lead 2-3 and both assembly modes of P4, the
    distance |P5 - P7| (NaN where P4 cannot be placed).  Returns (dist, a, b)
    of shape (len(phis), 2, n_a)."""
    phis = np.asarray(phis, float)[:, None, None]
    a = np.linspace(-math.pi, math.pi, n_a, endpoint=False)[None, None, :]
    sig = np.array([1.0, -1.0])[None, :, None]
    return _chain(g, phis, a, sig)


def _chain(g, phi, a, sig):
    th = phi + g.m
    p3x = g.L12 * np.cos(th) + g.L23 * np.cos(a)
    p3y = g.L12 * np.sin(th) + g.L23 * np.sin(a)
    rx, ry = g.p6[0] - p3x, g.p6[1] - p3y
    d = np.hypot(rx, ry)
    c = (d * d + g.L34 ** 2 - g.L46 ** 2) / (2 * d * g.L34)
    b = np.arctan2(ry, rx) + sig * np.arccos(np.clip(c, -1, 1))
    x = p3x + g.L35 * np.cos(b + g.U) - g.p7[0]
    y = p3y + g.L35 * np.sin(b + g.U) - g.p7[1]
    dist = np.where(np.abs(c) <= 1, np.hypot(x, y), np.nan)
    return dist, np.broadcast_to(a, dist.shape), b


def chain_extreme(g, phis, s, n_a=1440, refine=60):
    """Brute force: the largest (s = +1) or smallest (s = -1) |P5 - P7| the
    chain reaches at each crank angle: the best of a grid of a and both
    modes, refined by golden-section search within one grid step."""
    dist, aa, _ = chain_distance_grid(g, phis, n_a)
    val = np.where(np.isnan(dist), -np.inf, s * dist)
    flat = val.reshape(len(phis), -1)
    k = np.argmax(flat, axis=1)
    best = flat[np.arange(len(phis)), k]
    sig = np.where(k // n_a == 0, 1.0, -1.0)
    a_c = aa.reshape(len(phis), -1)[np.arange(len(phis)), k]
    h = TWO_PI / n_a
    lo, hi = a_c - h, a_c + h
    phi = np.asarray(phis, float)
    gr = (math.sqrt(5) - 1) / 2

    def f(x):
        d, _, _ = _chain(g, phi, x, sig)
        return np.where(np.isnan(d), -np.inf, s * d)

    x1, x2 = hi - gr * (hi - lo), lo + gr * (hi - lo)
    f1, f2 = f(x1), f(x2)
    for _ in range(refine):
        left = f1 >= f2
        hi = np.where(left, x2, hi)
        lo = np.where(left, lo, x1)
        x2n = np.where(left, x1, lo + gr * (hi - lo))
        x1n = np.where(left, hi - gr * (hi - lo), x2)
        f1, f2 = np.where(left, f(x1n), f2), np.where(left, f1, f(x2n))
        x1, x2 = x1n, x2n
    return s * np.maximum(best, np.maximum(f1, f2))


def triad_fold_mp(g: Triad, a, b, phi):
    """The fold point (a, b, phi) of F1 = F2 = det J = 0 near the float guess,
    by mpmath.findroot at 30 digits; returns mpf (a, b, phi)."""
    with mpmath.workdps(DPS):
        mp = mpmath.mpf
        L12, m, L23, L34, L35, L46, L57 = (mp(x) for x in (g.L12, g.m, g.L23, g.L34, g.L35,
                                                            g.L46, g.L57))
        L45 = mp(g.L45)
        U = mpmath.acos((L34 ** 2 + L35 ** 2 - L45 ** 2) / (2 * L34 * L35))
        p6x, p6y, p7x, p7y = mp(g.p6[0]), mp(g.p6[1]), mp(g.p7[0]), mp(g.p7[1])
        sc = 4 * L23 * L46 * L57 * max(L34, L35)

        def F(x, y, p):
            p3x = L12 * mpmath.cos(p + m) + L23 * mpmath.cos(x)
            p3y = L12 * mpmath.sin(p + m) + L23 * mpmath.sin(x)
            r4x = p3x + L34 * mpmath.cos(y) - p6x
            r4y = p3y + L34 * mpmath.sin(y) - p6y
            r5x = p3x + L35 * mpmath.cos(y + U) - p7x
            r5y = p3y + L35 * mpmath.sin(y + U) - p7y
            j11 = 2 * L23 * (r4y * mpmath.cos(x) - r4x * mpmath.sin(x))
            j12 = 2 * L34 * (r4y * mpmath.cos(y) - r4x * mpmath.sin(y))
            j21 = 2 * L23 * (r5y * mpmath.cos(x) - r5x * mpmath.sin(x))
            j22 = 2 * L35 * (r5y * mpmath.cos(y + U) - r5x * mpmath.sin(y + U))
            return [(r4x ** 2 + r4y ** 2 - L46 ** 2) / (2 * L46 ** 2),
                    (r5x ** 2 + r5y ** 2 - L57 ** 2) / (2 * L57 ** 2),
                    (j11 * j22 - j12 * j21) / sc]

        x = mpmath.findroot(F, (mp(a), mp(b), mp(phi)), tol=mp(10) ** (-2 * DPS + 6))
        res = max(abs(r) for r in F(x[0], x[1], x[2]))
        if res > mp(10) ** (-DPS + 4):
            raise ValueError(f"fold system residual {res}")
        return x[0], x[1], x[2]


def triad_reach_mp(g: Triad, phi, a_guess, sigma, s):
    """The extreme (s = +1: largest, s = -1: smallest) distance |P5 - P7| of the
    chain without lead 5-7 near the configuration with lead 2-3 at a_guess and
    assembly mode sigma of P4 (b = angle(P6 - P3) + sigma * angle at P3), in
    mpmath at 30 digits: a stationary point of |P5 - P7|^2 in a (root of its
    numerical derivative).  Independent of the fold system (no det J)."""
    with mpmath.workdps(DPS):
        mp = mpmath.mpf
        L12, m, L23, L34, L35, L46, L45 = (mp(x) for x in (g.L12, g.m, g.L23, g.L34, g.L35,
                                                            g.L46, g.L45))
        U = mpmath.acos((L34 ** 2 + L35 ** 2 - L45 ** 2) / (2 * L34 * L35))
        p6x, p6y, p7x, p7y = mp(g.p6[0]), mp(g.p6[1]), mp(g.p7[0]), mp(g.p7[1])
        ph = mp(phi)

        def dist2(a):
            p3x = L12 * mpmath.cos(ph + m) + L23 * mpmath.cos(a)
            p3y = L12 * mpmath.sin(ph + m) + L23 * mpmath.sin(a)
            rx, ry = p6x - p3x, p6y - p3y
            d = mpmath.hypot(rx, ry)
            b = mpmath.atan2(ry, rx) + sigma * mpmath.acos((d ** 2 + L34 ** 2 - L46 ** 2)
                                                           / (2 * d * L34))
            return (p3x + L35 * mpmath.cos(b + U) - p7x) ** 2 + \
                (p3y + L35 * mpmath.sin(b + U) - p7y) ** 2

        a = mpmath.findroot(lambda x: mpmath.diff(dist2, x),
                            (mp(a_guess), mp(a_guess) + mp(10) ** -7))
        if s * mpmath.diff(dist2, a, 2) > 0:
            raise ValueError("not the extreme sought")
        return mpmath.sqrt(dist2(a)), a


def triad_sigma(g: Triad, phi, a, b):
    """Assembly mode of P4 in the chain parametrisation at (phi, a, b)."""
    th = phi + g.m
    p3x = g.L12 * math.cos(th) + g.L23 * math.cos(a)
    p3y = g.L12 * math.sin(th) + g.L23 * math.sin(a)
    return 1 if wrap(b - math.atan2(g.p6[1] - p3y, g.p6[0] - p3x)) > 0 else -1


def random_triad(rng, spread=0.1):
    """Mechanism B's triad with every dimension perturbed (L57 left as B's)."""
    f = lambda x: x * _u(rng, 1 - spread, 1 + spread)
    while True:
        l34, l45, l35 = f(B_GEOM["L34"]), f(B_GEOM["L45"]), f(B_GEOM["L35"])
        if l45 < 0.97 * (l34 + l35) and l35 < 0.97 * (l34 + l45) and l34 < 0.97 * (l45 + l35):
            break
    return Triad(L12=f(B_GEOM["L12"]), m=_u(rng, -math.pi, math.pi),
                 p6=(f(B_GEOM["P6"][0]), f(B_GEOM["P6"][1])),
                 p7=(B_GEOM["P7"][0] + _u(rng, -30, 30), B_GEOM["P7"][1] + _u(rng, -30, 30)),
                 L23=f(B_GEOM["L23"]), L34=l34, L45=l45, L35=l35, L46=f(B_GEOM["L46"]),
                 L57=B_GEOM["L57"])


def _replace(g, **kw):
    d = {f.name: getattr(g, f.name) for f in fields(Triad)}
    d.update(kw)
    return Triad(**d)


def triad_lock(rng, rot, n, s=None, w_deg=None, tries=40):
    """A class III triad whose lead 5-7 is a hair too long (s = +1: L57 just
    above the smallest, over the revolution, of the largest |P5 - P7| the
    chain without lead 5-7 can reach) or too short (s = -1, the smallest
    reach), so that it cannot be assembled on a range of width w around
    the crank angle where that reach is extreme.  The start phi0 is placed at
    a random distance before the lock, the start (a0, b0) on a branch that
    meets the lock's first boundary (found by continuing backwards from the
    fold there with this module's own solver).  phi_start = phi0."""
    for _ in range(tries):
        case = _triad_lock_try(rng, rot, n, s, w_deg)
        if case is not None:
            return case
    raise RuntimeError("no triad lock case found")


REJECTS = {}


def _reject(why):
    """Count why a triad draw was rejected (diagnostics); returns None."""
    REJECTS[why] = REJECTS.get(why, 0) + 1
    return None


def _triad_lock_try(rng, rot, n, s, w_deg):
    s = (1 if rng.random() < 0.5 else -1) if s is None else s
    w_deg = random_width_deg(rng) if w_deg is None else w_deg
    w = w_deg * DEG
    g = random_triad(rng)
    coarse = np.arange(72) * 5.0 * DEG
    dist, aa, bb = chain_distance_grid(g, coarse, 720)
    if np.isnan(dist).all(axis=(1, 2)).any():
        return _reject("the chain locks")
    val = np.where(np.isnan(dist), -np.inf, s * dist).reshape(72, -1)
    k = int(np.argmin(val.max(axis=1)))
    j = int(np.argmax(val[k]))
    a_g, b_g = aa.reshape(72, -1)[k, j], bb.reshape(72, -1)[k, j]
    try:
        fc = _FoldCurve(g, coarse[k], *_fold_point(g, coarse[k], a_g, b_g))
        Ms = lambda p: s * fc.M(p)
        if abs(Ms(coarse[k]) - val[k, j]) > 1e-3 * abs(val[k, j]):
            return _reject("not the extreme the grid saw")
        from scipy.optimize import brentq, minimize_scalar
        opt = minimize_scalar(Ms, bounds=(coarse[k] - 6 * DEG, coarse[k] + 6 * DEG),
                              method="bounded", options={"xatol": 1e-10})
        phim = float(opt.x)
        if abs(phim - coarse[k]) > 5.9 * DEG:
            return _reject("no interior minimum")
        h = 1e-3
        m0, mp_, mm_ = Ms(phim), Ms(phim + h), Ms(phim - h)
        k2 = (mp_ + mm_ - 2 * m0) / h ** 2
        if not k2 > 1e-2:
            return _reject("flat minimum")
        L57 = s * (m0 + 0.5 * k2 * (0.5 * w) ** 2)
        if not L57 > 20.0:
            return _reject("L57 too short")
        g = _replace(g, L57=L57)
        fc.g = g
        f = lambda p: Ms(p) - s * L57
        fold = []
        for lo_, hi_ in ((phim - 1.5 * w, phim), (phim, phim + 1.5 * w)):
            fc.at(phim)
            p = brentq(f, lo_, hi_, xtol=1e-15, rtol=1e-15)
            a_f, b_f = fc.at(p)
            fold.append(triad_fold_mp(g, a_f, b_f, p))
    except (ValueError, ZeroDivisionError, RuntimeError):
        return _reject("fold curve or fold system failed")
    (a1, b1, p1), (a2, b2, p2) = fold
    if not 0.5 * w < float(p2 - p1) < 2.0 * w:
        return _reject("width off target")
    entry = (a1, b1, p1) if rot > 0 else (a2, b2, p2)
    width = float(p2 - p1)
    t = _u(rng, 10 * DEG, TWO_PI - width - 10 * DEG)
    phi_e = float(entry[2])
    phi0 = phi_e - rot * t
    start = _branch_start(g, entry, phi0, rot, w, rng)
    if start is None:
        return _reject("no branch from phi0 into the fold")
    a0, b0, walk = start
    case = Case(f"triad-{'long' if s > 0 else 'short'}", "triad", g.values(a0, b0, phi0),
                phi0, rot, n, "lock")
    case.extra.update(fold_entry=tuple(float(x) for x in entry), s=s,
                      walk_margin=walk["margin"], walk_steps=walk["steps"])
    return _finish(case, p1, p2)


def _near_fold_solutions(g, a_f, b_f, phi_f, eps):
    """The two solutions at phi_f + eps near the fold point (a_f, b_f):
    (a_f, b_f) +- c v sqrt(|eps|) from the fold's normal form, polished."""
    f1, f2, j11, j12, j21, j22, f1p, f2p = triad_eval(g, phi_f, a_f, b_f)
    # right null vector of J and left null vector
    if abs(j11) + abs(j12) > abs(j21) + abs(j22):
        v = (-j12, j11)
    else:
        v = (-j22, j21)
    nv = math.hypot(*v)
    v = (v[0] / nv, v[1] / nv)
    if abs(j11) + abs(j21) > abs(j12) + abs(j22):
        l = (-j21, j11)
    else:
        l = (-j22, j12)
    hh = 1e-4
    fp = triad_eval(g, phi_f, a_f + hh * v[0], b_f + hh * v[1])
    fm = triad_eval(g, phi_f, a_f - hh * v[0], b_f - hh * v[1])
    q = [(fp[i] + fm[i] - 2 * (f1, f2)[i]) / hh ** 2 for i in (0, 1)]
    lq = l[0] * q[0] + l[1] * q[1]
    lp = l[0] * f1p + l[1] * f2p
    s2 = -2 * lp * eps / lq
    if not s2 > 0:
        return []
    out = []
    for sgn in (1, -1):
        c = sgn * math.sqrt(s2)
        sol = triad_newton(g, phi_f + eps, a_f + c * v[0], b_f + c * v[1])
        if sol is not None and math.hypot(sol[0] - a_f, sol[1] - b_f) < 3 * abs(c) + 1e-6:
            out.append(sol)
    if len(out) == 2 and \
            math.hypot(out[0][0] - out[1][0], out[0][1] - out[1][1]) < 0.5 * math.sqrt(s2):
        return []
    return out


def _branch_start(g, entry, phi0, rot, w, rng):
    """Walk backwards from just before the fold at ``entry`` to phi0 on one of
    the two solutions that meet there; (a0, b0, walk) or None."""
    a_f, b_f, p_f = (float(x) for x in entry)
    eps = -rot * min(1e-5, 0.05 * w)
    sols = _near_fold_solutions(g, a_f, b_f, p_f, eps)
    if len(sols) != 2:
        return _reject("no two solutions near the fold")
    order = [0, 1] if rng.random() < 0.5 else [1, 0]
    for i in order:
        a, b, _ = sols[i]
        back = triad_walk(g, p_f + eps, phi0, a, b)
        if not back["ok"] or back["margin"] < 1e-7:
            continue
        # and forwards again, from the start the pipeline gets, to the fold
        fwd = triad_walk(g, phi0, p_f + eps, back["a"], back["b"])
        if not fwd["ok"] or math.hypot(fwd["a"] - a, fwd["b"] - b) > 1e-7:
            continue
        # away from the fold the branch is not near another singular position
        mid = triad_walk(g, phi0, p_f - rot * min(5 * DEG, 0.8 * abs(p_f - phi0)),
                         back["a"], back["b"])
        if not mid["ok"] or mid["margin"] < 1e-4:
            continue
        return back["a"], back["b"], fwd
    return _reject("no clean branch")


def triad_healthy(rng, phi0, rot, n, min_margin=0.05, tries=50):
    """Mechanism B with every dimension perturbed by up to 5 %, started on the
    branch continued from B's (by a homotopy in the dimensions at phi1 = 0,
    phiM0 = 173 deg, then in phi to phi0 with the perturbed phiM0); kept if
    the branch runs the whole revolution, closes, and its margin stays
    above ``min_margin``."""
    for _ in range(tries):
        tgt = random_triad(rng, spread=0.05)
        tgt = _replace(tgt, L57=B_GEOM["L57"] * _u(rng, 0.97, 1.03), m=B_GEOM["m"])
        base = Triad(B_GEOM["L12"], B_GEOM["m"], B_GEOM["P6"], B_GEOM["P7"], B_GEOM["L23"],
                     B_GEOM["L34"], B_GEOM["L45"], B_GEOM["L35"], B_GEOM["L46"], B_GEOM["L57"])
        sol = triad_newton(base, 0.0, *B_START)
        ok = sol is not None
        for k in range(1, 41):
            if not ok:
                break
            t = k / 40
            mix = Triad(*(
                tuple((1 - t) * x + t * y for x, y in zip(u, v)) if isinstance(u, tuple)
                else (1 - t) * u + t * v
                for u, v in ((getattr(base, f.name), getattr(tgt, f.name))
                             for f in fields(Triad))))
            sol = triad_newton(mix, 0.0, sol[0], sol[1])
            ok = sol is not None and abs(sol[2]) / mix.scale > min_margin
        if not ok:
            continue
        # the same branch with another mounting phase: phi -> phi + m - m_new
        m_new = _u(rng, -math.pi, math.pi)
        g = _replace(tgt, m=m_new)
        walk = triad_walk(g, 0.0 + tgt.m - m_new, phi0, sol[0], sol[1])
        if not walk["ok"]:
            continue
        rev = triad_walk(g, phi0, phi0 + rot * TWO_PI, walk["a"], walk["b"])
        if not rev["ok"] or rev["margin"] < min_margin:
            continue
        if abs(wrap(rev["a"] - walk["a"])) > 1e-9 or abs(wrap(rev["b"] - walk["b"])) > 1e-9:
            continue
        case = Case("triad-healthy", "triad", g.values(walk["a"], walk["b"], phi0), phi0, rot,
                    n, "ok")
        case.extra["margin"] = rev["margin"]
        return case
    raise RuntimeError("no healthy triad found")


def check_triad_case(case, n_local=401, n_a=720, walk_step_deg=0.1):
    """Brute-force check of a triad lock against its mpmath boundaries:

    * around each boundary, n_local crank angles over 3 w: the largest (or
      smallest) |P5 - P7| the chain can reach (grid of n_a angles a, both
      modes, golden refinement) crosses L57 between the two angles bracketing
      the mpmath boundary, and inside the range the triad cannot be
      assembled at all;
    * the branch started from (a0, b0) at phi0 reaches the entry fold:
      an independent fixed-step walk (steps of walk_step_deg, plain Newton
      from the last solution, no predictor), then steps halving the distance
      down to 1e-6 rad before the boundary, ends within O(sqrt(1e-6)) of the
      fold configuration."""
    probs = []
    g = triad_from_values(case.values)
    s = case.extra["s"]
    lo, hi = case.lock
    w = hi - lo
    for b, inside in ((lo, +1), (hi, -1)):
        loc = b + np.linspace(-1.5 * w, 1.5 * w, n_local)
        reach = chain_extreme(g, loc, s, n_a)
        ok = s * reach >= s * g.L57
        step = loc[1] - loc[0]
        change = np.flatnonzero(ok[1:] != ok[:-1])
        near = [j for j in change if loc[j] - step <= b <= loc[j + 1] + step]
        if len(near) != 1:
            probs.append(f"local scan: {len(near)} changes at {b} ({len(change)} in all)")
            continue
        j = near[0]
        if ok[j] != (inside > 0):
            probs.append("wrong side of the boundary")
    mid = np.linspace(lo, hi, 201)[1:-1]
    if (s * chain_extreme(g, mid, s, n_a) >= s * g.L57).any():
        probs.append("the chain reaches L57 inside the mpmath range")
    # 1e-9 rad (6e-8 deg) either side of the entry boundary, in mpmath: the chain
    # reaches L57 before it and not after it
    a_f, b_f, p_f = case.extra["fold_entry"]
    sigma = triad_sigma(g, p_f, a_f, b_f)
    try:
        for side, reach_ok in ((-1, True), (1, False)):
            reach, _ = triad_reach_mp(g, case.boundary + side * case.rot * 1e-9, a_f, sigma, s)
            if (s * (reach - mpmath.mpf(g.L57)) >= 0) != reach_ok:
                probs.append(f"mpmath reach on the wrong side of L57 {1e-9 * side:+g} rad "
                             "from the boundary")
    except (ValueError, ZeroDivisionError) as exc:
        probs.append(f"mpmath reach: {exc}")
    # fixed-step walk from the start to just before the entry
    sol = triad_newton(g, case.phi0, case.values["triad.a0"], case.values["triad.b0"])
    if sol is None:
        return probs + ["no solution at phi0 from (a0, b0)"]
    a, b, det0 = sol
    end = case.boundary - case.rot * 1e-6
    span = end - case.phi0
    nstep = int(abs(span) / (walk_step_deg * DEG)) + 1
    phis = case.phi0 + span * np.arange(1, nstep + 1) / nstep
    for p in phis[:-1]:
        sol = triad_newton(g, float(p), a, b)
        if sol is None or math.copysign(1, sol[2]) != math.copysign(1, det0) or \
                max(abs(sol[0] - a), abs(sol[1] - b)) > 0.05:
            return probs + [f"fixed-step walk lost the branch at {p}"]
        a, b = sol[0], sol[1]
    # the last approach: halve the distance to the boundary (graded steps)
    d = abs(float(phis[-2] - end)) if nstep > 1 else abs(span)
    while d > 1e-6:
        d = max(d / 2, 1e-6)
        p = case.boundary - case.rot * d
        sol = triad_newton(g, p, a, b)
        if sol is None or math.copysign(1, sol[2]) != math.copysign(1, det0):
            return probs + [f"graded walk lost the branch {d:.3g} rad before the boundary"]
        a, b = sol[0], sol[1]
    if math.hypot(a - a_f, b - b_f) > 0.05:
        probs.append(f"the branch ends {math.hypot(a - a_f, b - b_f):.3g} rad from the fold")
    return probs


def check_triad_healthy(case, step_deg=0.1, min_margin=0.05):
    """Brute-force check of a healthy triad: a fixed-step walk over the whole
    revolution from (a0, b0) (plain Newton from the last solution, steps of
    step_deg) keeps the sign of det J, a margin above ``min_margin`` and
    closes on its start."""
    g = triad_from_values(case.values)
    sol = triad_newton(g, case.phi0, case.values["triad.a0"], case.values["triad.b0"])
    if sol is None:
        return ["no solution at phi0"]
    a, b, det0 = sol
    a_start, b_start = a, b
    n = int(round(360.0 / step_deg))
    for k in range(1, n + 1):
        p = case.phi0 + case.rot * TWO_PI * k / n
        sol = triad_newton(g, p, a, b)
        if sol is None or math.copysign(1, sol[2]) != math.copysign(1, det0) or \
                max(abs(sol[0] - a), abs(sol[1] - b)) > 0.05:
            return [f"walk lost the branch at {p}"]
        a, b = sol[0], sol[1]
        if abs(sol[2]) / g.scale < min_margin:
            return [f"margin {abs(sol[2]) / g.scale:.3g} at {p}"]
    if abs(wrap(a - a_start)) > 1e-9 or abs(wrap(b - b_start)) > 1e-9:
        return ["the revolution does not close"]
    return []


# --------------------------------------------------------------------------- suites
def dyad_suite(seed=2024, n_each=80, n_parallelograms=60, n_healthy=(100, 60, 60)):
    """The dyad cases of the acceptance tests: locks of every kind, parallelograms,
    healthy mechanisms.  Crank grids: 360 positions mostly, some 72 and 720;
    random phi0 and direction."""
    rng = np.random.default_rng(seed)

    def grid():
        n = int(rng.choice([360] * 6 + [72, 720]))
        return _u(rng, -math.pi, math.pi), (1 if rng.random() < 0.5 else -1), n

    cases = []
    for k in range(n_each):
        cases.append(fourbar_lock(rng, *grid(), which="stretched"))
        cases.append(fourbar_lock(rng, *grid(), which="folded"))
        cases.append(slider_lock(rng, *grid()))
        cases.append(coulisse_lock(rng, *grid()))
    for k in range(n_parallelograms):
        cases.append(parallelogram(rng, *grid()))
    for k in range(n_healthy[0]):
        cases.append(fourbar_healthy(rng, *grid()))
    for k in range(n_healthy[1]):
        cases.append(slider_healthy(rng, *grid()))
    for k in range(n_healthy[2]):
        cases.append(coulisse_healthy(rng, *grid()))
    return cases


def triad_suite(seed=77, n_locks=24, n_healthy=12):
    rng = np.random.default_rng(seed)
    cases = []
    for k in range(n_locks):
        n = int(rng.choice([360, 360, 360, 72, 720]))
        rot = 1 if rng.random() < 0.5 else -1
        cases.append(triad_lock(rng, rot, n, s=(1 if k % 2 == 0 else -1)))
    for k in range(n_healthy):
        n = int(rng.choice([360, 360, 72, 720]))
        cases.append(triad_healthy(rng, _u(rng, -math.pi, math.pi),
                                   1 if rng.random() < 0.5 else -1, n))
    return cases


def fourbar_sweep_rows(seed, phi0, rot, n, n_locks=60, n_parallelograms=20, n_healthy=80):
    """Four-bar cases on the sweep study's one crank grid (phases vary through
    phiM0 and the pivot's direction)."""
    rng = np.random.default_rng(seed)
    cases = []
    for k in range(n_locks):
        cases.append(fourbar_lock(rng, phi0, rot, n, which="stretched" if k % 2 else "folded"))
    for k in range(n_parallelograms):
        cases.append(parallelogram(rng, phi0, rot, n))
    for k in range(n_healthy):
        cases.append(fourbar_healthy(rng, phi0, rot, n))
    order = rng.permutation(len(cases))
    return [cases[i] for i in order]
