"""The class III group with a slider in place of lead 5-7 (a block pinned at
vertex 5 slides on a guide line): study format, kinematics against the
60-digit reference of tests/support/naive.py (points as unknowns, not the kernel's
angles), kinetostatics (virtual power, and the dense solve with the block's
slide), the between-sample watch, and a sweep over its dimensions with its
Pareto analysis."""

import dataclasses
import functools
import math
import re

import numpy as np
import pytest

from support import naive
from pipeline.compiler import source_for
from pipeline.compiler.emit import emitter_classes
from pipeline.group_types import code_names
from pipeline.group_types.class3 import G_CLASS3_SLIDER
from pipeline.solve.reactions import scene_forces
from pipeline.kernels import config as kc
from pipeline.kernels import sweep as ks
from pipeline.group_types.class3.model import ClassIIISlider
from pipeline.solve.scene import revolution_angles, run_scene, solve_curves
from pipeline.study.reader import load_study, parse_study
from pipeline.base.errors import StudyError
from support.lanes import assert_lanes_agree, evaluate_with, scalar_forces, widened_draws
from support.power import virtual_power
from support.references import against_mp_reference
from support.tolerances import FAIL_ANGLE_RAD, MP_REFERENCE_REL, REACTION_MP_REL, SELF_FD_REL, VIRTUAL_POWER_REL

DEG = math.pi / 180.0
N_CYCLE = 72                    # positions of a full cycle compared with the reference
ANGLE_TOL_DEG = math.degrees(FAIL_ANGLE_RAD)   # a failure's reported crank angle vs the exact fold
SCENE = "ov7_class3_slider"
SWEEP = "ov7_class3_slider_sweep"


def _study(studies, **group_changes):
    """The scene study with its class III group's fields replaced."""
    study = load_study(studies / f"{SCENE}.toml")
    m = study.mechanism
    groups = tuple(dataclasses.replace(g, **group_changes) if isinstance(g, ClassIIISlider)
                   else g for g in m.groups)
    return dataclasses.replace(study, mechanism=dataclasses.replace(m, groups=groups))


def _with_crank(study, **changes):
    m = study.mechanism
    return dataclasses.replace(study, mechanism=dataclasses.replace(
        m, crank=dataclasses.replace(m.crank, **changes)))


def _cycle(study, n=N_CYCLE, order=kc.ACCELERATIONS):
    crank = study.mechanism.crank
    plan = study.mechanism.compile()
    c = solve_curves(plan, revolution_angles(crank, n), order,
                     close_at=crank.phi0 + crank.rot * 2 * math.pi)
    return plan, c


# ------------------------------------------------------------------ study format
def _broken(studies, old, new):
    text = (studies / f"{SCENE}.toml").read_text()
    assert old in text, old
    return text.replace(old, new, 1)


SLIDER = 'slider = { point = "P7", angle = 171.0, offset = 261.0 }'
ERRORS = [
    # (change, field named in the message, reason fragment)
    ((SLIDER, SLIDER + '\npivot_5 = "P7"'), "mechanism.groups[0].pivot_5", "has no lead 5-7"),
    ((SLIDER, SLIDER + "\nL57 = 261.0"), "mechanism.groups[0].L57", "has no lead 5-7"),
    ((SLIDER, ""), "mechanism.groups[0].pivot_5", "or, for a block on a guide"),
    ((SLIDER, SLIDER.replace('"P7"', '"P9"')), "mechanism.groups[0].slider.point",
     "unknown point 'P9'"),
    ((SLIDER, SLIDER.replace('"P7"', '"P5"')), "mechanism.groups[0].slider.point",
     "point 'P5' is solved later"),
    ((SLIDER, SLIDER.replace("angle = 171.0, ", "")), "mechanism.groups[0].slider.angle",
     "required field is missing"),
    ((SLIDER, SLIDER.replace("offset = 261.0", 'offset = "far"')),
     "mechanism.groups[0].slider.offset", "expected a number"),
    ((SLIDER, SLIDER.replace("angle = 171.0", "angle = nan")),
     "mechanism.groups[0].slider.angle", "must be finite"),
    ((SLIDER, SLIDER.replace("}", ', link = ["P7", "P7"] }')),
     "mechanism.groups[0].slider.link", "two different points"),
    ((SLIDER, SLIDER.replace("}", ', link = ["P7"] }')),
     "mechanism.groups[0].slider.link", "expected 2 names"),
    ((SLIDER, SLIDER.replace("offset", "ofset")), "mechanism.groups[0].slider.ofset",
     "unknown key"),
    ((SLIDER, "slider = 261.0"), "mechanism.groups[0].slider", "expected a table"),
    (("L35 = 174.0", "L35 = 300.0"), "mechanism.groups[0].L45", "not a triangle"),
    (("L46 = 104.5", "L46 = 0.0"), "mechanism.groups[0].L46", "must be positive"),
]


