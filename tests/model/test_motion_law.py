"""Issue 14 items 2 and 3: peaks as sweep metrics and constraints, and the timing
of the cycle ([output.motion_law], the law error), each against closed forms or an
independent computation, with the errors a study can make."""

import contextlib
import io
import math
from dataclasses import replace

import h5py
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import pipeline
from pipeline.cli import main
from pipeline.kernels import config as kc
from pipeline.kernels import sweep as ks
from pipeline.kernels.metrics import law_error, relative_angle
from pipeline.results.storage import variables
from pipeline.solve.peaks import _magnitudes, scene_peaks
from pipeline.solve.scene import real_motion, revolution_angles, run_scene, solve_curves
from pipeline.study.reader import load_study, parse_study
from pipeline.base.errors import StudyError
from pipeline.runs.sweep import build_problem, run_sweep
from pipeline.model.metric_catalogue import metric_values
from pipeline.study.sweep_spec import apply_design, parameter_rows
from pipeline.study.sampling import draw_checked
from support import naive
from support.tolerances import LAW_VS_NAIVE_REL, SWEEP_VS_SCENE_REL

OV7_LAW = """
[output.motion_law]
phases = [
  { from = 240, to = 30, law = "dwell" },
  { from = 30, to = 130, law = "LAW", level = 1 },
  { from = 130, to = 240, law = "LAW", level = 0 },
]
"""
LAW_TOL = 1e-12      # a rocker exactly on its law: rounding only
LANE_LAW_TOL = 1e-9  # ... its angles from the lane path's increments (FMA, atan series)


def with_law(studies, block, name="ov7_class3.toml"):
    """A study's text with ``block`` (a table of its own) appended."""
    return (studies / name).read_text() + block


def law_of(studies, block):
    return parse_study(with_law(studies, block), "law.toml").output.motion_law


# ---------------------------------------------------------------- the law, closed forms
CLOSED = {   # written differently from pipeline.motion_law on purpose
    "linear": lambda x: x,
    "harmonic": lambda x: np.sin(0.5 * np.pi * x) ** 2,
    "cycloidal": lambda x: (2 * np.pi * x - np.sin(2 * np.pi * x)) / (2 * np.pi),
}


@pytest.mark.parametrize("name", sorted(CLOSED))
def test_swing_laws_equal_their_closed_forms(studies, name):
    law = law_of(studies, OV7_LAW.replace("LAW", name))
    psi = np.arange(0.0, 720.0, 0.25) - 180.0          # two turns, from -180 deg
    p = np.mod(psi, 360.0)
    y = CLOSED[name]
    want = np.where((p >= 30) & (p < 130), y((p - 30) / 100.0),
                    np.where((p >= 130) & (p < 240), 1.0 - y((p - 130) / 110.0), 0.0))
    np.testing.assert_allclose(law.at(psi), want, rtol=0, atol=1e-14)
    # the same law written from another phase on, with angles past 360
    again = law_of(studies, """
[output.motion_law]
phases = [
  { from = 390, to = 130, law = "LAW", level = 1 },
  { from = 130, to = 240, law = "LAW", level = 0 },
  { from = 240, to = 390, law = "dwell" },
]
""".replace("LAW", name))
    np.testing.assert_allclose(again.at(psi), want, rtol=0, atol=1e-14)


def test_table_interpolation_is_periodic(studies):
    angles = [10.0, 50.0, 120.0, 200.0, 300.0]
    values = [2.0, 5.0, 3.0, 7.0, 4.0]                   # any units: normalised by 2 .. 7
    block = (f"\n[output.motion_law]\nangles = {angles}\nvalues = {values}\n")
    law = law_of(studies, block)
    u = (np.array(values) - 2.0) / 5.0
    np.testing.assert_allclose(law.at(angles), u, atol=1e-15)
    np.testing.assert_allclose(law.at(np.array(angles) - 720.0), u, atol=1e-15)
    # straight lines between the points, and across the turn: 300 -> 370 (= 10)
    assert law.at([30.0])[0] == pytest.approx((u[0] + u[1]) / 2, abs=1e-15)
    assert law.at([335.0])[0] == pytest.approx((u[4] + u[0]) / 2, abs=1e-15)
    assert law.at([0.0])[0] == pytest.approx(u[4] + (u[0] - u[4]) * 60.0 / 70.0, abs=1e-15)
    # a periodic cubic spline of a smooth periodic law: O(h^4), and smooth across the turn
    grid = np.arange(0.0, 360.0, 15.0)
    f = np.cos(np.radians(grid)) + 0.3 * np.sin(np.radians(2 * grid))
    cubic = law_of(studies, "\n[output.motion_law]\ninterpolation = \"cubic\"\n"
                            f"angles = {grid.tolist()}\nvalues = {f.tolist()}\n")
    t = np.arange(0.0, 360.0, 2.5)
    exact = np.cos(np.radians(t)) + 0.3 * np.sin(np.radians(2 * t))
    np.testing.assert_allclose(cubic.at(t), (exact - f.min()) / np.ptp(f), atol=2e-4)
    eps = 1e-7
    assert cubic.at([-eps])[0] == pytest.approx(cubic.at([eps])[0], abs=1e-6)


