"""Property tests (Hypothesis) for the kinematic group kernels.

Physics that cannot be faked, checked on random inputs (STYLE.md, "Tests for
numerical code"):

* every group keeps its link lengths / guide constraints, picks the assembly
  branch its mode W asks for (DOMAIN.md section 2), and its exact first and
  second analogs equal high-order central differences of an independently
  written closed-form (or Newton) position along a random smooth path of the
  known points;
* impossible inputs give NO_ASSEMBLY / a non-OK status and NaN, toggles give
  SINGULAR (or OK with finite numbers), never an exception;
* the invariant ``assert_no_silent_nan``: a NaN output always comes with a
  non-OK status.

The kernels are called directly on small (n_points, 2) arrays; the class III
revolution goes through ``Mechanism.compile()`` and ``scene.solve_curves``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, event, example, given, note, settings
from hypothesis import strategies as st

from pipeline.kernels import config as kc
from pipeline.group_types.rpr.kernels import rpr
from pipeline.group_types.rrp.kernels import rrp
from pipeline.group_types.rrr.kernels import rrr
from pipeline.kernels.groups import attach, crank
from pipeline.group_types.class3 import kernels as triad_kernels
from pipeline.group_types.class3.kernels import class3, ternary_angle
from pipeline.model.mechanism import Crank, Mechanism
from pipeline.group_types.class3.model import ClassIII
from pipeline.group_types.rrr.model import RRR
from pipeline.solve.scene import solve_curves
from support.tolerances import CLOSURE_MM, KERNEL_EXACT_REL, LENGTH_REL, SELF_FD_REL, WELL_INSIDE_REL

TOLS = kc.default_tolerances()
SING = float(TOLS[kc.T_SINGULAR])
SLACK = float(TOLS[kc.T_ASSEMBLY_SLACK])
KNOWN_STATUS = set(kc.STATUS_NAMES)

FD_STEP = 0.02            # FD stencil step, as a fraction of the motion's time scale
TOGGLE_REL = 1e-13        # "at a toggle": the exact construction perturbed by this (relative)
TOGGLE_NEAR_REL = 1e-8    # "near a toggle": this far inside (relative)

FAST = dict(deadline=None, database=None,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])


# ============================================================== invariants
def assert_no_silent_nan(pos, status, *analogs):
    """Every NaN (or inf) output must come with a non-OK status.

    ``pos`` (and each of ``analogs``) is (..., n_points, 2); ``status`` is a
    scalar (one group call) or has the shape of the leading axes (one status
    per crank position).  Pass only the analogs the call computed.
    """
    status = np.asarray(status)
    for name, arr in zip(("pos", "d1", "d2"), (pos,) + analogs):
        arr = np.asarray(arr, dtype=float)
        finite = np.isfinite(arr.reshape(status.shape + (-1,))).all(axis=-1)
        silent = ~finite & (status == kc.OK)
        assert not silent.any(), (
            f"non-finite {name} with status OK at {np.argwhere(silent).ravel().tolist()}")
    assert set(np.unique(status).tolist()) <= KNOWN_STATUS, f"unknown status {status}"


def assert_nan_point(i, pos, d1=None, d2=None):
    for name, arr in (("pos", pos), ("d1", d1), ("d2", d2)):
        if arr is not None:
            assert np.isnan(arr[i]).all(), f"{name}[{i}] = {arr[i]} should be NaN"


def assert_fd(name, exact, fd, scale, noise=0.0, rel=SELF_FD_REL):
    """Kernel analog vs finite difference, relative to the larger of the FD value
    and the scale of the inputs' own analogs, plus the FD's own rounding noise."""
    err = float(np.abs(np.asarray(exact) - fd).max())
    bound = rel * (float(np.abs(fd).max()) + scale) + noise
    assert err <= bound, f"{name}: exact {exact} vs FD {fd}: error {err:.3e} > {bound:.3e}"


# ============================================================== small geometry
def e(angle):
    return np.array([math.cos(angle), math.sin(angle)])


def perp(v):
    return np.array([-v[1], v[0]])


def cross(u, v):
    return float(u[0] * v[1] - u[1] * v[0])


def norm(v):
    return float(math.hypot(v[0], v[1]))


def rotate(v, alpha):
    c, s = math.cos(alpha), math.sin(alpha)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def wrap(x):
    return (x + math.pi) % (2.0 * math.pi) - math.pi


# 8th-order central differences, offsets 1..4 (same stencil as tests/support/naive.py)
_W1 = (4.0 / 5.0, -1.0 / 5.0, 4.0 / 105.0, -1.0 / 280.0)
_W2C = -205.0 / 72.0
_W2 = (8.0 / 5.0, -1.0 / 5.0, 8.0 / 315.0, -1.0 / 560.0)
OFFSETS = (0, 1, -1, 2, -2, 3, -3, 4, -4)   # centre first, then outward (continuation)


@dataclass(frozen=True)
class FD:
    """Central-difference analogs and bounds of their rounding noise."""
    d1: np.ndarray
    d2: np.ndarray
    noise1: float
    noise2: float


def fd_from_samples(samples, h, size=0.0):
    """First and second derivatives at t = 0 from samples[k] = f(k h), k = -4..4.
    The samples carry rounding of ~eps times the size of the geometry that
    produced them (``size``, mm) or of the samples themselves; the stencil
    amplifies it by ~10/h and ~30/h^2; the noise bounds keep a 100x margin."""
    f = {k: np.asarray(v, dtype=float) for k, v in samples.items()}
    d1 = sum(w * (f[k] - f[-k]) for k, w in zip(range(1, 5), _W1)) / h
    d2 = (_W2C * f[0] + sum(w * (f[k] + f[-k]) for k, w in zip(range(1, 5), _W2))) / h ** 2
    big = max([size] + [float(np.abs(v).max()) for v in f.values()]) * np.finfo(float).eps
    return FD(d1, d2, 1e3 * big / h, 3e3 * big / h ** 2)


def fd(fun, inputs, length, margin=1.0, size=0.0, sampler=None):
    """Analogs of ``fun(t)`` at t = 0 by central differences, or of a ``sampler``
    h -> {k: f(k h)} (a continuation solver walks outward from k = 0).
    ``length``: the shortest length of the group (sets the time scale with the
    inputs' speeds); ``margin``: its distance from a toggle; ``size``: the
    largest coordinate difference the reference computes with (rounding)."""
    if sampler is None:
        sampler = lambda h: {k: fun(k * h) for k in OFFSETS}     # noqa: E731
    h = fd_step(sampler, inputs, length, margin)
    return fd_from_samples(sampler(h), h, size)


def rate_of(v, a, length):
    """Relative rate (1/rad) of a motion with analogs of size v, a over ``length``."""
    return v / length + math.sqrt(a / length)


def fd_step(sampler, inputs, length, margin):
    """Stencil step: FD_STEP times the time scale of the motion.  The rate is the
    larger of the inputs' own and the output's, measured on the reference itself
    (coarse 2nd-order differences, never the kernel's analogs).  Near a toggle the
    analogs grow like 1/margin and the time left to reach it shrinks like
    margin / rate."""
    h0 = 1e-5
    f = sampler(h0)
    v = np.abs(f[1] - f[-1]).max() / (2 * h0)
    a = np.abs(f[1] - 2 * f[0] + f[-1]).max() / h0 ** 2
    rate = max([rate_of(v, a, length)] + [rate_of(p.speed(), p.accel(), length)
                                          for p in inputs])
    return min(0.1, FD_STEP * margin / max(rate, 1e-9))


@dataclass(frozen=True)
class Path:
    """A known point on a smooth path P(t) = p + v t + acc t^2 / 2 (t = phi1 - phi1_0),
    so P'(0) = v and P''(0) = acc are exact."""
    p: np.ndarray
    v: np.ndarray
    acc: np.ndarray

    def at(self, t):
        return self.p + self.v * t + 0.5 * self.acc * t * t

    def shift(self, origin):
        """The same motion seen from ``origin`` (the stencil then differences
        small numbers: less rounding noise)."""
        return Path(self.p - origin, self.v, self.acc)

    def speed(self):
        return norm(self.v)

    def accel(self):
        return norm(self.acc)


def kernel_arrays(paths, n_out):
    """pos, d1, d2 with the known points first and ``n_out`` unknown (NaN) rows."""
    n = len(paths) + n_out
    pos = np.full((n, 2), np.nan)
    d1 = np.full((n, 2), np.nan)
    d2 = np.full((n, 2), np.nan)
    for i, p in enumerate(paths):
        pos[i], d1[i], d2[i] = p.p, p.v, p.acc
    return pos, d1, d2


def motion_scale(paths, length):
    """Scales of the inputs' analogs: s1 for first, s2 for second analogs."""
    s1 = sum(p.speed() for p in paths)
    s2 = sum(p.accel() for p in paths) + s1 * s1 / length
    return s1, s2


# ============================================================== strategies
def real(lo, hi):
    """Floats in [lo, hi] without subnormal-like dust (|x| < 1e-6 becomes 0): the
    properties are about geometry, not about underflow."""
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False).map(
        lambda x: 0.0 if abs(x) < 1e-6 else x)


coord = real(-100.0, 100.0)
point = st.tuples(coord, coord).map(np.array)
vec = st.tuples(real(-50.0, 50.0), real(-50.0, 50.0)).map(np.array)
zero_or_vec = st.one_of(st.just(np.zeros(2)), vec)
length = real(1.0, 200.0)
angle = real(-math.pi, math.pi)
mode = st.sampled_from([-1.0, 1.0])
orders = st.sampled_from([0, 1, 2])


@st.composite
def paths(draw, p=point, v=zero_or_vec, a=zero_or_vec):
    return Path(draw(p), draw(v), draw(a))


# ============================================================== 1. RRR
def ref_rrr(A, C, l_ab, l_cb, w):
    """Circle intersection written independently: B = C + x e_CA + y n, with the
    side fixed by DOMAIN.md section 2: C->B = rot(A - C, -W U, L_CB) turns A - C
    clockwise for W = +1, so sign(cross(A - C, B - C)) = -W, i.e. y = -W |y|."""
    d = A - C
    r = norm(d)
    u = d / r
    x = (r * r + l_cb * l_cb - l_ab * l_ab) / (2.0 * r)
    y = math.sqrt(max(l_cb * l_cb - x * x, 0.0))
    return C + x * u - w * y * perp(u)


def call_rrr(A, C, l_ab, l_cb, w, order):
    pos, d1, d2 = kernel_arrays([A, C], 1)
    st_, margin = rrr(pos, d1, d2, 0, 1, 2, l_ab, l_cb, w, order, SING, SLACK)
    return int(st_), float(margin), pos, d1, d2


def computed(pos, d1, d2, order):
    return (pos, d1, d2)[:order + 1]


@settings(max_examples=300, **FAST)
@given(A=paths(), C=paths(), l_ab=length, l_cb=length, w=mode, order=orders)
@example(A=Path(np.zeros(2), np.ones(2), np.zeros(2)), C=Path(np.zeros(2), np.zeros(2),
         np.zeros(2)), l_ab=10.0, l_cb=10.0, w=1.0, order=2)       # A == C
def test_rrr_random_inputs(A, C, l_ab, l_cb, w, order):
    """Any inputs: status decided by the triangle inequality, lengths kept, the
    branch of DOMAIN.md section 2, the differentiated closure; never NaN with OK."""
    status, margin, pos, d1, d2 = call_rrr(A, C, l_ab, l_cb, w, order)
    assert_no_silent_nan(pos, status, *computed(pos, d1, d2, order)[1:])
    r = norm(A.p - C.p)
    gap = WELL_INSIDE_REL * (l_ab + l_cb)
    feasible = r > abs(l_ab - l_cb) + gap and r < l_ab + l_cb - gap
    impossible = r > (l_ab + l_cb) * (1 + WELL_INSIDE_REL) or r < abs(l_ab - l_cb) * (
        1 - WELL_INSIDE_REL) or r == 0.0
    note(f"|AC| = {r!r}, status {status}, margin {margin!r}")
    if impossible:
        assert status == kc.NO_ASSEMBLY
        assert_nan_point(2, *computed(pos, d1, d2, order))
        return
    if not feasible:
        return  # within the slack of a toggle: only the invariant above
    assert status == kc.OK
    B = pos[2]
    assert abs(norm(B - A.p) - l_ab) <= LENGTH_REL * l_ab
    assert abs(norm(B - C.p) - l_cb) <= LENGTH_REL * l_cb
    sin_b = cross(A.p - B, C.p - B) / (l_ab * l_cb)
    assert margin == pytest.approx(abs(sin_b), rel=1e-6, abs=1e-12)
    if margin > 1e-6:
        assert np.sign(cross(A.p - C.p, B - C.p)) == -w, "branch does not match W"
        np.testing.assert_allclose(B, ref_rrr(A.p, C.p, l_ab, l_cb, w),
                                   rtol=0, atol=LENGTH_REL * (l_ab + l_cb) / margin)
    if order >= 1:
        # (B - A).(B' - A') = 0 and (B - C).(B' - C') = 0
        for P, L in ((A, l_ab), (C, l_cb)):
            res = np.dot(B - P.p, d1[2] - P.v)
            assert abs(res) <= KERNEL_EXACT_REL * L * (norm(d1[2]) + P.speed()) / margin
    if order >= 2:
        # (B - P).(B'' - P'') + |B' - P'|^2 = 0
        for P, L in ((A, l_ab), (C, l_cb)):
            q = d1[2] - P.v
            res = np.dot(B - P.p, d2[2] - P.acc) + np.dot(q, q)
            scale = L * (norm(d2[2]) + P.accel()) + np.dot(q, q)
            assert abs(res) <= KERNEL_EXACT_REL * scale / margin


@st.composite
def rrr_assembled(draw):
    """A, C and the solution B drawn first: lengths and W follow, so the dyad
    assembles by construction; the angle at B is kept away from a toggle."""
    A, C = draw(paths(v=vec, a=zero_or_vec)), draw(paths(v=zero_or_vec, a=zero_or_vec))
    B = draw(point)
    l_ab, l_cb, r = norm(B - A.p), norm(B - C.p), norm(A.p - C.p)
    assume(min(l_ab, l_cb, r) > 5.0)
    sin_b = abs(cross(A.p - B, C.p - B)) / (l_ab * l_cb)
    assume(sin_b > 0.2)
    w = -float(np.sign(cross(A.p - C.p, B - C.p)))
    return A, C, B, l_ab, l_cb, w, sin_b


@settings(max_examples=150, **FAST)
@given(case=rrr_assembled())
def test_rrr_analogs_match_finite_differences(case):
    """A and C move along random smooth paths: the kernel's d1, d2 at t = 0 equal
    8th-order central differences of the independent closed form B(t)."""
    A, C, B0, l_ab, l_cb, w, sin_b = case
    status, margin, pos, d1, d2 = call_rrr(A, C, l_ab, l_cb, w, 2)
    assert status == kc.OK
    np.testing.assert_allclose(pos[2], B0, rtol=0, atol=LENGTH_REL * (l_ab + l_cb) / sin_b)
    lmin = min(l_ab, l_cb, norm(A.p - C.p))
    s1, s2 = motion_scale([A, C], lmin)
    As, Cs = A.shift(C.p), C.shift(C.p)
    f = fd(lambda t: ref_rrr(As.at(t), Cs.at(t), l_ab, l_cb, w), [A, C], lmin, sin_b,
           size=l_ab + l_cb + norm(A.p - C.p))
    note(f"kernel d1 {d1[2]}, d2 {d2[2]}")
    assert_fd("B'", d1[2], f.d1, s1, f.noise1)
    assert_fd("B''", d2[2], f.d2, s2, f.noise2)


@settings(max_examples=200, **FAST)
@given(C=point, theta=angle, l_ab=real(5.0, 200.0),
       ratio=st.one_of(real(0.2, 0.8), real(1.25, 5.0)),
       kind=st.sampled_from(["outer", "inner"]),
       rel=st.sampled_from([0.0, TOGGLE_REL, -TOGGLE_REL, 0.1 * TOGGLE_REL,
                            -0.1 * TOGGLE_REL, TOGGLE_NEAR_REL]),
       w=mode, order=orders)
def test_rrr_at_and_near_toggle(C, theta, l_ab, ratio, kind, rel, w, order):
    """|AC| = L_AB + L_CB (outer) or |L_AB - L_CB| (inner), exactly or within
    1e-13 relative: SINGULAR, or OK with finite numbers (the slack of the cosine
    law absorbs the rounding); 1e-8 inside: OK (its margin, ~1e-4, is far above
    the singular tolerance); never an exception, never a silent NaN."""
    l_cb = ratio * l_ab
    if kind == "outer":
        r = (l_ab + l_cb) * (1.0 - rel)       # rel > 0: inside
    else:
        r = abs(l_ab - l_cb) * (1.0 + rel)
    A = Path(C + r * e(theta), np.array([3.0, -7.0]), np.array([1.0, 2.0]))
    Cp = Path(np.asarray(C), np.array([-1.0, 0.5]), np.zeros(2))
    status, margin, pos, d1, d2 = call_rrr(A, Cp, l_ab, l_cb, w, order)
    note(f"status {status}, margin {margin!r}")
    assert status in (kc.OK, kc.SINGULAR)
    assert_no_silent_nan(pos, status, *computed(pos, d1, d2, order)[1:])
    assert np.isfinite(pos[2]).all(), "the toggle position itself is defined"
    assert abs(norm(pos[2] - Cp.p) - l_cb) <= LENGTH_REL * l_cb
    assert abs(norm(pos[2] - A.p) - l_ab) <= 1e-6 * l_ab
    if rel == TOGGLE_NEAR_REL:
        assert status == kc.OK, "1e-8 inside a toggle is far above the singular tolerance"
    if status == kc.SINGULAR and order >= 1:
        assert_nan_point(2, None, d1, d2 if order >= 2 else None)


@settings(max_examples=100, **FAST)
@given(C=point, theta=angle, l_ab=real(5.0, 200.0), ratio=real(0.2, 5.0),
       kind=st.sampled_from(["outer", "inner"]), w=mode, order=orders)
def test_rrr_clearly_impossible(C, theta, l_ab, ratio, kind, w, order):
    """1e-6 outside the outer or inner toggle: NO_ASSEMBLY and a NaN point."""
    l_cb = ratio * l_ab
    assume(abs(l_ab - l_cb) > 0.05 * l_ab)
    r = (l_ab + l_cb) * (1.0 + 1e-6) if kind == "outer" else abs(l_ab - l_cb) * (1.0 - 1e-6)
    A = Path(C + r * e(theta), np.ones(2), np.ones(2))
    status, margin, pos, d1, d2 = call_rrr(A, Path(np.asarray(C), np.zeros(2), np.zeros(2)),
                                           l_ab, l_cb, w, order)
    assert status == kc.NO_ASSEMBLY
    assert_nan_point(2, *computed(pos, d1, d2, order))


# ============================================================== 2. RRP and RPR
def guide_direction(angle_, ga, gb, t):
    """Unit vector of the guide at t: fixed absolute angle, or the link ga->gb
    turned by ``angle_``."""
    if ga is None:
        return e(angle_)
    d = gb.at(t) - ga.at(t)
    return rotate(d / norm(d), angle_)


def ref_rrp(A, G, u, l_ab, w):
    """B = G + s u on the guide with |B - A| = L: s^2 - 2 s u.(A - G) + |A - G|^2 - L^2 = 0;
    mode W takes the root with (B - A).u = W sqrt(disc)."""
    d = A - G
    p = float(np.dot(u, d))
    disc = p * p - float(np.dot(d, d)) + l_ab * l_ab
    return G + (p + w * math.sqrt(max(disc, 0.0))) * u


def call_rrp(A, G, ga, gb, l_ab, angle_, w, order):
    known = [A, G] + ([ga, gb] if ga is not None else [])
    pos, d1, d2 = kernel_arrays(known, 1)
    ib = len(known)
    ia_, ib_ = (2, 3) if ga is not None else (-1, -1)
    st_, margin = rrp(pos, d1, d2, 0, 1, ib, ia_, ib_, l_ab, angle_, w, order, SING, SLACK)
    return int(st_), float(margin), pos, d1, d2, ib


def guide_rate(ga, gb):
    """Guide angle analog th' at t = 0 (0 for a fixed guide), from the definition
    th = atan2(gb - ga) + angle: th' = (d x d') / |d|^2."""
    if ga is None:
        return 0.0
    d, v = gb.p - ga.p, gb.v - ga.v
    return cross(d, v) / float(np.dot(d, d))


@st.composite
def guides(draw):
    """(angle, ga, gb): a fixed guide, or one turning with a link ga->gb."""
    angle_ = draw(angle)
    if draw(st.booleans()):
        return angle_, None, None
    ga = draw(paths())
    gb = draw(paths())
    assume(norm(gb.p - ga.p) > 5.0)
    return angle_, ga, gb


@settings(max_examples=250, **FAST)
@given(A=paths(), G=paths(), guide=guides(), l_ab=length, w=mode, order=orders)
def test_rrp_random_inputs(A, G, guide, l_ab, w, order):
    """Any inputs: OK when A is within L of the guide line (B on the line, |B - A| = L,
    (B - A).u has the sign of W, differentiated constraints hold), NO_ASSEMBLY
    and NaN when it is farther; never NaN with OK."""
    angle_, ga, gb = guide
    status, margin, pos, d1, d2, ib = call_rrp(A, G, ga, gb, l_ab, angle_, w, order)
    assert_no_silent_nan(pos, status, *computed(pos, d1, d2, order)[1:])
    u = guide_direction(angle_, ga, gb, 0.0)
    dist = abs(cross(u, A.p - G.p))       # distance of A from the guide line
    note(f"distance {dist!r}, L {l_ab!r}, status {status}, margin {margin!r}")
    if dist > l_ab * (1.0 + WELL_INSIDE_REL):
        assert status == kc.NO_ASSEMBLY
        assert_nan_point(ib, *computed(pos, d1, d2, order))
        return
    if dist > l_ab * (1.0 - WELL_INSIDE_REL):
        return
    assert status == kc.OK
    B = pos[ib]
    scale = l_ab + norm(A.p - G.p)
    assert abs(norm(B - A.p) - l_ab) <= LENGTH_REL * l_ab
    assert abs(cross(u, B - G.p)) <= LENGTH_REL * scale, "B is off the guide"
    cos_ = float(np.dot(B - A.p, u)) / l_ab
    assert margin == pytest.approx(abs(cos_), rel=1e-6, abs=1e-9)
    if margin > 1e-6:
        assert np.sign(cos_) == w, "slider on the wrong side (mode W)"
    th1 = guide_rate(ga, gb)
    n = perp(u)
    if order >= 1:
        v = d1[ib]
        # |B - A| = L: (B - A).(B' - A') = 0;  on the line: (B - G) x u = 0 differentiated:
        # (B' - G') x u + th' (B - G) x n = 0
        assert abs(np.dot(B - A.p, v - A.v)) <= KERNEL_EXACT_REL * l_ab * (
            norm(v) + A.speed() + 1.0) / margin
        line = cross(v - G.v, u) + th1 * cross(B - G.p, n)
        assert abs(line) <= KERNEL_EXACT_REL * (norm(v) + G.speed() + abs(th1) * scale
                                                + 1.0) / margin
    if order >= 2:
        # (B - A).(B'' - A'') + |B' - A'|^2 = 0
        q = d1[ib] - A.v
        res = np.dot(B - A.p, d2[ib] - A.acc) + np.dot(q, q)
        bound = l_ab * (norm(d2[ib]) + A.accel() + 1.0) + np.dot(q, q)
        assert abs(res) <= KERNEL_EXACT_REL * bound / margin


@st.composite
def rrp_assembled(draw):
    """Guide, slider position s0 on it and the link direction drawn first."""
    angle_, ga, gb = draw(guides())
    G = draw(paths(v=zero_or_vec))
    if ga is not None:
        # a slower guide: its turning moves B by s th' with an arm s up to 150 mm
        ga, gb = Path(ga.p, ga.v * 0.2, ga.acc * 0.2), Path(gb.p, gb.v * 0.2, gb.acc * 0.2)
    u = guide_direction(angle_, ga, gb, 0.0)
    s0 = draw(real(-150.0, 150.0))
    l_ab = draw(real(5.0, 200.0))
    psi = draw(angle)
    cos_ = math.cos(psi)
    assume(abs(cos_) > 0.2)
    B0 = G.p + s0 * u
    A = Path(B0 - l_ab * rotate(u, psi), draw(zero_or_vec), draw(zero_or_vec))
    w = float(np.sign(cos_))
    return A, G, angle_, ga, gb, l_ab, w, B0, abs(cos_)


@settings(max_examples=150, **FAST)
@given(case=rrp_assembled())
def test_rrp_analogs_match_finite_differences(case):
    """Fixed and turning guides: d1, d2 equal central differences of the independent
    closed form along random paths of A, G and the guide link."""
    A, G, angle_, ga, gb, l_ab, w, B0, cos_ = case
    status, margin, pos, d1, d2, ib = call_rrp(A, G, ga, gb, l_ab, angle_, w, 2)
    assert status == kc.OK
    np.testing.assert_allclose(pos[ib], B0, rtol=0, atol=1e-9 * (norm(B0 - G.p) + l_ab) / cos_)
    moving = [A, G] + ([ga, gb] if ga is not None else [])
    lg = norm(gb.p - ga.p) if ga is not None else math.inf
    lmin = min(l_ab, lg)
    s1, s2 = motion_scale(moving, lmin)
    arm = norm(B0 - G.p)              # B moves by s th' across the guide
    s1 += arm * s1 / lg
    s2 += arm * s2 / lg
    o = G.p
    As, Gs = A.shift(o), G.shift(o)
    gas, gbs = (ga.shift(o), gb.shift(o)) if ga is not None else (None, None)
    f = fd(lambda t: ref_rrp(As.at(t), Gs.at(t), guide_direction(angle_, gas, gbs, t), l_ab, w),
           moving, lmin, cos_, size=l_ab + arm + norm(A.p - G.p))
    note(f"kernel d1 {d1[ib]}, d2 {d2[ib]}")
    assert_fd("B'", d1[ib], f.d1, s1, f.noise1)
    assert_fd("B''", d2[ib], f.d2, s2, f.noise2)


@settings(max_examples=150, **FAST)
@given(G=point, guide=guides(), p=real(-100.0, 100.0), l_ab=real(5.0, 200.0),
       side=mode, w=mode, order=orders,
       rel=st.sampled_from([0.0, TOGGLE_REL, -TOGGLE_REL, TOGGLE_NEAR_REL, -1e-6]))
@example(G=np.zeros(2), guide=(0.0, None, None), p=3.0, l_ab=10.0, side=1.0, w=1.0, order=2,
         rel=0.0)   # exactly perpendicular, no rounding at all: margin 0
def test_rrp_at_and_near_toggle(G, guide, p, l_ab, side, w, order, rel):
    """Link perpendicular to the guide (A at distance L from it): SINGULAR or OK
    with finite numbers; 1e-8 inside: OK; 1e-6 outside: NO_ASSEMBLY and NaN."""
    angle_, ga, gb = guide
    u = guide_direction(angle_, ga, gb, 0.0)
    A = Path(G + p * u + side * l_ab * (1.0 - rel) * perp(u), np.array([2.0, -1.0]),
             np.array([0.5, 0.5]))
    Gp = Path(np.asarray(G, float), np.zeros(2), np.zeros(2))
    status, margin, pos, d1, d2, ib = call_rrp(A, Gp, ga, gb, l_ab, angle_, w, order)
    note(f"status {status}, margin {margin!r}")
    assert_no_silent_nan(pos, status, *computed(pos, d1, d2, order)[1:])
    if rel < 0.0 and abs(rel) > 1e-9:
        assert status == kc.NO_ASSEMBLY
        assert_nan_point(ib, *computed(pos, d1, d2, order))
        return
    assert status in (kc.OK, kc.SINGULAR)
    assert np.isfinite(pos[ib]).all()
    assert abs(norm(pos[ib] - A.p) - l_ab) <= 1e-6 * l_ab
    if rel == TOGGLE_NEAR_REL:
        assert status == kc.OK
    if status == kc.SINGULAR and order >= 1:
        assert_nan_point(ib, None, d1, d2 if order >= 2 else None)


def ref_rpr(A, C, offset, guide_length, w):
    """Guide direction u with A - C = s u + e n (n = u turned +90 deg),
    s = W sqrt(|A - C|^2 - e^2): perp(A - C) = s n - e u, hence
    u = (s (A - C) - e perp(A - C)) / |A - C|^2."""
    d = A - C
    rho2 = float(np.dot(d, d))
    s = w * math.sqrt(max(rho2 - offset * offset, 0.0))
    u = (s * d - offset * perp(d)) / rho2
    return C + guide_length * u


def call_rpr(A, C, offset, guide_length, w, order):
    pos, d1, d2 = kernel_arrays([A, C], 1)
    st_, margin = rpr(pos, d1, d2, 0, 1, 2, offset, guide_length, w, order, SING, SLACK)
    return int(st_), float(margin), pos, d1, d2


offsets = st.one_of(st.just(0.0), real(0.5, 60.0), real(-60.0, -0.5))


@settings(max_examples=250, **FAST)
@given(A=paths(), C=paths(), offset=offsets, guide_length=length, w=mode, order=orders)
def test_rpr_random_inputs(A, C, offset, guide_length, w, order):
    """Any inputs: OK when the block can reach the guide (|A - C| > |e|): the guide
    end at guide_length from C, A at signed distance e from the guide line, on
    the W side; NO_ASSEMBLY and NaN when |A - C| < |e|; never NaN with OK."""
    status, margin, pos, d1, d2 = call_rpr(A, C, offset, guide_length, w, order)
    assert_no_silent_nan(pos, status, *computed(pos, d1, d2, order)[1:])
    rho = norm(A.p - C.p)
    note(f"rho {rho!r}, status {status}, margin {margin!r}")
    if rho < abs(offset) * (1.0 - WELL_INSIDE_REL):
        assert status == kc.NO_ASSEMBLY
        assert_nan_point(2, *computed(pos, d1, d2, order))
        return
    if rho < abs(offset) * (1.0 + WELL_INSIDE_REL) or rho < 1e-6:
        return
    assert status == kc.OK
    u = (pos[2] - C.p) / guide_length
    assert abs(norm(pos[2] - C.p) - guide_length) <= LENGTH_REL * guide_length
    d = A.p - C.p
    s = float(np.dot(d, u))
    assert abs(float(np.dot(d, perp(u))) - offset) <= LENGTH_REL * (rho + abs(offset))
    assert margin == pytest.approx(abs(s) / guide_length, rel=1e-6)
    if abs(s) > 1e-6 * rho:
        assert np.sign(s) == w, "block on the wrong side of the pivot (mode W)"
    if order >= 1:
        # |B - C| = Lg: (B - C).(B' - C') = 0
        assert abs(np.dot(pos[2] - C.p, d1[2] - C.v)) <= KERNEL_EXACT_REL * guide_length * (
            norm(d1[2]) + C.speed() + 1.0)


@st.composite
def rpr_assembled(draw):
    """A coulisse that assembles, its block at least 0.2 |A - C| from the toggle."""
    A, C = draw(paths(v=vec)), draw(paths())
    offset = draw(offsets)
    guide_length = draw(real(5.0, 200.0))
    w = draw(mode)
    rho = norm(A.p - C.p)
    assume(rho > 5.0 and rho * rho - offset * offset > (0.2 * rho) ** 2)
    return A, C, offset, guide_length, w


@settings(max_examples=150, **FAST)
@given(case=rpr_assembled())
def test_rpr_analogs_match_finite_differences(case):
    """With and without offset: d1, d2 of the guide end equal central differences
    of the independent closed form along random paths of A and C."""
    A, C, offset, guide_length, w = case
    status, margin, pos, d1, d2 = call_rpr(A, C, offset, guide_length, w, 2)
    assert status == kc.OK
    np.testing.assert_allclose(pos[2], ref_rpr(A.p, C.p, offset, guide_length, w), rtol=0,
                               atol=LENGTH_REL * 10 * guide_length)
    rho = norm(A.p - C.p)
    s = math.sqrt(rho * rho - offset * offset)
    s1, s2 = motion_scale([A, C], s)
    As, Cs = A.shift(C.p), C.shift(C.p)
    f = fd(lambda t: ref_rpr(As.at(t), Cs.at(t), offset, guide_length, w), [A, C], s, s / rho,
           size=rho + abs(offset) + guide_length)
    k = guide_length / s
    note(f"kernel d1 {d1[2]}, d2 {d2[2]}")
    assert_fd("B'", d1[2], f.d1, k * s1, f.noise1)
    assert_fd("B''", d2[2], f.d2, k * s2, f.noise2)


def rpr_toggle_case(C, theta, offset, sign, guide_length, w, order, rel):
    A = Path(C + offset * (1.0 + rel) * e(theta), np.array([1.0, 3.0]), np.array([-2.0, 1.0]))
    Cp = Path(np.asarray(C, float), np.zeros(2), np.zeros(2))
    status, margin, pos, d1, d2 = call_rpr(A, Cp, sign * offset, guide_length, w, order)
    note(f"|A - C| / |e| - 1 = {norm(A.p - Cp.p) / offset - 1.0:.3e}, "
         f"status {kc.STATUS_NAMES[status]}, margin {margin!r}")
    assert_no_silent_nan(pos, status, *computed(pos, d1, d2, order)[1:])
    return status, pos


rpr_toggle_args = dict(C=point, theta=angle, offset=real(1.0, 60.0), sign=mode,
                       guide_length=real(5.0, 200.0), w=mode, order=orders)


@settings(max_examples=100, **FAST)
@given(rel=st.sampled_from([TOGGLE_NEAR_REL, WELL_INSIDE_REL]), **rpr_toggle_args)
def test_rpr_near_toggle_with_offset(C, theta, offset, sign, guide_length, w, order, rel):
    """Offset coulisse 1e-8 (or 1e-6) inside its toggle |A - C| = |e|: OK, finite."""
    status, pos = rpr_toggle_case(C, theta, offset, sign, guide_length, w, order, rel)
    assert status == kc.OK
    assert np.isfinite(pos[2]).all()


@settings(max_examples=60, **FAST)
@given(rel=st.sampled_from([0.0, 0.1 * TOGGLE_REL, -0.1 * TOGGLE_REL]), **rpr_toggle_args)
@example(C=np.zeros(2), theta=0.0, offset=5.0, sign=1.0, guide_length=50.0, w=1.0, order=2,
         rel=0.0)   # exactly on the toggle, no rounding at all: SINGULAR
@example(C=np.zeros(2), theta=0.25, offset=1.0, sign=1.0, guide_length=50.0, w=1.0, order=2,
         rel=0.0)   # exactly on the toggle up to rounding (was NO_ASSEMBLY before the slack)
def test_rpr_at_toggle_with_offset(C, theta, offset, sign, guide_length, w, order, rel):
    """Offset coulisse exactly at its toggle (up to rounding, 1e-14 relative):
    SINGULAR, or OK with finite numbers, as for RRR and RRP: never NO_ASSEMBLY."""
    status, pos = rpr_toggle_case(C, theta, offset, sign, guide_length, w, order, rel)
    assert status in (kc.OK, kc.SINGULAR)
    assert np.isfinite(pos[2]).all()


@settings(max_examples=40, **FAST)
@given(C=point, guide_length=real(5.0, 200.0), w=mode, order=orders)
def test_rpr_block_on_the_pivot(C, guide_length, w, order):
    """Without offset, the block on the pivot leaves the guide angle undefined:
    SINGULAR (positions finite, analogs NaN), never a silent NaN."""
    A = Path(np.asarray(C, float), np.array([1.0, 3.0]), np.zeros(2))
    status, margin, pos, d1, d2 = call_rpr(A, A, 0.0, guide_length, w, order)
    assert status == kc.SINGULAR
    assert_no_silent_nan(pos, status, *computed(pos, d1, d2, order)[1:])
    if order >= 1:
        assert_nan_point(2, None, d1, d2 if order >= 2 else None)


# ============================================================== 3. attached points, crank
@settings(max_examples=150, **FAST)
@given(base=paths(), a=paths(), b=paths(), rel_angle=angle, dist=real(0.0, 200.0),
       along_link=st.booleans(), order=orders)
def test_attached_point_is_rigid(base, a, b, rel_angle, dist, along_link, order):
    """P = base + rot(a->b, angle, length): |P - base| = length, the angle of
    P - base relative to a->b is ``angle``; d1, d2 equal central differences."""
    if along_link:
        assume(norm(b.p - a.p) > 5.0)
        pos, d1, d2 = kernel_arrays([base, a, b], 1)
        status, margin = attach(pos, d1, d2, 0, 1, 2, 3, rel_angle, dist, order)
    else:
        pos, d1, d2 = kernel_arrays([base], 1)
        status, margin = attach(pos, d1, d2, 0, -1, -1, 1, rel_angle, dist, order)
    io = pos.shape[0] - 1
    assert status == kc.OK
    assert_no_silent_nan(pos, status, *computed(pos, d1, d2, order)[1:])
    P = pos[io]
    assert abs(norm(P - base.p) - dist) <= LENGTH_REL * (dist + 1.0)

    def ref(t, origin=np.zeros(2)):
        u = e(0.0) if not along_link else (b.at(t) - a.at(t)) / norm(b.at(t) - a.at(t))
        return base.shift(origin).at(t) + dist * rotate(u, rel_angle)

    np.testing.assert_allclose(P, ref(0.0), rtol=0, atol=LENGTH_REL * (dist + 100.0))
    if dist > 1e-3:
        link_dir = (b.p - a.p) if along_link else e(0.0)
        got = math.atan2(*(P - base.p)[::-1]) - math.atan2(*link_dir[::-1])
        assert abs(wrap(got - rel_angle)) <= 1e-9 * (1.0 + 100.0 / dist)
    if order == 0:
        return
    moving = [base] + ([a, b] if along_link else [])
    lmin = norm(b.p - a.p) if along_link else 100.0
    s1, s2 = motion_scale(moving, lmin)
    k = 1.0 + dist / lmin
    f = fd(lambda t: ref(t, base.p), moving, lmin, size=dist * (1.0 + 200.0 / lmin) + lmin)
    assert_fd("P'", d1[io], f.d1, k * s1, f.noise1)
    if order >= 2:
        assert_fd("P''", d2[io], f.d2, k * s2, f.noise2)


@settings(max_examples=30, **FAST)
@given(base=point, rel_angle=angle, dist=real(0.0, 200.0), order=orders)
def test_attached_point_on_a_zero_length_link(base, rel_angle, dist, order):
    """A link whose two points coincide has no direction: SINGULAR and NaN."""
    p = Path(np.asarray(base, float), np.ones(2), np.ones(2))
    pos, d1, d2 = kernel_arrays([p, p, p], 1)
    status, margin = attach(pos, d1, d2, 0, 1, 2, 3, rel_angle, dist, order)
    assert status == kc.SINGULAR
    assert_nan_point(3, *computed(pos, d1, d2, order))


@settings(max_examples=50, **FAST)
@given(pivot=paths(), l12=real(1.0, 100.0), phi_m0=angle, phi1=angle)
def test_crank_tip(pivot, l12, phi_m0, phi1):
    """Crank tip at L from the pivot at angle phi1 + phiM0; analogs by FD in phi1."""
    pos, d1, d2 = kernel_arrays([pivot], 1)
    status, _ = crank(pos, d1, d2, 0, 1, l12, phi_m0, phi1, 2)
    assert status == kc.OK
    assert abs(norm(pos[1] - pivot.p) - l12) <= LENGTH_REL * l12
    ref = lambda t: pivot.at(t) + l12 * e(phi1 + t + phi_m0)     # noqa: E731
    f = fd(lambda t: ref(t) - pivot.p, [pivot], l12, size=l12)
    s1, s2 = motion_scale([pivot], l12)
    assert_fd("P2'", d1[1], f.d1, s1 + l12, f.noise1)
    assert_fd("P2''", d2[1], f.d2, s2 + l12, f.noise2)


# ============================================================== 4. class III (triad)
@dataclass(frozen=True)
class Triad:
    """Dimensions of a class III group (DOMAIN.md section 5), with an independent
    closure, Jacobian, margin and Newton solver for reference."""
    l23: float
    l34: float
    l45: float
    l35: float
    l46: float
    l57: float
    orientation: float

    @property
    def u435(self):
        """Signed angle at vertex 3, from the cosine law (computed here, not by the kernel)."""
        c = (self.l34 ** 2 + self.l35 ** 2 - self.l45 ** 2) / (2.0 * self.l34 * self.l35)
        return self.orientation * math.acos(min(1.0, max(-1.0, c)))

    def points(self, p2, a, b):
        p3 = p2 + self.l23 * e(a)
        return p3, p3 + self.l34 * e(b), p3 + self.l35 * e(b + self.u435)

    def residual_jacobian(self, p2, p6, p7, a, b):
        """Squared-distance closure (DOMAIN.md sections 5 and 9) and its Jacobian."""
        u = self.u435
        p3, p4, p5 = self.points(p2, a, b)
        r4, r5 = p4 - p6, p5 - p7
        f = np.array([r4 @ r4 - self.l46 ** 2, r5 @ r5 - self.l57 ** 2])
        na, nb, nc = perp(e(a)), perp(e(b)), perp(e(b + u))
        jac = 2.0 * np.array([[self.l23 * (r4 @ na), self.l34 * (r4 @ nb)],
                              [self.l23 * (r5 @ na), self.l35 * (r5 @ nc)]])
        return f, jac

    def margin(self, p2, p6, p7, a, b):
        _, jac = self.residual_jacobian(p2, p6, p7, a, b)
        return abs(np.linalg.det(jac)) / (4.0 * self.l23 * self.l46 * self.l57
                                          * max(self.l34, self.l35))

    def solve(self, p2, p6, p7, a, b):
        """Plain Newton polished to rounding (the FD reference needs positions to
        ~1e-14 relative; the kernel stops at its tolerance)."""
        for _ in range(40):
            f, jac = self.residual_jacobian(p2, p6, p7, a, b)
            da, db = np.linalg.solve(jac, f)
            a, b = a - da, b - db
            if max(abs(da), abs(db)) < 1e-15:
                break
        f, _ = self.residual_jacobian(p2, p6, p7, a, b)
        assert abs(f[0]) / self.l46 + abs(f[1]) / self.l57 < 1e-9, "reference Newton failed"
        return a, b


def call_class3(tri, P2, P6, P7, a_guess, b_guess, order, det_sign=0.0, tols=TOLS,
                may_stop=0.0):
    pos, d1, d2 = kernel_arrays([P2, P6, P7], 3)
    state = np.zeros((1, kc.N_STATE))
    state[0, kc.S_MAY_STOP] = may_stop
    state[0, kc.S_A] = a_guess
    state[0, kc.S_B] = b_guess
    state[0, kc.S_DET_SIGN] = det_sign
    u435 = ternary_angle(tri.l34, tri.l45, tri.l35, tri.orientation)
    status, margin = class3(pos, d1, d2, 0, 1, 2, 3, 4, 5, tri.l23, tri.l34, u435, tri.l35,
                            tri.l46, tri.l57, state, 0, order, tols)
    return int(status), float(margin), pos, d1, d2, state


@st.composite
def triads(draw):
    """A triad assembled by construction: P2, the angles a and b, the ternary
    triangle (sides L34, L35 and the angle between them), then P6 at L46 from P4
    and P7 at L57 from P5 in random directions."""
    U = draw(real(0.3, 2.8))
    l34, l35 = draw(real(30.0, 200.0)), draw(real(30.0, 200.0))
    l45 = math.sqrt(l34 ** 2 + l35 ** 2 - 2.0 * l34 * l35 * math.cos(U))
    tri = Triad(draw(real(50.0, 300.0)), l34, l45, l35, draw(real(30.0, 300.0)),
                draw(real(30.0, 300.0)), draw(mode))
    p2 = draw(point)
    a, b = draw(angle), draw(angle)
    _, p4, p5 = tri.points(p2, a, b)
    p6 = p4 + tri.l46 * e(draw(angle))
    p7 = p5 + tri.l57 * e(draw(angle))
    return tri, p2, p6, p7, a, b


def check_triad_geometry(tri, pos, p6, p7):
    p2, p3, p4, p5 = pos[0], pos[3], pos[4], pos[5]
    assert abs(norm(p4 - p6) - tri.l46) <= CLOSURE_MM, "closure |P4 - P6| = L46"
    assert abs(norm(p5 - p7) - tri.l57) <= CLOSURE_MM, "closure |P5 - P7| = L57"
    for (p, q, L) in ((p2, p3, tri.l23), (p3, p4, tri.l34), (p3, p5, tri.l35), (p4, p5, tri.l45)):
        assert abs(norm(q - p) - L) <= LENGTH_REL * L
    assert np.sign(cross(p4 - p3, p5 - p3)) == tri.orientation, "ternary triangle mirrored"


@pytest.mark.slow
@settings(max_examples=120, **FAST)
@given(case=triads(), P2v=vec, P2a=zero_or_vec, p67_move=st.booleans(),
       v6=vec, v7=vec, a6=vec, a7=vec,
       da=real(-1.0, 1.0), db=real(-1.0, 1.0))
def test_class3_newton_and_analogs(case, P2v, P2a, p67_move, v6, v7, a6, a7, da, db):
    """Newton from a perturbed guess converges on a triad assembled by
    construction: closure residual <= 1e-9 mm, ternary sides kept, margin equal
    to |det J| / (4 L23 L46 L57 max(L34, L35)); d1, d2 equal central differences
    of positions re-solved (independent Newton) as P2 (and P6, P7) move."""
    tri, p2, p6, p7, a0, b0 = case
    m0 = tri.margin(p2, p6, p7, a0, b0)
    assume(m0 > 0.1)
    P2 = Path(p2, P2v, P2a)
    if p67_move:
        P6, P7 = Path(p6, 0.2 * v6, 0.2 * a6), Path(p7, 0.2 * v7, 0.2 * a7)
    else:
        P6, P7 = Path(p6, np.zeros(2), np.zeros(2)), Path(p7, np.zeros(2), np.zeros(2))
    pert = 0.5 * min(0.1, m0)
    status, margin, pos, d1, d2, state = call_class3(tri, P2, P6, P7, a0 + pert * da,
                                                     b0 + pert * db, 2)
    a, b = state[0, kc.S_A], state[0, kc.S_B]
    m0 = tri.margin(p2, p6, p7, a, b)
    note(f"margin {m0:.3g}, status {status}, iterations {state[0, kc.S_ITERS]}, "
         f"root {(a, b)} (built around {(a0, b0)})")
    # Two roots can lie closer than the perturbation (near a fold of the closure
    # curves): Newton may legitimately land on the other one.  Whatever it
    # found must be a root, with all the properties below.
    assert margin == pytest.approx(m0, rel=1e-6, abs=1e-12)
    assert state[0, kc.S_MARGIN] == margin
    assert status == (kc.OK if margin >= SING else kc.SINGULAR)
    assert_no_silent_nan(pos, status, d1, d2)
    check_triad_geometry(tri, pos, p6, p7)
    if m0 < 0.05:
        return    # the analogs of a near-dead position are tested elsewhere
    _, jac = tri.residual_jacobian(p2, p6, p7, a, b)
    assert state[0, kc.S_DET_SIGN] == np.sign(np.linalg.det(jac))

    # velocity closure: r4.(P4' - P6') = 0, r5.(P5' - P7') = 0, rigid ternary
    for (i, P, L) in ((4, P6, tri.l46), (5, P7, tri.l57)):
        q = d1[i] - P.v
        assert abs(np.dot(pos[i] - P.p, q)) <= KERNEL_EXACT_REL * L * (norm(d1[i]) + P.speed()
                                                                         + 1.0) / m0
    for (i, j, L) in ((3, 4, tri.l34), (3, 5, tri.l35), (4, 5, tri.l45), (0, 3, tri.l23)):
        assert abs(np.dot(pos[j] - pos[i], d1[j] - d1[i])) <= KERNEL_EXACT_REL * L * (
            norm(d1[j]) + norm(d1[i]) + 1.0) / m0

    # finite differences of re-solved positions, continued outward from t = 0
    lmin = min(tri.l23, tri.l34, tri.l35, tri.l46, tri.l57)
    s1, s2 = motion_scale([P2, P6, P7], lmin)
    P2s, P6s, P7s = P2.shift(p2), P6.shift(p2), P7.shift(p2)
    ab0 = tri.solve(P2s.p, P6s.p, P7s.p, a, b)         # polished to rounding

    def sampler(h):
        samples = {0: np.array(tri.points(P2s.p, *ab0))}
        for sgn in (1, -1):
            ab = ab0
            for k in range(1, 5):
                t = sgn * k * h
                ab = tri.solve(P2s.at(t), P6s.at(t), P7s.at(t), *ab)
                samples[sgn * k] = np.array(tri.points(P2s.at(t), *ab))
        return samples

    f = fd(None, [P2, P6, P7], lmin, m0, size=tri.l23 + tri.l34 + tri.l35 + tri.l46 + tri.l57,
           sampler=sampler)
    k = max(tri.l23, tri.l34, tri.l35) / (lmin * m0)
    for row, name in enumerate(("P3", "P4", "P5")):
        assert_fd(name + "'", d1[3 + row], f.d1[row], k * s1, f.noise1)
        assert_fd(name + "''", d2[3 + row], f.d2[row], k * s2, f.noise2)


def test_continuation_slows_into_a_fold():
    """continuation.fold_limit from the margins of the last accepted step: half
    the way to where margin^2's line reaches zero in the direction of travel,
    no limit the other way, nor before that slope is known (then the first
    step's size), never below its floor; a step tried and retried (restore)
    brings the margin back with the angles."""
    from pipeline.kernels.continuation import (FOLD_FLOOR, accept, fold_limit, predict,
                                               restore, start_triad, step_limit)
    state = np.zeros((1, kc.N_STATE))
    start_triad(state, 0, 0.1, 0.2)
    first = TOLS[kc.T_SUBSTEP] * TOLS[kc.T_FIRST_STEP]
    assert fold_limit(state, TOLS, 1.0) == math.inf
    assert step_limit(state, TOLS) == first
    state[0, kc.S_DET_SIGN] = 1.0          # solved at the start, margin 0.3
    state[0, kc.S_MARGIN] = 0.3
    predict(state, 0.01)
    state[0, kc.S_MARGIN] = 0.2            # solved 0.01 rad on
    accept(state, 0.01)
    # margin^2 0.09 -> 0.04 over 0.01 rad: -5 per rad, zero 0.008 rad ahead
    assert state[0, kc.S_D_RATE] == pytest.approx(-5.0)
    assert fold_limit(state, TOLS, 1.0) == pytest.approx(0.004)
    assert fold_limit(state, TOLS, -1.0) == math.inf
    assert step_limit(state, TOLS) == TOLS[kc.T_SUBSTEP]     # (the angles did not move)
    predict(state, 0.004)
    state[0, kc.S_MARGIN] = 0.0            # the try failed
    restore(state)
    assert state[0, kc.S_MARGIN] == 0.2
    state[0, kc.S_MARGIN] = 1e-9           # at the fold: no shorter than the floor
    assert fold_limit(state, TOLS, 1.0) == (FOLD_FLOOR * TOLS[kc.T_SUBSTEP]
                                            * TOLS[kc.T_MIN_STEP])
    # the same step walked the other way (the crank turning back): the same rate
    state2 = np.zeros((1, kc.N_STATE))
    start_triad(state2, 0, 0.1, 0.2)
    state2[0, kc.S_DET_SIGN] = 1.0
    state2[0, kc.S_MARGIN] = 0.3
    predict(state2, -0.01)
    state2[0, kc.S_MARGIN] = 0.2
    accept(state2, -0.01)
    assert fold_limit(state2, TOLS, -1.0) == pytest.approx(0.004)
    assert fold_limit(state2, TOLS, 1.0) == math.inf


def _out_of_reach(case, which, extra, direction):
    """The triad of ``case`` with P6 (or P7) moved ``extra`` beyond the reach of
    its chain from P2, in ``direction``: (tri, p2, p6, p7)."""
    tri, p2, p6, p7, _, _ = case
    if which == "P6":
        p6 = p2 + (tri.l23 + tri.l34 + tri.l46 + extra) * e(direction)
    else:
        p7 = p2 + (tri.l23 + tri.l35 + tri.l57 + extra) * e(direction)
    return tri, p2, p6, p7


@settings(max_examples=60, **FAST)
@given(case=triads(), which=st.sampled_from(["P6", "P7"]), extra=real(1.0, 300.0),
       direction=angle, guess_a=angle, guess_b=angle, order=orders)
def test_class3_impossible(case, which, extra, direction, guess_a, guess_b, order):
    """A pivot placed beyond reach (|P6 - P2| > L23 + L34 + L46, or the same for
    P7): a non-OK status and NaN P3, P4, P5; no exception."""
    tri, p2, p6, p7 = _out_of_reach(case, which, extra, direction)
    fixed = lambda p: Path(p, np.zeros(2), np.zeros(2))      # noqa: E731
    status, margin, pos, d1, d2, state = call_class3(tri, Path(p2, np.ones(2), np.zeros(2)),
                                                     fixed(p6), fixed(p7), guess_a, guess_b,
                                                     order)
    note(f"status {kc.STATUS_NAMES[status]}, iterations {state[0, kc.S_ITERS]}")
    assert status in (kc.NEWTON_MAXITER, kc.SINGULAR)
    for i in (3, 4, 5):
        assert_nan_point(i, pos, d1, d2)
    assert margin == 0.0
    assert_no_silent_nan(pos, status, *computed(pos, d1, d2, order)[1:])


def _newton_steps(tri, p2, p6, p7, a, b, strikes_max):
    """(outcome, a, b, the Newton steps taken) of the class III Newton from (a, b)
    (its Python source, counting the 2x2 solves)."""
    u435 = ternary_angle(tri.l34, tri.l45, tri.l35, tri.orientation)
    taken = []
    solve2 = triad_kernels.solve2

    def counted(*args):
        taken.append(1)
        return solve2(*args)
    triad_kernels.solve2 = counted
    try:
        geo = (*p2, *p6, *p7, 0.0, 0.0, tri.l23, tri.l34, tri.l35, tri.l46, tri.l57, 0.0)
        outcome, a, b, _, _, _ = triad_kernels.newton.py_func(
            triad_kernels.LEAD, tuple(float(x) for x in geo), u435, a, b,
            TOLS[kc.T_NEWTON_TOL], int(TOLS[kc.T_NEWTON_MAXITER]), TOLS[kc.T_NEWTON_STEP],
            strikes_max)
    finally:
        triad_kernels.solve2 = solve2
    return outcome, a, b, len(taken)


@settings(max_examples=60, **FAST)
@given(case=triads(), which=st.sampled_from(["P6", "P7"]), extra=real(1.0, 300.0),
       direction=angle, guess_a=angle, guess_b=angle, sign=st.sampled_from([1.0, -1.0]))
def test_class3_newton_gives_up_where_it_does_not_contract(case, which, extra, direction,
                                                           guess_a, guess_b, sign):
    """A pivot beyond reach, solved where the continuation could retry at half
    the step (``continuation.may_stop``) after a solution (det J's sign known):
    Newton stops once two steps were no shorter than the one before, well short
    of the cap, with the status it has at the cap.  Where the try decides (no
    may_stop) or no solution came before (no sign), it runs to the cap."""
    tri, p2, p6, p7 = _out_of_reach(case, which, extra, direction)
    fixed = lambda p: Path(p, np.zeros(2), np.zeros(2))      # noqa: E731
    moving = Path(p2, np.ones(2), np.zeros(2))
    cap = int(TOLS[kc.T_NEWTON_MAXITER])
    runs = {(s, m): call_class3(tri, moving, fixed(p6), fixed(p7), guess_a, guess_b, 0,
                                det_sign=s, may_stop=m)
            for s in (0.0, sign) for m in (0.0, 1.0)}
    iters = {k: r[5][0, kc.S_ITERS] for k, r in runs.items()}
    note(f"statuses {[kc.STATUS_NAMES[r[0]] for r in runs.values()]}, iterations {iters}")
    at_cap = runs[(sign, 0.0)]
    assert at_cap[0] in (kc.NEWTON_MAXITER, kc.SINGULAR)
    for (s, m), r in runs.items():
        assert r[0] == at_cap[0] or at_cap[0] == kc.NEWTON_MAXITER and r[0] == kc.SINGULAR
        assert r[1] == 0.0
        if at_cap[0] == kc.NEWTON_MAXITER and not (s != 0.0 and m != 0.0):
            assert iters[(s, m)] == cap            # the try that decides: the cap
    if at_cap[0] == kc.NEWTON_MAXITER and runs[(sign, 1.0)][0] == kc.NEWTON_MAXITER:
        event("stopped early")
        assert iters[(sign, 1.0)] < cap


@settings(max_examples=200, **FAST)
@given(case=triads(), da=real(-1.0, 1.0), db=real(-1.0, 1.0), size=real(0.0, 0.05))
def test_class3_newton_on_the_continuation_unchanged_near_a_root(case, da, db, size):
    """From a guess as close as the continuation's predictor (within 0.05 rad)
    to a root with a clear margin, Newton's steps contract: the stopping rule
    never acts, and the root is the one the cap alone gives, to the bit."""
    tri, p2, p6, p7, a0, b0 = case
    assume(tri.margin(p2, p6, p7, a0, b0) > 0.1)
    a, b = a0 + size * da, b0 + size * db
    cap = int(TOLS[kc.T_NEWTON_MAXITER])
    plain = _newton_steps(tri, p2, p6, p7, a, b, cap + 1)
    ruled = _newton_steps(tri, p2, p6, p7, a, b, triad_kernels.STALL_STRIKES)
    assert plain[0] == 0, "no convergence from close by"
    assert ruled == plain


@settings(max_examples=40, **FAST)
@given(case=triads(), bad=st.sampled_from(["triangle", "zero_lead", "negative_side"]),
       order=orders)
def test_class3_bad_geometry(case, bad, order):
    """An impossible ternary triangle or a non-positive length: BAD_GEOMETRY, NaN."""
    tri, p2, p6, p7, a0, b0 = case
    if bad == "triangle":
        tri = Triad(tri.l23, tri.l34, tri.l34 + tri.l35 + 1.0, tri.l35, tri.l46, tri.l57,
                    tri.orientation)
    elif bad == "zero_lead":
        tri = Triad(tri.l23, tri.l34, tri.l45, tri.l35, 0.0, tri.l57, tri.orientation)
    else:
        tri = Triad(tri.l23, -tri.l34, tri.l45, tri.l35, tri.l46, tri.l57, tri.orientation)
    fixed = lambda p: Path(p, np.zeros(2), np.zeros(2))      # noqa: E731
    status, margin, pos, d1, d2, _ = call_class3(tri, fixed(p2), fixed(p6), fixed(p7), a0, b0,
                                                 order)
    assert status == kc.BAD_GEOMETRY
    for i in (3, 4, 5):
        assert_nan_point(i, pos, d1, d2)


@st.composite
def singular_triads(draw):
    """A triad at (or near) a dead position: the lines of leads 4-6 and 5-7 meet
    at a point Q on the line of lead 2-3, so the ternary link can turn about Q
    while P3 slides across lead 2-3: det J = 0.  ``tilt`` moves Q off that line,
    giving a margin that sweeps through the singular tolerance."""
    U = draw(real(0.3, 2.8))
    l34, l35 = draw(real(30.0, 200.0)), draw(real(30.0, 200.0))
    l45 = math.sqrt(l34 ** 2 + l35 ** 2 - 2.0 * l34 * l35 * math.cos(U))
    l23, l46, l57 = (draw(real(50.0, 300.0)), draw(real(30.0, 300.0)),
                     draw(real(30.0, 300.0)))
    tri = Triad(l23, l34, l45, l35, l46, l57, draw(mode))
    p2 = draw(point)
    a, b = draw(angle), draw(angle)
    p3, p4, p5 = tri.points(p2, a, b)
    tilt = draw(st.sampled_from([0.0, 1e-12, 1e-10, 1e-9, 3e-9, 1e-8, 1e-6]))
    q = p3 + draw(real(-400.0, 400.0)) * e(a) + tilt * 100.0 * perp(e(a))
    assume(norm(q - p4) > 1.0 and norm(q - p5) > 1.0)
    s6, s7 = draw(mode), draw(mode)
    p6 = p4 + s6 * l46 * (q - p4) / norm(q - p4)
    p7 = p5 + s7 * l57 * (q - p5) / norm(q - p5)
    return tri, p2, p6, p7, a, b, tilt


@settings(max_examples=120, **FAST)
@given(case=singular_triads(), pert=st.sampled_from([0.0, 1e-6, 1e-3, 0.05]),
       da=real(-1.0, 1.0), db=real(-1.0, 1.0), det_sign=st.sampled_from([0.0, 1.0]),
       order=orders)
def test_class3_near_singular(case, pert, da, db, det_sign, order):
    """At and near a dead position: no exception; a returned margin below the
    singular tolerance never comes with OK; OK means finite numbers and a
    margin (recomputed here) at or above the tolerance; started on the exact
    dead position the group reports SINGULAR."""
    tri, p2, p6, p7, a0, b0, tilt = case
    fixed = lambda p: Path(p, np.zeros(2), np.zeros(2))      # noqa: E731
    status, margin, pos, d1, d2, state = call_class3(
        tri, Path(p2, np.array([5.0, -3.0]), np.array([1.0, 1.0])), fixed(p6), fixed(p7),
        a0 + pert * da, b0 + pert * db, order, det_sign=det_sign)
    note(f"status {kc.STATUS_NAMES[status]}, margin {margin!r}, "
         f"own margin at the start {tri.margin(p2, p6, p7, a0, b0)!r}")
    assert status in KNOWN_STATUS
    assert_no_silent_nan(pos, status, *computed(pos, d1, d2, order)[1:])
    if margin < SING:
        assert status != kc.OK
    if status == kc.OK:
        a, b = state[0, kc.S_A], state[0, kc.S_B]
        assert tri.margin(p2, p6, p7, a, b) >= 0.5 * SING
        check_triad_geometry(tri, pos, p6, p7)
    if status == kc.SINGULAR:
        assert np.isfinite(pos[3:]).all() or np.isnan(pos[3:]).all()
        if order >= 1:
            for i in (3, 4, 5):
                assert_nan_point(i, None, d1, d2 if order >= 2 else None)
    if tilt == 0.0 and pert == 0.0 and det_sign == 0.0:
        assert status == kc.SINGULAR, "started on an exact dead position"
        assert np.isfinite(pos[3:]).all()


@st.composite
def crank_triad_plans(draw):
    """Crank P1-P2 and a triad assembled at the start angle phi0 (so the declared
    guess (a0, b0) is exact there); the rest of the revolution may or may not
    assemble."""
    l12 = draw(real(5.0, 40.0))
    phi_m0, phi0 = draw(angle), draw(angle)
    rot = draw(st.sampled_from([-1, 1]))
    p2 = l12 * e(phi0 + phi_m0)
    U = draw(real(0.3, 2.8))
    l34, l35 = draw(real(40.0, 200.0)), draw(real(40.0, 200.0))
    l45 = math.sqrt(l34 ** 2 + l35 ** 2 - 2.0 * l34 * l35 * math.cos(U))
    tri = Triad(draw(real(100.0, 300.0)), l34, l45, l35, draw(real(60.0, 300.0)),
                draw(real(60.0, 300.0)), draw(mode))
    a, b = draw(angle), draw(angle)
    _, p4, p5 = tri.points(p2, a, b)
    p6 = p4 + tri.l46 * e(draw(angle))
    p7 = p5 + tri.l57 * e(draw(angle))
    assume(tri.margin(p2, p6, p7, a, b) > 0.05)
    mech = Mechanism(
        name="random triad", fixed={"P1": (0.0, 0.0), "P6": tuple(p6), "P7": tuple(p7)},
        crank=Crank("P1", "P2", l12, phiM0=phi_m0, rot=rot, phi0=phi0),
        groups=(ClassIII("P2", "P6", "P7", ("P3", "P4", "P5"), tri.l23, tri.l34, tri.l45,
                         tri.l35, tri.l46, tri.l57, a, b, phi_start=phi0,
                         orientation=int(tri.orientation)),))
    return mech, tri


@pytest.mark.slow
@settings(max_examples=40, **FAST)
@given(case=crank_triad_plans(), n=st.sampled_from([24, 36, 90]))
def test_class3_full_revolution(case, n):
    """A random crank + triad over one revolution (continuation, closing check at
    phi0 + rot 2 pi): either overall OK, every position OK, closure kept, and the
    position continued to 2 pi equal to the first; or a non-OK status.  In all
    cases every NaN position has a non-OK per-position status."""
    mech, tri = case
    plan = mech.compile()
    c = mech.crank
    phis = c.phi0 + c.rot * 2.0 * math.pi * np.arange(n + 1) / n    # closing row included
    cur = solve_curves(plan, phis, kc.ACCELERATIONS, TOLS, close_at=c.phi0 + c.rot * 2 * math.pi)
    note(f"overall {kc.STATUS_NAMES[cur.overall]}, statuses {np.unique(cur.status)}")
    event(f"revolution {kc.STATUS_NAMES[cur.overall]}")
    assert_no_silent_nan(cur.pos, cur.status, cur.d1, cur.d2)
    assert cur.overall in KNOWN_STATUS
    if (cur.status != kc.OK).any():
        assert cur.overall != kc.OK
    ip = [plan.point(p) for p in ("P2", "P6", "P7", "P3", "P4", "P5")]
    p6, p7 = np.array(mech.fixed["P6"]), np.array(mech.fixed["P7"])
    for k in np.flatnonzero(cur.status == kc.OK):
        check_triad_geometry(tri, cur.pos[k][ip], p6, p7)
    if cur.overall == kc.OK:
        scale = TOLS[kc.T_CLOSE] * (tri.l23 + max(tri.l34, tri.l35)) + CLOSURE_MM
        err = np.abs(cur.pos[-1] - cur.pos[0]).max()
        assert err <= scale, f"revolution reported OK but does not close: {err:.3e} mm"
        assert (cur.margin[:, 1] >= SING).all()


@settings(max_examples=40, **FAST)
@given(l12=real(5.0, 60.0), l23=real(20.0, 150.0), l43=real(20.0, 150.0),
       p4=point, w=mode, n=st.sampled_from([36, 72]))
def test_fourbar_revolution_never_silent_nan(l12, l23, l43, p4, w, n):
    """Crank + RRR over a revolution (may lose assembly part of the way): every
    NaN position has a non-OK status, every OK one keeps its link lengths, and
    the closed form returns to its start."""
    mech = Mechanism(name="four-bar", fixed={"P1": (0.0, 0.0), "P4": tuple(p4)},
                     crank=Crank("P1", "P2", l12),
                     groups=(RRR("P2", "P4", "P3", l23, l43, int(w)),))
    plan = mech.compile()
    phis = 2.0 * math.pi * np.arange(n + 1) / n
    cur = solve_curves(plan, phis, kc.ACCELERATIONS, TOLS, close_at=2.0 * math.pi)
    assert_no_silent_nan(cur.pos, cur.status, cur.d1, cur.d2)
    i2, i3 = plan.point("P2"), plan.point("P3")
    for k in np.flatnonzero(cur.status == kc.OK):
        assert abs(norm(cur.pos[k, i3] - cur.pos[k, i2]) - l23) <= LENGTH_REL * l23
        assert abs(norm(cur.pos[k, i3] - p4) - l43) <= LENGTH_REL * l43
    if cur.status[0] == kc.OK:
        np.testing.assert_allclose(cur.pos[-1], cur.pos[0], rtol=0, atol=1e-9 * (l12 + l23))


# ============================================================== 5. degenerate inputs
def _still(x, y):
    return Path(np.array([x, y], float), np.array([1.0, 0.5]), np.array([0.3, -0.2]))


def _rrr_case(l_ab, l_cb, A):
    status, _, pos, d1, d2 = call_rrr(A, _still(0.0, 0.0), l_ab, l_cb, 1.0, 2)
    return status, pos, d1, d2


def _rrp_case(A, G, ga, gb, l_ab):
    status, _, pos, d1, d2, _ = call_rrp(A, G, ga, gb, l_ab, 0.0, 1.0, 2)
    return status, pos, d1, d2


@pytest.mark.parametrize("case", [
    pytest.param(lambda: _rrr_case(5.0, 0.0, _still(3.0, 4.0)), id="rrr-L_CB=0-on-circle"),
    pytest.param(lambda: _rrr_case(0.0, 5.0, _still(3.0, 4.0)), id="rrr-L_AB=0-on-circle"),
    pytest.param(lambda: _rrr_case(5.0, 0.0, _still(4.0, 0.0)), id="rrr-L_CB=0-off-circle"),
    pytest.param(lambda: _rrr_case(0.0, 0.0, _still(0.0, 0.0)), id="rrr-A=C"),
    pytest.param(lambda: _rrp_case(_still(0.0, 0.0), _still(0.0, 0.0), None, None, 0.0),
                 id="rrp-L=0-on-guide"),
    pytest.param(lambda: _rrp_case(_still(0.0, 3.0), _still(0.0, 0.0), _still(10.0, 10.0),
                                   _still(10.0, 10.0), 5.0),
                 id="rrp-guide-link-of-zero-length"),
])
def test_degenerate_inputs_never_silent_nan(case):
    """Zero-length links and guides: a degenerate group may fail, but never returns
    NaN with status OK."""
    status, pos, d1, d2 = case()
    assert_no_silent_nan(pos, status, d1, d2)