@pytest.mark.parametrize("change,field,reason", ERRORS, ids=[f"{e[1]}-{e[2]}" for e in ERRORS])
def test_declaration_error_names_file_field_reason(studies, tmp_path, change, field, reason):
    path = tmp_path / "bad_study.toml"
    path.write_text(_broken(studies, *change))
    with pytest.raises(StudyError) as e:
        load_study(path)
    msg = str(e.value)
    assert str(path) in msg and field in msg and reason in msg, msg


def test_the_group_is_declared_as_written(studies):
    g = load_study(studies / f"{SCENE}.toml").mechanism.groups[0]
    assert g == ClassIIISlider("P2", "P6", "P7", ("P3", "P4", "P5"), 272.5, 81.0, 104.5, 174.0,
                               104.5, math.radians(171.0), 261.0, math.radians(44.0),
                               math.radians(128.8), 0.0, 1, None, "triad")
    moved = parse_study(_broken(studies, SLIDER, SLIDER.replace("}", ', link = ["P1", "P2"] }')),
                        "x.toml").mechanism.groups[0]
    assert moved.guide_link == ("P1", "P2")
    plan = load_study(studies / f"{SCENE}.toml").mechanism.compile()
    assert plan.codes[1] == G_CLASS3_SLIDER
    assert code_names()[G_CLASS3_SLIDER] == "class3_slider"
    first = plan.param("triad.L23")
    assert list(plan.par_names[first:first + 11]) == [
        f"triad.{k}" for k in ("L23", "L34", "L45", "L35", "L46", "guide_angle",
                               "guide_offset", "orientation", "a0", "b0", "phi_start")]
    assert list(plan.gidx[1]) == [plan.point(p) for p in ("P2", "P6", "P7", "P3", "P4", "P5")] \
        + [-1, -1]


# ------------------------------------------------------------------ kinematics
# a guide that turns: an RRR dyad P2-P9-P7 (coupler 872.7, rocker 600 about P7) makes
# the rocker P7->P9 swing by about 10 deg; the guide runs along it + 171 deg
MOVING_GUIDE = ("""[[mechanism.groups]]       # lead 2-3""", """[[mechanism.groups]]
type = "RRR"
name = "guide rocker"
A = "P2"
C = "P7"
B = "P9"
L_AB = 872.7
L_CB = 600.0
W = -1

[[mechanism.groups]]       # lead 2-3""")
VARIANTS = {
    "study": ({}, {}),
    "guide": (dict(guide_angle=175.0 * DEG, guide_offset=255.0, L46=100.0),
              dict(ga=175.0 * DEG, e=255.0, L46=100.0)),
    "moving-guide": (None, dict(rocker=((46.0, 533.0), 872.7, 600.0, -1))),
}


def _variant(studies, name):
    changes, data = VARIANTS[name]
    if changes is None:
        text = _broken(studies, *MOVING_GUIDE)
        text = text.replace(SLIDER, SLIDER.replace("}", ', link = ["P7", "P9"] }'))
        study = parse_study(text, "moving_guide.toml")
    else:
        study = _study(studies, **changes)
    return study, naive.Class3SliderChain(dict(naive.SLIDER_DATA, **data))


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_matches_the_60_digit_reference(studies, variant):
    """A full cycle of 72 positions: every point's position, velocity and
    acceleration analogs against the reference's, which solves for the points
    themselves (six distance and line equations) and differentiates them."""
    study, chain = _variant(studies, variant)
    plan, c = _cycle(study)
    assert c.overall == kc.OK
    worst, _ = against_mp_reference(plan, c, chain)
    assert 0.0 < worst <= MP_REFERENCE_REL
    print(f"{variant}: worst relative error {worst:.2e}")
    if variant == "moving-guide":    # the guide really turns
        rocker = c.pos[:, plan.point("P9")] - c.pos[:, plan.point("P7")]
        assert np.ptp(np.arctan2(rocker[:, 1], rocker[:, 0])) > 5 * DEG