# ---------------------------------------------------------------- the law error kernel
def brute_law_error(theta, law, best):
    """Every shift (or none) and both orientations, in NumPy."""
    u = (theta - theta.min()) / np.ptp(theta)
    n = len(theta)
    fits = []
    for s in range(n) if best else [0]:
        ls = np.roll(law, -s)                           # ls[k] = law[k + s]
        for v in (u, 1.0 - u):
            e = v - ls
            fits.append((math.sqrt(np.mean(e * e)), float(np.abs(e).max()), s))
    return min(fits, key=lambda f: f[0])


@settings(max_examples=150, deadline=None)
@given(st.integers(5, 41), st.integers(0, 2 ** 32 - 1), st.booleans())
def test_law_error_kernel_equals_brute_force(n, seed, best):
    rng = np.random.default_rng(seed)
    theta = rng.normal(size=n)
    law = rng.random(n)
    rms, top, s = law_error(theta, np.concatenate([law, law]), 0, best, np.empty(n))
    ref = brute_law_error(theta, law, best)
    assert rms == pytest.approx(ref[0], rel=1e-12)
    # the shift found fits as well as the best one (another shift may tie)
    u = (theta - theta.min()) / np.ptp(theta)
    e = [math.sqrt(np.mean((v - np.roll(law, -s)) ** 2)) for v in (u, 1 - u)]
    assert min(e) == pytest.approx(rms, rel=1e-12) and (best or s == 0)
    assert top == pytest.approx(max(np.abs(v - np.roll(law, -s)).max()
                                    for v, ev in zip((u, 1 - u), e) if ev == min(e)), rel=1e-12)


def test_law_error_of_nothing_moving_is_nan():
    out = law_error(np.zeros(12), np.zeros(24), 0, True, np.empty(12))
    assert math.isnan(out[0]) and math.isnan(out[1]) and out[2] == -1


# ---------------------------------------------------------------- a design on its own law
def own_table(res, shift_deg=0.0):
    """[output.motion_law] as a table: the scene's own rocker angle (deg) at its
    dense positions, the cycle angles moved by ``shift_deg``."""
    plan, pos = res.plan, res.dense.pos
    ip, iq = (plan.point_names.index(p) for p in res.study.output.rocker)
    r = pos[:, iq] - pos[:, ip]
    theta = np.degrees([relative_angle(r[0, 0], r[0, 1], x, y) for x, y in r])
    crank = res.study.mechanism.crank
    psi = np.degrees(crank.rot * (res.dense.phi - crank.phi0)) + shift_deg
    order = np.argsort(np.mod(psi, 360.0))
    return np.mod(psi, 360.0)[order], theta[order]


def table_block(angles, values, align="best"):
    return (f"\n[output.motion_law]\nalign = \"{align}\"\nangles = {list(map(float, angles))}\n"
            f"values = {list(map(float, values))}\n")


def test_base_design_against_its_own_law(studies):
    """Mechanism A (the OV-7 base design) against a table of its own rocker angle:
    no law error; moved 30 deg round the turn, the best alignment finds the 30 deg
    and no error, the fixed one sees the whole misalignment."""
    base = pipeline.solve_scene(studies / "ov7_base.toml")
    angles, values = own_table(base)
    res = pipeline.solve_scene(parse_study(with_law(studies, table_block(angles, values),
                                                    "ov7_base.toml"), "own.toml"))
    m = res.motion
    assert m["law_error"] < LAW_TOL and m["law_error_max"] < LAW_TOL and m["law_shift"] == 0.0
    angles, values = own_table(base, 30.0)
    moved = parse_study(with_law(studies, table_block(angles, values), "ov7_base.toml"), "m.toml")
    m = pipeline.solve_scene(moved).motion
    assert m["law_error"] < LAW_TOL and m["law_shift"] == pytest.approx(30.0, abs=1e-9)
    fixed = parse_study(with_law(studies, table_block(angles, values, "fixed"), "ov7_base.toml"),
                        "f.toml")
    m = pipeline.solve_scene(fixed).motion
    assert m["law_error"] > 0.05 and m["law_shift"] == 0.0


def test_sweep_law_error_of_mechanism_b_on_its_own_law(studies):
    """The synthesis study with mechanism B's own law: its reference design has
    none, on the lane path (the rocker angles handed from the lanes) and on the
    careful path; a candidate that is not mechanism B has some."""
    res = pipeline.solve_scene(studies / "ov7_class3.toml")
    angles, values = own_table(res)
    text = with_law(studies, "", "ov7_synthesis.toml")
    text = text.replace("[sweep]\n", table_block(angles, values) + "\n[sweep]\n", 1)
    text = text.replace('objectives = ["dwell_error", "peak_reaction"]',
                        'objectives = ["law_error", "peak_reaction"]')
    study = parse_study(text, "own.toml")
    pb = build_problem(study, study.sweep)
    x, _ = draw_checked(pb.spec, 0)
    pars = np.ascontiguousarray(np.vstack([pb.plan.par, parameter_rows(pb.plan, pb.spec,
                                                                          x[:40])]))
    s, m = pb.evaluate_rows(pars)
    assert s[0] == kc.OK and m[0, ks.M_LAW_RMS] < LANE_LAW_TOL and m[0, ks.M_LAW_SHIFT] == 0.0
    ok = s == kc.OK
    assert (m[1:][ok[1:], ks.M_LAW_RMS] > 1e-4).all()
    n = len(pb.phis)
    out = np.full(ks.N_METRICS, np.nan)
    st_ = pb.kernels.evaluate_careful(pars[0], pb.phis, pb.phi_close, pb.tols, pb.settings(),
                                      pb.loads, np.empty(n), np.empty((n + 1, 4)),
                                      np.empty(n + pb.dwell_w + 1, np.int64),
                                      np.empty(n + pb.dwell_w + 1, np.int64), out)
    assert st_ == kc.OK and out[ks.M_LAW_RMS] < LANE_LAW_TOL
    # lanes and the careful path agree on every candidate's law error
    for i in np.flatnonzero(ok)[:8]:
        st_ = pb.kernels.evaluate_careful(pars[i], pb.phis, pb.phi_close, pb.tols,
                                          pb.settings(), pb.loads, np.empty(n),
                                          np.empty((n + 1, 4)),
                                          np.empty(n + pb.dwell_w + 1, np.int64),
                                          np.empty(n + pb.dwell_w + 1, np.int64), out)
        assert out[ks.M_LAW_RMS] == pytest.approx(m[i, ks.M_LAW_RMS], rel=1e-9)
        for c in (ks.M_PEAK_R, ks.M_PEAK_ACC, ks.M_MIN_TRANS, ks.M_LAW_MAX, ks.M_LAW_SHIFT):
            assert out[c] == pytest.approx(m[i, c], rel=1e-9, nan_ok=True), c


# ---------------------------------------------------------------- declaration errors
def _phases(*rows):
    return "\n[output.motion_law]\nphases = [\n" + ",\n".join(rows) + "\n]\n"