def test_velocity_is_derivative_of_position(studies):
    """A central difference of the kernel's own positions reproduces its analogs."""
    plan = load_study(studies / f"{SCENE}.toml").mechanism.compile()
    h = 1e-5
    nv = plan.n_visible
    for phi in np.deg2rad([-17.0, -133.0, -251.0]):
        c = solve_curves(plan, np.array([phi - h, phi, phi + h]), kc.ACCELERATIONS)
        fd1 = (c.pos[2] - c.pos[0]) / (2 * h)
        fd2 = (c.pos[2] - 2 * c.pos[1] + c.pos[0]) / h ** 2
        assert np.abs(fd1[:nv] - c.d1[1, :nv]).max() <= SELF_FD_REL * np.abs(c.d1[1, :nv]).max()
        assert np.abs(fd2[:nv] - c.d2[1, :nv]).max() <= 1e-4 * np.abs(c.d2[1, :nv]).max()


def test_the_scene_assembles_with_a_comfortable_margin(studies):
    """The shipped scene: OK over the revolution, P5 on its line and P4 on its
    circle, the margin |det J| / (L23 L46 max(L34, L35)) above 0.9 (mechanism
    B's own is 0.93), and the block's travel about 25 mm."""
    study = load_study(studies / f"{SCENE}.toml")
    res = run_scene(study)
    assert res.status == kc.OK and res.failure is None
    g = res.plan.group_names.index("triad")
    d = res.dense
    assert d.margin[:, g].min() > 0.9
    assert d.iterations.max() <= 6
    p = {k: d.pos[:, res.plan.point(k)] for k in ("P4", "P5", "P6", "P7")}
    n = np.array([-math.sin(171 * DEG), math.cos(171 * DEG)])
    assert np.abs((p["P5"] - p["P7"]) @ n - 261.0).max() <= 1e-9
    assert np.abs(np.hypot(*(p["P4"] - p["P6"]).T) - 104.5).max() <= 1e-9
    u = np.array([math.cos(171 * DEG), math.sin(171 * DEG)])
    assert 24.0 < np.ptp(p["P5"] @ u) < 26.0


# ------------------------------------------------------------------ kinetostatics
@pytest.mark.parametrize("eps1", [0.0, -350.0])
def test_virtual_power_identity(studies, eps1):
    """M_bal omega1 + sum over the links (F . v_S + M omega) = 0, with the
    block's slide (its normal force and couple do no work) and a load on it."""
    study = _with_crank(load_study(studies / f"{SCENE}.toml"), eps1=eps1)
    plan, c = _cycle(study)
    fr = scene_forces(study.mechanism, plan, c)
    total, scale = virtual_power(study, plan, c, fr)
    assert np.isfinite(total).all()
    worst = (np.abs(total) / scale).max()
    assert worst <= VIRTUAL_POWER_REL
    print(f"eps1 = {eps1}: virtual power residual {worst:.2e} of the largest term")


def test_reactions_and_slide_force_match_the_dense_solve(studies):
    """Every revolute reaction, the block's slide (normal force N, couple C) and
    M_bal against tests/support/naive.py's dense solve on its 60-digit kinematics."""
    eps1 = 420.0
    study = _with_crank(load_study(studies / f"{SCENE}.toml"), eps1=eps1)
    plan, c = _cycle(study, 12)
    fr = scene_forces(study.mechanism, plan, c)
    crank = study.mechanism.crank
    assert fr.joint_names == ("R1", "R2", "R3", "R4", "R5", "R6")
    assert fr.slide_names == ("slide[block]",)
    chain = naive.Class3SliderChain(naive.SLIDER_DATA, naive._slider_com)
    for k in range(0, 12, 2):
        ref = naive.naive_forces_slider(chain, c.phi[k], crank.omega1, eps1)
        scale = max(np.abs(ref[n]).max() for n in fr.joint_names + fr.slide_names)
        for j, n in enumerate(fr.joint_names):
            assert np.abs(fr.R[k, j] - ref[n]).max() <= REACTION_MP_REL * scale, (k, n)
        n = "slide[block]"
        assert abs(fr.slide[k, 0, 0] - ref[n][0]) <= REACTION_MP_REL * scale, (k, "N")
        assert abs(fr.slide[k, 0, 1] - ref[n][1]) <= REACTION_MP_REL * scale * 1e-3, (k, "C")
        assert abs(fr.M_bal[k] - ref["M_bal"]) <= REACTION_MP_REL * max(abs(ref["M_bal"]), 1)


# ------------------------------------------------------------------ the between-sample watch
# The guide moved to 138.783 mm from P7: the block's line then lies, for crank
# angles within 0.7 deg of -278.4 deg, beyond what the group can reach (P5's
# least distance from P7 along n there, over the one-parameter motion of lead
# 2-3, ternary and lead 4-6, is up to 138.7837 mm): it folds at both ends of
# that range, between the samples of a 72-position (or 360-position)
# revolution.  At 138.80 mm it passes within 0.017 mm of folding: no failure.
LOCK_OFFSET, NEAR_OFFSET = 138.783, 138.80
BRANCHES = {"upper": (72.649, 14.712), "lower": (52.673, 83.588)}    # (a0, b0) deg at 0


@functools.lru_cache(maxsize=None)
def _exact_fold(offset, start_deg, rot):
    """The crank angle (rad) where the group first folds walking from phi1 = 0
    in the direction ``rot``: the reference chain continued in float steps of
    0.1 deg (the lock is 0.7 deg wide) to the last angle it reaches on its
    branch (bisected to 1e-9 rad), then the fold itself (the closure and a
    singular Jacobian of the point equations) solved at 60 digits from there."""
    chain = naive.Class3SliderChain(dict(naive.SLIDER_DATA, e=offset,
                                         start=tuple(s * DEG for s in start_deg)),
                                    max_step=0.1 * DEG)
    phi, x = 0.0, chain.guess(0.0)
    while abs(phi) < 2 * math.pi:
        try:
            x = chain.guess(phi + rot * 0.1 * DEG)
        except ValueError:
            break
        phi += rot * 0.1 * DEG
    lo, hi = phi, phi + rot * 0.1 * DEG
    while abs(hi - lo) > 1e-9:
        mid = 0.5 * (lo + hi)
        try:
            x = chain.guess(mid)
            lo = mid
        except ValueError:
            hi = mid
    phi_f, _ = chain.fold(lo, x)
    assert abs(float(phi_f) - lo) < 1e-6, (float(phi_f), lo)   # the fold where the walk ends
    return float(phi_f)


def _deg_err(got, want):
    return abs(math.remainder(got - want, 2 * math.pi)) / DEG


def test_the_group_is_watched(studies):
    plan = load_study(studies / f"{SCENE}.toml").mechanism.compile()
    emitter = emitter_classes()[G_CLASS3_SLIDER]
    assert emitter.watched and emitter.continued and emitter.fast
    # (the generated source's constants: compiling the module would add nothing)
    src = source_for(plan, ("P7", "P5"))
    assert re.search(r"^WATCH_G = np\.array\(\[1\], dtype=np\.int64\)", src, re.M)
    assert re.search(r"^N_TRIADS = np\.int64\(1\)", src, re.M)
    assert re.search(r"^HAS_LANES = True\b", src, re.M)