DWELL = '  { from = 240, to = 30, law = "dwell" }'
FWD = '  { from = 30, to = 130, law = "cycloidal", level = 1 }'
BACK = '  { from = 130, to = 240, law = "cycloidal", level = 0 }'
LAW_ERRORS = [
    (_phases(DWELL, FWD, BACK) + "angles = [0, 1, 2]\n", "output.motion_law", "not both"),
    ("\n[output.motion_law]\nalign = \"best\"\n", "output.motion_law", "give the law"),
    (_phases(DWELL, FWD.replace("from = 30", "from = 40"), BACK),
     "output.motion_law.phases[1].from", "must join"),
    (_phases('  { from = 0, to = 200, law = "dwell" }',
             '  { from = 200, to = 40, law = "linear", level = 1 }',
             '  { from = 40, to = 0, law = "linear", level = 0 }'),
     "output.motion_law.phases", "360 deg"),
    (_phases(DWELL, FWD.replace("level = 1", "level = 1.5"), BACK),
     "output.motion_law.phases[1].level", "between 0"),
    (_phases(DWELL, FWD.replace("level = 1", "level = 0"), BACK),
     "output.motion_law.phases[1].level", "stays at 0"),
    (_phases(DWELL, FWD.replace("level = 1", "level = 0.5"), BACK),
     "output.motion_law.phases", "must reach 0 (the dwell) and 1"),
    (_phases(DWELL, FWD.replace("cycloidal", "parabolic"), BACK),
     "output.motion_law.phases[1].law", "must be one of"),
    (_phases(DWELL, FWD.replace("level = 1", "level = 1, lvel = 1"), BACK),
     "output.motion_law.phases[1].lvel", "unknown key"),
    (_phases(DWELL.replace("to = 30", "to = 240"), FWD, BACK),
     "output.motion_law.phases[0].to", "is empty"),
    (_phases(DWELL.replace('"dwell"', '"dwell", level = 0')),
     "output.motion_law.phases[0].level", "unknown key"),
    (table_block([0, 10, 5], [1, 2, 3]), "output.motion_law.angles", "must increase"),
    (table_block([0, 100, 360], [1, 2, 3]), "output.motion_law.angles", "less than one turn"),
    (table_block([0, 100, 200], [1, 2]), "output.motion_law.values", "2 values for 3 angles"),
    (table_block([0, 100, 200], [1, 1, 1]), "output.motion_law.values", "do not move"),
    (table_block([0, 100], [1, 2]), "output.motion_law.angles", "at least 3"),
    (table_block([0, 100, 200], [1, 2, 3], "free"), "output.motion_law.align",
     "must be one of best, fixed"),
]


@pytest.mark.parametrize("block,field,reason", LAW_ERRORS, ids=[c[2] for c in LAW_ERRORS])
def test_motion_law_errors_name_file_field_reason(studies, block, field, reason):
    with pytest.raises(StudyError) as e:
        parse_study(with_law(studies, block), "bad_law.toml")
    msg = str(e.value)
    assert "bad_law.toml" in msg and field in msg and reason in msg, msg


def test_a_law_needs_a_rocker(studies):
    text = with_law(studies, _phases(DWELL, FWD, BACK)).replace(
        'rocker = ["P7", "P5"]', "", 1)
    with pytest.raises(StudyError, match=r"output.motion_law: .*output.rocker"):
        parse_study(text, "x.toml")


def synthesis_with(studies, old, new, law=True):
    text = (studies / "ov7_synthesis.toml").read_text()
    if law:
        text = text.replace("[sweep]\n", _phases(DWELL, FWD, BACK) + "\n[sweep]\n", 1)
    assert old in text, old
    return text.replace(old, new, 1)


OBJ = 'objectives = ["dwell_error", "peak_reaction"]'
CONS = "singularity_margin_min = 0.3\n"
SWEEP_ERRORS = [
    ((OBJ, 'objectives = ["law_error"]', False), "sweep.objectives",
     "needs the required motion law: declare [output.motion_law]"),
    ((OBJ, OBJ + '\nmetrics = ["law_shift"]', False), "sweep.metrics",
     "law_shift needs the required motion law"),
    ((OBJ, 'objectives = ["min_transmission_angle"]', True), "sweep.objectives",
     "minimise transmission_deviation instead"),
    ((CONS, CONS + "foo = { min = 1 }\n", True), "sweep.constraints.foo",
     "unknown constraint 'foo'"),
    ((CONS, CONS + "min_transmission_angle = { min = 40, max = 30 }\n", True),
     "sweep.constraints.min_transmission_angle.max", "the bounds are empty"),
    ((CONS, CONS + "min_transmission_angle = {}\n", True),
     "sweep.constraints.min_transmission_angle", "give min, max or both"),
    ((CONS, CONS + "min_transmission_angle = 30\n", True),
     "sweep.constraints.min_transmission_angle", "expected { min = ..., max = ... }"),
    ((CONS, CONS + "min_transmission_angle = { mn = 30 }\n", True),
     "sweep.constraints.min_transmission_angle.mn", "unknown key"),
    ((CONS, CONS + "peak_joint = { max = 3 }\n", True), "sweep.constraints.peak_joint",
     "an index, not a quantity"),
    ((CONS, CONS + "law_error = { max = 0.1 }\n", False), "sweep.constraints.law_error",
     "needs the required motion law"),
    ((CONS, CONS + "singularity_margin = { min = 0.2 }\n", True),
     "sweep.constraints.singularity_margin_min", "given twice"),
    ((CONS, "singularity_margin = { min = 0.2, max = 0.9 }\n", True),
     "sweep.constraints.singularity_margin.max", "a minimum only"),
]