@pytest.mark.parametrize("branch", list(BRANCHES))
@pytest.mark.parametrize("rot", [-1, 1])
def test_a_fold_between_positions_is_found(studies, branch, rot):
    """The locked guide: SINGULAR (the group folds) at the first end of the
    range met from phi1 = 0 in the crank's direction, to 1e-10 rad, in the class
    III group, at every order of analysis and on both branches; no sample of
    the revolution lies in the range."""
    a0, b0 = BRANCHES[branch]
    study = _with_crank(_study(studies, guide_offset=LOCK_OFFSET, a0=a0 * DEG, b0=b0 * DEG),
                        rot=rot, omega1=rot * 94.4)
    exact = _exact_fold(LOCK_OFFSET, (a0, b0), rot)
    other = _exact_fold(LOCK_OFFSET, (a0, b0), -rot)
    assert 0.3 < _deg_err(exact, other) < 1.0               # the range's width, deg
    for n in (36, 72):
        phis = revolution_angles(study.mechanism.crank, n)
        assert min(_deg_err(p, exact) for p in phis) > 1.0   # between two samples
        for order in (kc.POSITIONS, kc.VELOCITIES, kc.ACCELERATIONS):
            plan, c = _cycle(study, n, order)
            assert c.overall == kc.SINGULAR, kc.STATUS_NAMES[c.overall]
            assert _deg_err(c.fail_phi, exact) <= ANGLE_TOL_DEG, (c.fail_phi / DEG, exact / DEG)
            assert c.fail_group == plan.group_names.index("triad")
            print(f"{branch} rot {rot:+d} n {n}: {_deg_err(c.fail_phi, exact):.1e} deg off")


@pytest.mark.parametrize("branch", list(BRANCHES))
def test_a_near_miss_is_no_false_alarm(studies, branch):
    """The guide 0.017 mm short of the lock: the margin dips to 0.02 at the
    samples and lower between them, the revolution is OK, with no failure."""
    a0, b0 = BRANCHES[branch]
    study = _study(studies, guide_offset=NEAR_OFFSET, a0=a0 * DEG, b0=b0 * DEG)
    for n in (36, 72, 360):
        plan, c = _cycle(study, n, kc.ACCELERATIONS)
        assert c.overall == kc.OK and (c.status == kc.OK).all()
        assert math.isnan(c.fail_phi) and c.fail_group == -1
        assert c.margin[:, 1].min() < 0.03


def test_the_sweep_reports_the_fold_too(studies):
    """The same rows in a sweep of 360 positions (the careful path, watched):
    the locked guide SINGULAR at its first fold (M_FAIL_PHI, 1e-10 rad) in the
    class III group (M_FAIL_GROUP), the near miss and the reference design OK."""
    from pipeline.runs.sweep import build_problem
    study = load_study(studies / f"{SWEEP}.toml")
    pb = build_problem(study, study.sweep)
    assert min(_deg_err(p, -278.42 * DEG) for p in pb.phis) > 0.3
    rows, want = [], []
    for branch, (a0, b0) in BRANCHES.items():
        for offset in (LOCK_OFFSET, NEAR_OFFSET):
            par = pb.plan.par.copy()
            for key, v in (("guide_offset", offset), ("a0", a0 * DEG), ("b0", b0 * DEG)):
                par[pb.plan.param(f"triad.{key}")] = v
            rows.append(par)
            want.append(_exact_fold(offset, (a0, b0), -1) if offset == LOCK_OFFSET else None)
    rows.append(pb.plan.par.copy())
    want.append(None)
    status, metrics = pb.evaluate_rows(np.array(rows))
    for i, exact in enumerate(want):
        if exact is None:
            assert status[i] == kc.OK and math.isnan(metrics[i, ks.M_FAIL_GROUP]), i
        else:
            assert status[i] == kc.SINGULAR, kc.STATUS_NAMES[int(status[i])]
            assert _deg_err(metrics[i, ks.M_FAIL_PHI], exact) <= ANGLE_TOL_DEG
            assert metrics[i, ks.M_FAIL_GROUP] == 1


# ------------------------------------------------------------------ a sweep over the group
SWEEP_N = 160


@pytest.fixture(scope="module")
def slider_sweep(studies, tmp_path_factory):
    from support.sweep_helpers import run_and_analyze
    return run_and_analyze(studies / f"{SWEEP}.toml",
                           tmp_path_factory.mktemp("class3_slider_sweep") / "sweep.h5", SWEEP_N)