@pytest.mark.parametrize("change,field,reason", SWEEP_ERRORS, ids=[c[2] for c in SWEEP_ERRORS])
def test_sweep_metric_errors_name_file_field_reason(studies, change, field, reason):
    with pytest.raises(StudyError) as e:
        parse_study(synthesis_with(studies, *change), "bad_sweep.toml")
    msg = str(e.value)
    assert "bad_sweep.toml" in msg and field in msg and reason in msg, msg


def test_transmission_needs_a_dyad_or_a_class_iii_group():
    """A crank with an attached point only has no transmission angle to bound
    (every dyad has one: RRR, RRP, RPR, PRP, RPP; see pipeline.peaks)."""
    text = """
[study]
kind = "sweep"
name = "crank_only"
[mechanism.fixed]
P1 = [0.0, 0.0]
[mechanism.crank]
pivot = "P1"
tip = "P2"
length = 10.0
omega1 = 10.0
[[mechanism.groups]]
type = "attach"
point = "P3"
base = "P2"
along = ["P1", "P2"]
length = 5.0
[output]
rocker = ["P1", "P3"]
[sweep]
stroke_radius = 15.0
objectives = ["dwell_error"]
metrics = ["min_transmission_angle"]
[sweep.variables]
L12 = { param = "crank.length" }
"""
    with pytest.raises(StudyError, match=r"sweep.metrics: min_transmission_angle needs a dyad "
                                         r"or a class III group"):
        parse_study(text, "t.toml")


def test_general_bounds_parse(studies):
    spec = parse_study(synthesis_with(
        studies, "stroke = [11.0, 15.0]          # mm\n" + CONS,
        "singularity_margin = { min = 0.25 }\nstroke = { min = 12 }\n"
        "min_transmission_angle = { min = 30 }\nlaw_error = { max = 0.2 }\n"), "ok.toml").sweep
    assert spec.margin_min == 0.25 and spec.stroke_bounds == (12.0, math.inf)
    assert spec.bounds == (("min_transmission_angle", 30.0, math.inf),
                           ("law_error", -math.inf, 0.2))
    # bounded metrics are computed and stored
    assert {"min_transmission_angle", "law_error"} <= set(spec.metrics)


# ---------------------------------------------------------------- metrics, independently
ALL = ('metrics = ["dwell_error", "stroke", "peak_acceleration", "peak_eps", '
       '"min_transmission_angle", "transmission_deviation", "law_error", "law_error_max", '
       '"law_shift"]\n')


@pytest.fixture(scope="module")
def all_metrics(studies):
    """The synthesis study with every new metric, its reference design and the
    drawn candidates of chunk 0 evaluated."""
    study = parse_study(synthesis_with(studies, OBJ, OBJ + "\n" + ALL), "all.toml")
    pb = build_problem(study, study.sweep)
    x, _ = draw_checked(pb.spec, 0)
    rows = np.ascontiguousarray(np.vstack([pb.plan.par, parameter_rows(pb.plan, pb.spec,
                                                                          x[:300])]))
    X = np.vstack([[pb.plan.par[pb.plan.param(v.param)] for v in pb.spec.variables], x[:300]])
    s, m = pb.evaluate_rows(rows)
    done = np.flatnonzero(m[:, ks.M_FORCES_DONE] == 1.0)
    assert done[0] == 0 and len(done) > 20
    return study, pb, X, s, m, done


def _lead_angle_deg(J, P, A, B, C, D):
    """Class III lead J-P against J->Q, Q the meet of lines A-B and C-D, by a
    2x2 solve and arccos (not pipeline's homogeneous form)."""
    out = []
    for j, p, a, b, c, d in zip(J, P, A, B, C, D):
        t = np.linalg.solve(np.column_stack([b - a, -(d - c)]), c - a)
        q = a + t[0] * (b - a)
        u, w = p - j, q - j
        cosang = abs(u @ w) / (np.linalg.norm(u) * np.linalg.norm(w))
        out.append(np.degrees(np.arccos(min(cosang, 1.0))))
    return np.array(out)


def test_new_metrics_equal_an_independent_computation(all_metrics):
    """peak_acceleration, peak_eps, min_transmission_angle and the law error of a
    few candidates against the scene path's dense curves and NumPy formulas."""
    study, pb, X, s, m, done = all_metrics
    crank = study.mechanism.crank
    law = study.output.motion_law
    for i in done[:6]:
        mech = apply_design(study.mechanism, study.sweep, X[i])
        plan = mech.compile()
        c = solve_curves(plan, pb.phis, kc.ACCELERATIONS, close_at=pb.phi_close)
        assert c.overall == kc.OK
        P = {p: plan.point_names.index(p) for p in plan.point_names}
        a = (c.d2 * crank.omega1 ** 2 + c.d1 * crank.eps1) / 1000.0
        acc = np.hypot(a[:, P["P8"], 0], a[:, P["P8"], 1]).max()
        assert metric_values(m, "peak_acceleration")[i] == pytest.approx(acc,
                                                                         rel=SWEEP_VS_SCENE_REL)
        # the rocker's angle, unwrapped, and its second difference: eps by finite
        # differences of the scene's exact first analog
        r = c.pos[:, P["P5"]] - c.pos[:, P["P7"]]
        r1 = c.d1[:, P["P5"]] - c.d1[:, P["P7"]]
        th1 = (r[:, 0] * r1[:, 1] - r[:, 1] * r1[:, 0]) / (r ** 2).sum(axis=1)
        h = 1e-5
        fd = solve_curves(plan, np.column_stack([pb.phis - h, pb.phis + h]).ravel(),
                          kc.VELOCITIES)
        assert fd.overall == kc.OK
        rm, rp = (fd.pos[sl, P["P5"]] - fd.pos[sl, P["P7"]] for sl in
                  (slice(0, None, 2), slice(1, None, 2)))
        dm, dp = (fd.d1[sl, P["P5"]] - fd.d1[sl, P["P7"]] for sl in
                  (slice(0, None, 2), slice(1, None, 2)))
        t1m = (rm[:, 0] * dm[:, 1] - rm[:, 1] * dm[:, 0]) / (rm ** 2).sum(axis=1)
        t1p = (rp[:, 0] * dp[:, 1] - rp[:, 1] * dp[:, 0]) / (rp ** 2).sum(axis=1)
        th2 = (t1p - t1m) / (2 * h)
        eps = np.abs(th2 * crank.omega1 ** 2 + th1 * crank.eps1).max()
        assert metric_values(m, "peak_eps")[i] == pytest.approx(eps, rel=1e-6)
        # transmission: both class III leads, by another formula
        g = {k: c.pos[:, P[k]] for k in ("P2", "P3", "P4", "P5", "P6", "P7")}
        t4 = _lead_angle_deg(g["P4"], g["P6"], g["P2"], g["P3"], g["P5"], g["P7"])
        t5 = _lead_angle_deg(g["P5"], g["P7"], g["P2"], g["P3"], g["P4"], g["P6"])
        low = min(t4.min(), t5.min())
        assert metric_values(m, "min_transmission_angle")[i] == pytest.approx(low, abs=1e-8)
        assert metric_values(m, "transmission_deviation")[i] == pytest.approx(90 - low, abs=1e-8)
        # the law error by brute force over every shift, from the scene's rocker angle
        theta = np.unwrap(np.arctan2(r[:, 1], r[:, 0]))
        ref = brute_law_error(theta, law.on_grid(crank, pb.phis), True)
        assert metric_values(m, "law_error")[i] == pytest.approx(ref[0], rel=1e-9)
        assert metric_values(m, "law_error_max")[i] == pytest.approx(ref[1], rel=1e-9)