def test_sweep_matches_the_scene_path(slider_sweep):
    """The lengths, the guide's offset and its angle (deg in the study and the
    file, rad in the plan) are design variables: each candidate's metrics are
    those of its own scene, and the margin constraint applies."""
    import h5py
    from pipeline.study.sweep_spec import apply_design
    from support.tolerances import SWEEP_VS_SCENE_REL
    study, path = slider_sweep
    with h5py.File(path, "r") as f:
        x = f["candidates/params"][()]
        status = f["candidates/status"][()]
        m = {k: f[f"metrics/{k}"][()] for k in ("peak_reaction", "singularity_margin",
                                                "stroke")}
        constraints = [c.decode() for c in f["constraint"][()]]
    assert (status == kc.OK).all()
    assert np.ptp(x[:, 4]) > 15.0 and 161.0 <= x[:, 4].min()          # degrees
    assert constraints == ["stroke_min", "stroke_max", "singularity_margin_min"]
    done = np.flatnonzero(np.isfinite(m["peak_reaction"]))
    assert len(done) >= 3
    for i in done[:3]:
        mech = apply_design(study.mechanism, study.sweep, x[i])
        g = mech.groups[0]
        assert (g.L23, g.L35, g.L46, g.guide_offset, g.guide_angle) == \
            (x[i, 0], x[i, 1], x[i, 2], x[i, 3], x[i, 4] * DEG)
        plan = mech.compile()
        crank = mech.crank
        c = solve_curves(plan, revolution_angles(crank, study.sweep.positions),
                         kc.ACCELERATIONS, close_at=crank.phi0 + crank.rot * 2 * math.pi)
        fr = scene_forces(mech, plan, c)
        tri = plan.group_names.index("triad")
        assert m["peak_reaction"][i] == pytest.approx(fr.magnitude.max(), rel=SWEEP_VS_SCENE_REL)
        assert m["singularity_margin"][i] == pytest.approx(c.margin[:, tri].min(),
                                                           rel=SWEEP_VS_SCENE_REL)


def test_pareto_analysis_of_the_sweep(slider_sweep):
    """The fronts of the stored analysis are those of a brute-force dominance
    test over the feasible candidates."""
    from support.sweep_helpers import assert_fronts_are_the_brute_force_rank
    assert_fronts_are_the_brute_force_rank(slider_sweep[1])


def test_the_scene_runs_and_exports(studies, tmp_path):
    """`pipeline run` of the scene writes its results and pictures, and
    `pipeline export` its tables."""
    from pipeline.cli import main
    out = tmp_path / "scene.h5"
    assert main(["run", str(studies / f"{SCENE}.toml"), "-o", str(out), "-q"]) == 0
    assert out.exists() and (tmp_path / "scene.png").exists()
    assert main(["export", str(out), "--csv", str(tmp_path / "tables"), "-q"]) == 0
    reactions = (tmp_path / "tables" / "reactions.csv").read_text()
    head = reactions.splitlines()[0].split(",")
    assert [c for c in head if c.startswith("R6 (") and c.endswith(") [N]")] and "M_bal" in reactions


# ----------------------------------------------------------------- the lanes
def test_class3_slider_lanes_agree_with_the_careful_path(studies):
    """The class III group with a block on a guide (the shipped sweep: forces,
    a return spring) in the lanes: Newton on |P4 - P6| = L46 and the block's
    line, as the careful path's slider_closure_unit; the lanes
    against the careful path alone (statuses, failing groups and angles, the
    metrics and the singularity margin to the lanes' figures), and the force
    lanes, from the lanes' solutions handed over (the careful kernel's
    ``handed``, the slider variant), against the scalar force stage: the same bits.  The
    guide's offset and lead 4-6 widened so that some draws fold or cannot
    assemble somewhere in the revolution."""
    pb, pars = widened_draws(studies, "ov7_class3_slider_sweep",
                             [("min = 240.0, max = 280.0", "min = 150.0, max = 330.0"),
                              ("min = 95.0, max = 115.0", "min = 60.0, max = 140.0")], 3000)
    status = assert_lanes_agree(pb, pars, class3=True)
    assert (status != kc.OK).sum() > 20
    k, settings = pb.kernels, pb.settings()
    assert k.HAS_LANE_FORCES and k.SAME_BITS and k.lane_forces_apply(settings)
    s1, m1 = pb.evaluate_rows(pars)
    s0, m0 = evaluate_with(k, pb, pars, scalar_forces(settings))
    np.testing.assert_array_equal(s1, s0)
    assert m1.tobytes() == m0.tobytes()
    assert (m1[:, ks.M_FORCES_DONE] == 1.0).sum() > 500