def test_sweep_peaks_agree_with_the_scenes_refined_peaks(all_metrics):
    """The sweep's grid maxima (minimum) against pipeline.peaks on the same design at
    the same positions: the scene's grid value is the sweep's, and its refined peak
    lies beyond it by no more than a grid maximum can miss, |f''| h^2 / 8 (the
    second difference at the peak / 8, with room for its change over the step)."""
    study, pb, X, s, m, done = all_metrics
    for i in done[:3]:
        mech = apply_design(study.mechanism, study.sweep, X[i])
        rocker = tuple(study.output.rocker)
        mech = replace(mech, links=(rocker,))
        scene = replace(study, kind="scene", mechanism=mech, sweep=None,
                        output=replace(study.output, links=(rocker,), link_labels=("7_5",),
                                       dense_positions=pb.spec.positions,
                                       analysis="accelerations"))
        res = run_scene(scene)
        peaks = {(p.quantity, p.item): p for p in scene_peaks(res)}
        grid = _magnitudes(scene, res.plan, res.dense)
        checks = [(("acceleration", "P8"), "peak_acceleration", 1.0),
                  (("eps", "7_5"), "peak_eps", 1.0)]
        for key, metric, sign in checks:
            p = peaks[key]
            v = metric_values(m, metric)[i]
            assert p.grid_value == pytest.approx(v, rel=SWEEP_VS_SCENE_REL), (i, metric)
            f = grid[(key[0], key[1], p.unit)]
            k = int(np.argmax(f))
            d2 = abs(f[k - 1] - 2 * f[k] + f[(k + 1) % len(f)])
            assert v * (1 - 1e-12) <= p.value <= v + 1.5 * d2 / 8 + 1e-12 * v, (i, metric, p, v)
        # the smallest transmission angle: the scene's per lead, the sweep's over both
        trans = [p for p in peaks.values() if p.quantity == "min_transmission_angle"]
        v = metric_values(m, "min_transmission_angle")[i]
        assert min(p.grid_value for p in trans) == pytest.approx(v, abs=1e-9)
        lower = []
        for p in trans:
            f = 90.0 - grid[("transmission_deviation", p.item, "deg")]
            k = int(np.argmin(f))
            lower.append(f[k] - 1.5 * abs(f[k - 1] - 2 * f[k] + f[(k + 1) % len(f)]) / 8)
        assert min(lower) - 1e-9 <= min(p.value for p in trans) <= v + 1e-12


def test_only_what_is_asked_is_computed(studies, all_metrics, tmp_path):
    """The default study asks for none of the new metrics: its settings say so (the
    kernels skip them), they stay NaN and its file has no such columns; a study
    that asks for the peaks but no forces gets the peaks without the reactions."""
    study = load_study(studies / "ov7_synthesis.toml")
    pb = build_problem(study, study.sweep)
    sv = pb.settings()
    assert len(sv) == ks.N_SETTINGS
    assert sv[ks.SET_WANT_PEAKS] == sv[ks.SET_WANT_TRANSMISSION] == sv[ks.SET_WANT_LAW] == 0.0
    _, pb_all, _, _, m_all, _ = all_metrics
    s, m = pb.evaluate_rows(np.ascontiguousarray(pb.plan.par[None, :]))
    new = [ks.M_PEAK_ACC, ks.M_PEAK_EPS, ks.M_MIN_TRANS, ks.M_LAW_RMS, ks.M_LAW_MAX,
           ks.M_LAW_SHIFT]
    assert s[0] == kc.OK and np.isnan(m[0, new]).all() and np.isfinite(m_all[0, new]).all()
    # the default study's numbers are those of a study that asks for everything
    for c in (ks.M_STROKE, ks.M_DWELL, ks.M_MARGIN, ks.M_PEAK_R, ks.M_PEAK_MBAL):
        assert m[0, c] == m_all[0, c]
    # peaks without forces
    text = (studies / "ov7_synthesis.toml").read_text().replace(
        OBJ, 'objectives = ["dwell_error"]\nmetrics = ["stroke", "peak_acceleration"]')
    only = parse_study(text, "only.toml")
    assert not only.sweep.wants_forces and only.sweep.wants_peaks
    pb2 = build_problem(only, only.sweep)
    s2, m2 = pb2.evaluate_rows(np.ascontiguousarray(pb.plan.par[None, :]))
    assert np.isnan(m2[0, ks.M_PEAK_R]) and m2[0, ks.M_FORCES_DONE] == 1.0
    assert m2[0, ks.M_PEAK_ACC] == m_all[0, ks.M_PEAK_ACC]
    assert np.isnan(m2[0, [ks.M_MIN_TRANS, ks.M_LAW_RMS]]).all()
    with h5py.File(_small_default_run(study, tmp_path), "r") as f:
        stored = set(variables(f["metrics"]))     # the metrics, not the candidate scale
        assert stored == set(study.sweep.metrics)
        assert not {"peak_acceleration", "peak_eps", "min_transmission_angle", "law_error",
                    "law_error_max", "law_shift"} & stored


def _small_default_run(study, tmp_path):
    out = tmp_path / "default.h5"
    run_sweep(study, out, candidates=200, chunk_size=100, progress=False)
    return out


# ---------------------------------------------------------------- the law study, end to end
@pytest.fixture(scope="module")
def law_run(studies, tmp_path_factory):
    study = load_study(studies / "ov7_synthesis_law.toml")
    out = tmp_path_factory.mktemp("law") / "ov7_synthesis_law.h5"
    run_sweep(study, out, candidates=3000, chunk_size=1000, progress=False)
    return study, out


def _cli(*argv):
    buf, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return code, buf.getvalue(), err.getvalue()


def txt(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def test_law_study_file_columns_and_constraints(law_run, studies):
    study, out = law_run
    assert study.sweep.objectives == ("law_error", "peak_reaction")
    units = {"law_error": "1", "law_error_max": "1", "law_shift": "deg",
             "min_transmission_angle": "deg", "peak_acceleration": "m/s²"}
    with h5py.File(out, "r") as f:
        for name, u in units.items():
            d = f[f"metrics/{name}"]
            assert txt(d.attrs["units"]) == u and "long_name" in d.attrs, name
            assert d.dims[0][0].name == "/candidate"
        assert "grid" in f["metrics/min_transmission_angle"].attrs["long_name"]
        names = [txt(x) for x in f["candidates/constraints"].attrs["names"]]
        assert names[-1] == "min_transmission_angle_min"
        assert txt(f["candidates/constraints"].attrs["units"][-1]) == "deg"
        G = f["candidates/constraints"][()]
        t = f["metrics/min_transmission_angle"][()]
        feas = f["candidates/feasible"][()]
        ok = np.isfinite(t)
        np.testing.assert_array_equal(G[ok, -1], 30.0 - t[ok])
        assert feas.sum() > 50 and (t[feas] >= 30.0).all()
        assert ((t < 30.0) & ok).any() and not feas[(t < 30.0) & ok].any()
        assert (f["metrics/law_error"][()][feas] > 0).all()
        ref = float(f["reference/law_error"][0])
    # the scene (mechanism B at its own speed: the law error does not depend on it)
    res = pipeline.solve_scene(parse_study(with_law(
        studies, OV7_LAW.replace("LAW", "cycloidal")), "b.toml"))
    assert res.motion["law_error"] == pytest.approx(ref, rel=SWEEP_VS_SCENE_REL)


def test_law_study_analyze_and_browse(law_run, tmp_path):
    _, out = law_run
    code, text, err = _cli("analyze", out)
    assert code == 0, err
    assert "law_error" in text
    code, text, err = _cli("browse", out, "--top", "3")
    assert code == 0 and "best law_error" in text, err
    code, text, err = _cli("browse", out, "--candidate", "knee")
    assert code == 0 and "min_transmission_angle" in text and "law_shift" in text, err


def test_scene_reports_and_stores_the_law_error(studies, tmp_path):
    study = tmp_path / "b_law.toml"
    study.write_text(with_law(studies, OV7_LAW.replace("LAW", "harmonic")))
    out = tmp_path / "b.h5"
    code, text, err = _cli("run", study, "-o", out, "--no-pictures")
    assert code == 0, err
    assert "law_error:" in text and "RMS" in text and "shifted by" in text
    with h5py.File(out, "r") as f:
        g = f["motion"]
        assert txt(g["law_error"].attrs["units"]) == "1"
        assert txt(g["law_shift"].attrs["units"]) == "deg"
        # naive.py's rocker angles at the scene's 360 positions (psi = k deg: rot = -1,
        # phi1 = -k deg) against the law's closed form, every shift by brute force
        theta = np.array(naive.mech_b_rocker_angles(360)[0])
        psi = np.arange(360.0)
        p = np.mod(psi, 360.0)
        y = CLOSED["harmonic"]
        law = np.where((p >= 30) & (p < 130), y((p - 30) / 100.0),
                       np.where((p >= 130) & (p < 240), 1.0 - y((p - 130) / 110.0), 0.0))
        rms, top, s = brute_law_error(theta, law, True)
        assert g["law_error"][()] == pytest.approx(rms, rel=LAW_VS_NAIVE_REL)
        assert g["law_error_max"][()] == pytest.approx(top, rel=LAW_VS_NAIVE_REL)
        assert g["law_shift"][()] == pytest.approx(s * 360.0 / 360)
        assert txt(g.attrs["law_align"]) == "best"
        # every transmission angle on the scene's dimension: the class III group's two leads
        assert [txt(x) for x in f["dyad"][()]] == ["triad lead P4-P6", "triad lead P5-P7"]
        assert f["peaks/min_transmission_angle"].shape == (2,)
