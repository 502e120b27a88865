"""Inputs besides the crank: an oscillating rocker driven through a swing by a
cam law, a slider driven along its guide by a stroke table, and a second crank
geared to the first.  Study format, the laws against their definitions, the
kinematics against the 60-digit reference of tests/support/naive.py over a full
cycle, kinetostatics against the naive dense solve (with the inputs' drives as
unknowns) and virtual power with eps1 != 0, and a sweep over an input's
dimensions with its Pareto analysis."""

import dataclasses
import math

import mpmath
import numpy as np
import pytest

from support import naive
from support.references import against_mp_reference
from pipeline.group_types import G_CRANK, G_INPUT
from pipeline.kernels import config as kc
from pipeline.kernels.inputs import linear_law, rise_return, table_law
from pipeline.model.groups.law import Law
from pipeline.model.groups.rotary_input import RotaryInput
from pipeline.model.groups.slider_input import SliderInput
from pipeline.solve.scene import revolution_angles, run_scene, solve_curves
from pipeline.runs.sweep import build_problem
from pipeline.study.reader import load_study, parse_study
from pipeline.base.errors import StudyError
from pipeline.study.sweep_spec import parameter_rows
from pipeline.study.sampling import draw_candidates
from support.lanes import assert_force_lanes_round, assert_lanes_agree, widened_draws
from support.power import virtual_power
from support.tolerances import FAIL_ANGLE_RAD, REACTION_MP_REL, VIRTUAL_POWER_REL

DEG = math.pi / 180.0
N_CYCLE = 36
STUDIES = ("feed_fivebar", "cam_rocker_input", "actuator_slider_input")


# ------------------------------------------------------------------ the laws
def _mp_derivatives(f, phi):
    """f, f', f'' at phi by mpmath's own differentiation at 40 digits."""
    with mpmath.workdps(40):
        x = mpmath.mpf(phi)
        return [float(mpmath.diff(f, x, k)) for k in range(3)]


@pytest.mark.parametrize("cycloidal", [False, True])
@pytest.mark.parametrize("rise_deg", [180.0, 120.0, 250.0])
def test_rise_return_laws_match_their_definition(cycloidal, rise_deg):
    start, travel, phase, rise = 0.3, -0.7, 40 * DEG, rise_deg * DEG
    rng = np.random.default_rng(3)
    for phi in rng.uniform(-2 * math.pi, 4 * math.pi, 40):
        u = (phi - phase) % (2 * math.pi)
        if min(abs(u), abs(u - rise), abs(u - 2 * math.pi)) < 1e-3:
            continue                      # mpmath.diff must not straddle a turning point
        ref = _mp_derivatives(lambda x: naive.mp_rise_return(x, start, travel, phase, rise,
                                                             cycloidal), phi)
        got = rise_return(phi, start, travel, phase, rise, cycloidal)
        for k in range(3):
            assert abs(got[k] - ref[k]) <= 1e-13 * (1 + abs(ref[k])), (phi, k, got, ref)


def test_rise_return_turns_at_the_rise_and_closes_the_cycle():
    for cyc in (False, True):
        q0 = rise_return(0.2, 1.0, 2.0, 0.2, 2.0, cyc)
        top = rise_return(2.2, 1.0, 2.0, 0.2, 2.0, cyc)
        again = rise_return(0.2 + 2 * math.pi, 1.0, 2.0, 0.2, 2.0, cyc)
        assert q0[0] == 1.0 and abs(top[0] - 3.0) < 1e-15 and again[0] == q0[0]
        assert q0[1] == 0.0 and abs(top[1]) < 1e-15
        if cyc:                           # cycloidal: no jump of acceleration at the ends
            assert abs(q0[2]) < 1e-15 and abs(top[2]) < 1e-14


def test_linear_law():
    assert linear_law(0.7, -2.0, 0.25) == (0.25 - 1.4, -2.0, 0.0)


def test_table_law_is_the_periodic_spline_through_the_table():
    rng = np.random.default_rng(5)
    cycle = np.sort(rng.choice(np.arange(0, 360, 7), 9, replace=False)) + 11.0
    values = rng.uniform(-5, 5, 9)
    law = Law("table", phase=0.4, table=tuple(zip(np.radians(cycle), values)))
    knots, coef = law.spline()
    ref = naive.MpPeriodicSpline(np.radians(cycle), values)
    for c, v in zip(cycle, values):          # through every point, also a cycle later
        for shift in (0.0, 2 * math.pi, -4 * math.pi):
            q = table_law(math.radians(c) + 0.4 + shift, 0.4, knots, coef)[0]
            assert abs(q - v) <= 1e-13 * 5, (c, q, v)
    for phi in rng.uniform(-7, 7, 40):
        u = (phi - 0.4 - knots[0]) % (2 * math.pi) + knots[0]
        if np.min(np.abs(knots - u)) < 1e-3:
            continue
        want = _mp_derivatives(lambda x: ref(x - mpmath.mpf(0.4)), phi)
        got = table_law(phi, 0.4, knots, coef)
        for k in range(3):
            assert abs(got[k] - want[k]) <= 1e-12 * (1 + abs(want[k])), (phi, k, got, want)


# ------------------------------------------------------------------ study format
def _broken(studies, name, old, new):
    text = (studies / f"{name}.toml").read_text()
    assert old in text, old
    return text.replace(old, new, 1)


LINEAR = 'law = { type = "linear", ratio = 1, phase = 90.0 }'
CYCLOIDAL = 'law = { type = "cycloidal", start = 30.0, travel = 40.0, phase = 0.0, rise = 150.0 }'
TABLE_CYCLE = "cycle = [0, 30, 60,"
ERRORS = [
    ("feed_fivebar", (LINEAR, LINEAR.replace("ratio = 1", "ratio = 1.5")),
     "mechanism.groups[0].law.ratio", "must be a whole number"),
    ("feed_fivebar", (LINEAR, LINEAR.replace("ratio = 1", "ratio = 0")),
     "mechanism.groups[0].law.ratio", "must not be zero"),
    ("feed_fivebar", (LINEAR, LINEAR.replace('"linear"', '"sine"')),
     "mechanism.groups[0].law.type", "must be one of harmonic, cycloidal, table, linear"),
    ("feed_fivebar", (LINEAR, LINEAR.replace("phase", "phaze")),
     "mechanism.groups[0].law.phaze", "unknown key"),
    ("feed_fivebar", ('pivot = "P4"', 'pivot = "P2"'),
     "mechanism.groups[0].pivot", "must be a fixed point"),
    ("feed_fivebar", ('tip = "P5"', 'tip = "P2"'),
     "mechanism.groups[0].tip", "defined twice"),
    ("feed_fivebar", ("length = 9.0", "length = -9.0"),
     "mechanism.groups[0].length", "must be positive"),
    ("feed_fivebar", (LINEAR, ""),
     "mechanism.groups[0].law", "required field is missing"),
    ("cam_rocker_input", (CYCLOIDAL, CYCLOIDAL.replace("rise = 150.0", "rise = 360.0")),
     "mechanism.groups[0].law.rise", "less than 360 deg"),
    ("cam_rocker_input", (CYCLOIDAL, CYCLOIDAL.replace("travel = 40.0", "travel = 0.0")),
     "mechanism.groups[0].law.travel", "must not be zero"),
    ("actuator_slider_input", ('type = "table"', 'type = "linear", ratio = 1'),
     "mechanism.groups[0].law.type", "a slider input cannot follow a linear law"),
    ("actuator_slider_input", (TABLE_CYCLE, "cycle = [0, 30, 20,"),
     "mechanism.groups[0].law.cycle", "cycle angles must increase"),
    ("actuator_slider_input", (TABLE_CYCLE, "cycle = [0, 30, 60, 65,"),
     "mechanism.groups[0].law.values", "13 cycle angles, 12 values"),
    ("actuator_slider_input", (TABLE_CYCLE, "cycle = [-40, 30, 60,"),
     "mechanism.groups[0].law.cycle", "must be less than the first + 360 deg"),
    ("actuator_slider_input", ('guide_point = "P4"', 'guide_point = "P3"'),
     "mechanism.groups[0].guide_point", "solved later"),
]


@pytest.mark.parametrize("name,change,field,reason", ERRORS,
                         ids=[f"{e[0]}-{e[2]}-{i}" for i, e in enumerate(ERRORS)])
def test_declaration_error_names_file_field_reason(studies, tmp_path, name, change, field, reason):
    path = tmp_path / "bad_study.toml"
    path.write_text(_broken(studies, name, *change))
    with pytest.raises(StudyError) as e:
        load_study(path)
    msg = str(e.value)
    assert str(path) in msg and field in msg and reason in msg, msg


def test_a_table_may_close_the_cycle_itself(studies, tmp_path):
    text = (studies / "actuator_slider_input.toml").read_text()
    closed = text.replace("300, 330]", "300, 330, 360]").replace("2.0, 0.0] }", "2.0, 0.0, 0.0] }")
    path = tmp_path / "closed.toml"
    path.write_text(closed)
    a = load_study(path).mechanism.groups[0].law
    assert a == load_study(studies / "actuator_slider_input.toml").mechanism.groups[0].law
    path.write_text(closed.replace("2.0, 0.0, 0.0] }", "2.0, 0.0, 1.0] }"))
    with pytest.raises(StudyError, match=r"law\.values.*closes at 360 deg with 1 mm"):
        load_study(path)


def test_the_inputs_are_declared_as_written(studies):
    g = load_study(studies / "feed_fivebar.toml").mechanism.groups[0]
    assert g == RotaryInput("P4", "P5", 9.0, Law("linear", ratio=1.0, phase=math.pi / 2),
                            "second crank")
    g = load_study(studies / "cam_rocker_input.toml").mechanism.groups[0]
    assert g.law == Law("cycloidal", phase=0.0, start=30 * DEG, travel=40 * DEG,
                        rise=150 * DEG)
    g = load_study(studies / "actuator_slider_input.toml").mechanism.groups[0]
    assert isinstance(g, SliderInput) and (g.guide_point, g.block, g.guide_angle) == \
        ("P4", "P5", 0.0)
    assert g.law.table[3] == (90 * DEG, 12.0)
    plan = load_study(studies / "cam_rocker_input.toml").mechanism.compile()
    assert list(plan.par_names[plan.goff[1]:plan.goff[1] + 5]) == \
        ["rocker.length", "rocker.start_angle", "rocker.travel_angle", "rocker.phase_angle",
         "rocker.rise_angle"]
    assert list(plan.codes[:2]) == [G_CRANK, G_INPUT]
    assert plan.input_names == ("rocker",) and list(plan.input_body) == [1]


# ------------------------------------------------------------------ kinematics
CHAINS = {"feed_fivebar": ("fivebar", naive.FIVEBAR_DATA),
          "cam_rocker_input": ("cam_rocker", naive.CAM_ROCKER_DATA),
          "actuator_slider_input": ("actuator", naive.ACTUATOR_DATA)}


def _cycle(study, n=N_CYCLE):
    crank = study.mechanism.crank
    plan = study.mechanism.compile()
    c = solve_curves(plan, revolution_angles(crank, n), kc.ACCELERATIONS,
                     close_at=crank.phi0 + crank.rot * 2 * math.pi)
    return plan, c


@pytest.mark.parametrize("name", STUDIES)
def test_inputs_match_the_60_digit_reference_over_a_cycle(studies, name):
    """Positions, first and second analogs of every point, within
    MP_REFERENCE_REL of each one's largest value over the cycle."""
    plan, c = _cycle(load_study(studies / f"{name}.toml"))
    assert (c.status == kc.OK).all()
    kind, data = CHAINS[name]
    chain = naive.InputChain(kind, data)
    _, names = against_mp_reference(plan, c, chain, planned_only=True, label=name)
    assert len(names) >= 5


def test_the_geared_crank_keeps_its_phase_and_ratio(studies):
    """The second crank's angle is phase + ratio * phi1 at every position, with
    a ratio of -2 too (counter-rotating at twice the speed)."""
    study = load_study(studies / "feed_fivebar.toml")
    m = study.mechanism
    for ratio in (1.0, -2.0):
        g = dataclasses.replace(m.groups[0], law=Law("linear", ratio=ratio, phase=math.pi / 2))
        st = dataclasses.replace(study, mechanism=dataclasses.replace(
            m, groups=(g,) + m.groups[1:]))
        plan, c = _cycle(st, 72)
        i4, i5 = plan.point("P4"), plan.point("P5")
        ang = np.arctan2(c.pos[:, i5, 1] - c.pos[:, i4, 1], c.pos[:, i5, 0] - c.pos[:, i4, 0])
        want = math.pi / 2 + ratio * c.phi
        assert np.abs(np.angle(np.exp(1j * (ang - want)))).max() < 1e-14
        v = c.d1[:, i5] - c.d1[:, i4]
        assert np.allclose(np.hypot(*v.T), 9.0 * abs(ratio), rtol=1e-14)


# ------------------------------------------------------------------ kinetostatics
def _with_eps(study, eps1):
    m = study.mechanism
    return dataclasses.replace(study, mechanism=dataclasses.replace(
        m, crank=dataclasses.replace(m.crank, eps1=eps1)))


@pytest.mark.parametrize("name", STUDIES)
def test_virtual_power_with_the_inputs_driven(studies, name):
    """M_bal (the main shaft's moment, every input's share included) * omega1
    + the power of every load, gravity and inertia = 0, with eps1 != 0."""
    study = _with_eps(load_study(studies / f"{name}.toml"), -250.0)
    res = run_scene(study)
    assert res.dense.forces.drive.shape[1] == 1
    for curves in (res.table, res.dense):
        total, scale = virtual_power(study, res.plan, curves, curves.forces)
        assert np.isfinite(total).all()
        rel = np.abs(total) / scale
        assert rel.max() <= VIRTUAL_POWER_REL, f"{name}: {rel.max():.2e}"


@pytest.mark.parametrize("name,naive_fn,input_name", [
    ("feed_fivebar", naive.naive_forces_fivebar, "second crank"),
    ("actuator_slider_input", naive.naive_forces_actuator, "actuator")])
def test_reactions_and_drives_match_the_naive_dense_solve(studies, name, naive_fn, input_name):
    study = _with_eps(load_study(studies / f"{name}.toml"), 120.0)
    crank = study.mechanism.crank
    res = run_scene(study)
    fr = res.table.forces
    plan = res.plan
    for k, phi in enumerate(res.table.phi[:-1]):
        ref = naive_fn(float(phi), omega1=crank.omega1, eps1=crank.eps1)
        scale = max(np.abs(ref[j]).max() for j in plan.joint_names)
        for j, jn in enumerate(plan.joint_names):
            assert np.abs(fr.R[k, j] - ref[jn]).max() <= REACTION_MP_REL * scale, (phi, jn)
        for s, sn in enumerate(plan.slide_names):
            assert np.abs(fr.slide[k, s] - ref[sn]).max() <= REACTION_MP_REL * scale, (phi, sn)
        drive, share = fr.drive[k, 0]
        assert abs(drive - ref[input_name]) <= REACTION_MP_REL * (abs(ref[input_name]) + 1e-3)
        want_share = ref[input_name] * ref["q1"][input_name]
        assert abs(share - want_share) <= REACTION_MP_REL * (abs(ref["M_bal"]) + abs(want_share))
        assert abs(fr.M_bal[k] - (ref["M_bal"] + want_share)) <= \
            REACTION_MP_REL * (abs(ref["M_bal"]) + abs(want_share))


@pytest.mark.parametrize("name,naive_fn,input_name,units", [
    ("cam_rocker_input", None, "rocker", "N·m"),
    ("actuator_slider_input", naive.naive_forces_actuator, "actuator", "N")])
def test_the_drives_are_in_the_scene_file(studies, tmp_path, name, naive_fn, input_name, units):
    """A scene file keeps each input's drive and share at the table and dense
    positions, named and with units; the actuator's are naive.py's dense solve
    (60-digit kinematics) at every table position, and every share is the
    drive times dq/dphi1 (the cam's law from naive.py's closed form)."""
    import h5py
    from pipeline.runner import run_study
    study = load_study(studies / f"{name}.toml")
    crank = study.mechanism.crank
    out = tmp_path / f"{name}.h5"
    run_study(studies / f"{name}.toml", out)
    with h5py.File(out, "r") as f:
        for grid in ("table", "dense"):
            d = f[f"{grid}/input_drive"]
            assert d.attrs["units"] == units and list(d.attrs["inputs"]) == [input_name]
            assert f[f"{grid}/input_share"].attrs["units"] == "N·m"
        phi = np.radians(f["table/phi1"][()])
        drive = f["table/input_drive"][:, 0]
        share = f["table/input_share"][:, 0]
    assert len(phi) == 13
    law = study.mechanism.groups[0].law
    for k in range(12):
        if naive_fn is not None:
            ref = naive_fn(float(phi[k]), omega1=crank.omega1, eps1=crank.eps1)
            assert abs(drive[k] - ref[input_name]) <= \
                REACTION_MP_REL * (abs(ref[input_name]) + 1e-3), (k, drive[k], ref[input_name])
            q1 = ref["q1"][input_name]
        else:      # the cam's dq/dphi1 (rad/rad), the law differentiated at 30 digits
            with mpmath.workdps(30):
                q1 = float(mpmath.diff(lambda x: naive.mp_rise_return(
                    x, law.start, law.travel, law.phase, law.rise, law.kind == "cycloidal"),
                    mpmath.mpf(float(phi[k]))))
            assert np.isfinite(drive[k])
        assert abs(share[k] - drive[k] * q1) <= REACTION_MP_REL * (abs(share[k]) + 1e-3), k
    assert np.abs(share).max() > 0


@pytest.mark.parametrize("name", STUDIES)
def test_m_bal_is_the_lagrange_moment_of_the_whole_machine(studies, name):
    """The main shaft's moment from kinetostatics equals the Lagrange equation
    on phi1, J eps1 + (1/2) J' omega1^2 - Q: the inputs' inertia enters the
    reduced moment of inertia through their analogs, and their drives reach
    the shaft through q' (two independent routes to the same number)."""
    from pipeline.solve.reduced_dynamics import reduced_terms
    study = _with_eps(load_study(studies / f"{name}.toml"), 75.0)
    crank = study.mechanism.crank
    res = run_scene(study)
    fr = res.table.forces
    phi = res.table.phi
    J, half, Q = reduced_terms(res.plan, phi, mechanism=study.mechanism)
    want = J * crank.eps1 + half * crank.omega1 ** 2 - Q
    scale = np.abs(want).max()
    assert np.abs(fr.M_bal - want).max() <= 1e-9 * scale, np.abs(fr.M_bal - want).max() / scale


# ------------------------------------------------------------------ a sweep over an input
SWEEP_N = 160


@pytest.fixture(scope="module")
def cam_sweep(studies, tmp_path_factory):
    from support.sweep_helpers import run_and_analyze
    return run_and_analyze(studies / "cam_rocker_input_sweep.toml",
                           tmp_path_factory.mktemp("cam_sweep") / "cam.h5", SWEEP_N)


def test_sweep_over_the_cam_law_matches_the_scene_path(cam_sweep):
    """The law's swing and rise (deg in the study and the file, rad in the
    plan) and the arms' lengths are design variables: each candidate's peaks
    are those of its own scene."""
    import h5py
    from pipeline.solve.reactions import scene_forces
    from pipeline.study.sweep_spec import apply_design
    from support.tolerances import SWEEP_VS_SCENE_REL
    study, path = cam_sweep
    with h5py.File(path, "r") as f:
        x = f["candidates/params"][()]
        status = f["candidates/status"][()]
        m = {k: f[f"metrics/{k}"][()] for k in ("peak_reaction", "peak_acceleration",
                                                "peak_M_bal", "stroke")}
    assert (status == kc.OK).mean() > 0.9
    assert x[:, 1].min() >= 120.0 and x[:, 1].max() <= 220.0 and np.ptp(x[:, 1]) > 80.0
    # the force stage runs for the candidates that meet the stroke constraint
    feasible = [k for k in range(SWEEP_N) if status[k] == kc.OK and m["stroke"][k] >= 20.0]
    assert np.isfinite(m["peak_reaction"][feasible]).all()
    for i in feasible[:3]:
        mech = apply_design(study.mechanism, study.sweep, x[i])
        rocker = next(g for g in mech.groups if isinstance(g, RotaryInput))
        assert (rocker.law.travel, rocker.law.rise, rocker.length) == \
            (x[i, 0] * DEG, x[i, 1] * DEG, x[i, 2])
        plan = mech.compile()
        crank = mech.crank
        c = solve_curves(plan, revolution_angles(crank, study.sweep.positions), kc.ACCELERATIONS,
                         close_at=crank.phi0 + crank.rot * 2 * math.pi)
        fr = scene_forces(mech, plan, c)
        acc = np.hypot(*c.d2[:, plan.point("P6")].T) * crank.omega1 ** 2 / 1000.0
        arm = c.pos[:, plan.point("P5")] - c.pos[:, plan.point("P4")]
        swing = np.ptp(np.arctan2(arm[:, 1], arm[:, 0]))       # on the sweep's grid
        assert swing == pytest.approx(x[i, 0] * DEG, rel=1e-5)
        for key, want in (("peak_reaction", fr.magnitude.max()),
                          ("peak_M_bal", np.abs(fr.M_bal).max()), ("peak_acceleration", acc.max()),
                          ("stroke", study.sweep.stroke_radius * swing)):
            assert m[key][i] == pytest.approx(want, rel=SWEEP_VS_SCENE_REL), (i, key)


def test_pareto_analysis_of_the_cam_sweep(cam_sweep):
    from support.sweep_helpers import assert_fronts_are_the_brute_force_rank
    assert_fronts_are_the_brute_force_rank(cam_sweep[1])


def test_a_gear_ratio_cannot_be_swept(studies, tmp_path):
    text = (studies / "cam_rocker_input_sweep.toml").read_text()
    path = tmp_path / "bad.toml"
    path.write_text(text.replace('rise = { param = "rocker.rise_angle", min = 120.0, max = 220.0 }',
                                 'rise = { param = "rocker.rise_angle", min = 120.0, max = 360.0 }'))
    with pytest.raises(StudyError, match=r"sweep\.variables\.rise\.max.*within \(0, 360\) deg"):
        load_study(path)
    five = (studies / "feed_fivebar.toml").read_text().replace('kind = "scene"', 'kind = "sweep"')
    five += ('\n[sweep]\ncandidates = 10\n[sweep.variables]\n'
             'r = { param = "second crank.ratio", min = 1.0, max = 3.0 }\n')
    five = five.replace('analysis = "forces"', 'analysis = "forces"\nrocker = ["P5", "P3"]')
    path.write_text(five)
    with pytest.raises(StudyError, match=r"sweep\.variables\.r\.param.*gear ratio"):
        load_study(path)


# ------------------------------------------------------------------ between the samples
@pytest.mark.parametrize("law", ["cycloidal", "harmonic"])
@pytest.mark.parametrize("link", [37.9, 38.02, 38.029])
def test_a_lock_between_two_positions_is_found_where_it_begins(studies, law, link):
    """The link P5-P6 is too short at the top of the rocker's swing: the
    sinker bar cannot be reached in a window (34 deg wide down to under 2)
    that 36 positions may straddle.  The link folds at the window's first
    angle, a dead position the crank cannot pass: SINGULAR there (from the law's own formula by brentq), within
    1e-10 rad, for the smooth cycloidal law and for a harmonic one whose
    acceleration jumps at the top (rise 130 deg); the top of the swing lies
    5 deg from the nearest position."""
    from scipy.optimize import brentq
    study = load_study(studies / "cam_rocker_input.toml")
    m = study.mechanism
    rocker = m.groups[0]
    rocker = dataclasses.replace(rocker, law=dataclasses.replace(
        rocker.law, kind=law, phase=5 * DEG,
        rise=130 * DEG if law == "harmonic" else rocker.law.rise))
    mech = dataclasses.replace(m, groups=(rocker, dataclasses.replace(m.groups[1], L_AB=link)))
    plan = mech.compile()
    c = solve_curves(plan, revolution_angles(mech.crank, 36), kc.ACCELERATIONS,
                     close_at=2 * math.pi)
    lw = rocker.law

    def gap(p):      # > 0 where the link cannot reach the guide x = 80 mm (naive.py, 30 digits)
        with mpmath.workdps(30):
            q = naive.mp_rise_return(mpmath.mpf(p), lw.start, lw.travel, lw.phase, lw.rise,
                                     law == "cycloidal")
            return float(80 - (30 + 35 * mpmath.cos(q)) - link)

    # bracket on a fine grid with the law's closed form (README), then brentq on gap
    grid = np.radians(np.linspace(0.0, 360.0, 360001))
    u = (grid - lw.phase) % (2 * math.pi)
    x = np.where(u < lw.rise, u / lw.rise, (2 * math.pi - u) / (2 * math.pi - lw.rise))
    f = x - np.sin(2 * math.pi * x) / (2 * math.pi) if law == "cycloidal" else \
        (1 - np.cos(math.pi * x)) / 2
    v = 80.0 - (30.0 + 35.0 * np.cos(lw.start + lw.travel * f)) - link
    k = int(np.argmax(v > 0))
    assert k > 0 and (v > 0).sum() < len(v) * 0.1
    begin = brentq(gap, grid[k - 1], grid[k], xtol=1e-15)
    inside = [gap(p) > 0 for p in revolution_angles(mech.crank, 36)]
    if link == 38.029:                       # the window lies between two positions
        assert not any(inside)
    assert c.overall == kc.SINGULAR          # the dyad folds there: a dead position
    assert plan.group_names[int(c.fail_group)] == "lift"
    assert abs(c.fail_phi - begin) <= FAIL_ANGLE_RAD, c.fail_phi - begin


def test_the_drives_are_in_reactions_csv(studies, tmp_path):
    import pandas as pd
    from pipeline.cli import main
    out = tmp_path / "act.h5"
    assert main(["run", str(studies / "actuator_slider_input.toml"), "-o", str(out), "-q",
                 "--no-pictures"]) == 0
    assert main(["export", str(out), "--csv", str(tmp_path / "csv")]) == 0
    df = pd.read_csv(tmp_path / "csv" / "reactions.csv")
    res = run_scene(load_study(studies / "actuator_slider_input.toml"))
    fr = res.dense.forces                   # the CSV holds the dense positions, 12 digits
    n = len(df)
    assert n >= 360
    np.testing.assert_allclose(df["drive[actuator] [N]"], fr.drive[:n, 0, 0], rtol=1e-10,
                               atol=1e-12)
    np.testing.assert_allclose(df["share[actuator] [N·m]"], fr.drive[:n, 0, 1], rtol=1e-10,
                               atol=1e-15)
    np.testing.assert_allclose(df["M_bal [N·m]"], fr.M_bal[:n], rtol=1e-10, atol=1e-15)


# ------------------------------------------------------------------ laws the positions resolve
# a law steeper than the positions that sample it swung unseen between them: the cam with
# a 1 deg rise reported a peak acceleration of 14 m/s², status OK, where it is 1.8e6
STEEP = [
    ("cam_rocker_input", (CYCLOIDAL, CYCLOIDAL.replace("rise = 150.0", "rise = 1")),
     "mechanism.groups[0].law.rise", "at least 8 positions within its rise"),
    ("cam_rocker_input", (CYCLOIDAL, CYCLOIDAL.replace("rise = 150.0", "rise = 7.9")),
     "mechanism.groups[0].law.rise", "give a rise of 8 to 352 deg, or 365 positions"),
    ("cam_rocker_input", (CYCLOIDAL, CYCLOIDAL.replace("rise = 150.0", "rise = 355")),
     "mechanism.groups[0].law.rise", "law's return takes 5 deg"),
    ("cam_rocker_input", ("dense_positions = 360", "dense_positions = 16"),
     "mechanism.groups[0].law.rise", "(output.dense_positions = 16)"),
    ("feed_fivebar", (LINEAR, LINEAR.replace("ratio = 1", "ratio = 50")),
     "mechanism.groups[0].law.ratio", "a ratio of at most 45, or 400 positions"),
    ("actuator_slider_input", (TABLE_CYCLE, "cycle = [0, 30, 30.5,"),
     "mechanism.groups[0].law.cycle", "shortest spline piece, 30 to 30.5 deg"),
    ("cam_rocker_input_sweep", ("min = 120.0, max = 220.0", "min = 2.0, max = 220.0"),
     "sweep.variables.rise.min", "rocker.rise_angle = 2 deg"),
    ("cam_rocker_input_sweep", ("min = 120.0, max = 220.0", "min = 120.0, max = 355.0"),
     "sweep.variables.rise.max", "return takes 5 deg"),
    ("cam_rocker_input_sweep", ("positions = 360", "positions = 20"),
     "sweep.variables.rise.min", "give a rise of 144 to 216 deg, or 25 positions "
     "(sweep.positions = 20)"),
    ("cam_rocker_input_sweep", ("positions = 360", "positions = 18"),
     "mechanism.groups[0].law.rise", "(sweep.positions = 18)"),
]


@pytest.mark.parametrize("name,change,field,reason", STEEP,
                         ids=[f"{e[0]}-{e[2]}-{i}" for i, e in enumerate(STEEP)])
def test_a_law_steeper_than_its_positions_is_refused(studies, name, change, field, reason):
    from pipeline.study.reader import parse_study
    with pytest.raises(StudyError) as e:
        parse_study(_broken(studies, name, *change), "steep.toml")
    msg = str(e.value)
    assert field in msg and reason in msg and len(msg.splitlines()) == 1, msg


def test_laws_the_positions_resolve_load(studies):
    from pipeline.study.reader import parse_study
    for name, old, new in [
            ("cam_rocker_input", "rise = 150.0", "rise = 8"),
            ("cam_rocker_input", "rise = 150.0", "rise = 352"),
            ("cam_rocker_input", "dense_positions = 360", "dense_positions = 720\n# rise 4"),
            ("feed_fivebar", "ratio = 1,", "ratio = 45,"),
            ("actuator_slider_input", TABLE_CYCLE, "cycle = [0, 30, 32,")]:
        text = _broken(studies, name, old, new)
        if "rise 4" in new:
            text = text.replace("rise = 150.0", "rise = 4")
        parse_study(text, "ok.toml")


def _cycloid_peak_acceleration(rise, travel, phase, length, omega):
    """max over the cycle of |a| (m/s²) of the tip of a rotary input at
    ``length`` mm moved by a cycloidal law, from the law's own formula on 2e6
    points (no kernel): a = length omega^2 (q'' n - q'^2 e)."""
    phi = np.linspace(0.0, 2.0 * np.pi, 2_000_001)
    r, T = math.radians(rise), math.radians(travel)
    u = np.mod(phi - math.radians(phase), 2.0 * np.pi)
    up = u < r
    x = np.where(up, u / r, (2.0 * np.pi - u) / (2.0 * np.pi - r))
    s = np.where(up, 1.0 / r, -1.0 / (2.0 * np.pi - r))
    q1 = T * (1.0 - np.cos(2.0 * np.pi * x)) * s
    q2 = T * 2.0 * np.pi * np.sin(2.0 * np.pi * x) * s * s
    return float(np.max(length * omega ** 2 * np.sqrt(q2 ** 2 + q1 ** 4))) / 1000.0


def test_the_steepest_law_allowed_has_its_exact_peak(studies):
    """The cam's rise over 8 positions (8 deg of 360), not aligned with them: the
    scene's refined peak acceleration of the rocker's tip is the law's own."""
    from pipeline.solve.peaks import scene_peaks
    from pipeline.study.reader import parse_study
    text = _broken(studies, "cam_rocker_input", CYCLOIDAL,
                   CYCLOIDAL.replace("rise = 150.0", "rise = 8").replace("phase = 0.0",
                                                                         "phase = 0.37"))
    res = run_scene(parse_study(text, "steep.toml"))
    assert res.status == kc.OK
    peak = next(p for p in scene_peaks(res) if p.quantity == "acceleration" and p.item == "P5")
    ref = _cycloid_peak_acceleration(8.0, 40.0, 0.37, 35.0, 60.0)
    assert ref > 2.8e4 and peak.grid_value < 0.98 * ref     # the grid alone misses it
    assert peak.value == pytest.approx(ref, rel=1e-7)


# ----------------------------------------------------------------- the lanes
def test_input_and_rrp_lanes_agree_with_the_careful_path(studies):
    """The cam-driven rocker (a rotary input on a cycloidal law, an RRP on a
    guide of fixed direction, forces and peaks) in the lanes: the input's law
    from a table the lane fills by the careful path's own calls, the RRP by its
    careful lines on the hoisted guide direction.  The link's lower bound
    brought down so that a share of the draws cannot reach the sinker bar's
    guide all the way round: the RRP's toggle, which the lanes hand over."""
    pb, pars = widened_draws(studies, "cam_rocker_input_sweep",
                             [("min = 42.0, max = 55.0", "min = 30.0, max = 55.0")], 2000)
    status = assert_lanes_agree(pb, pars, class3=False)
    assert (status != kc.OK).sum() > 100
    assert pb.kernels.HAS_LANE_FORCES and pb.kernels.SAME_BITS


SLIDER_SWEEP = """
[output]
working_point = "P7"
rocker = ["P6", "P3"]
links = ["5_3", "6_3"]
analysis = "forces"

[sweep]
candidates = 1500
seed = 3
positions = 360
chunk_size = 1500
stroke_radius = 30.0
objectives = ["peak_acceleration", "peak_reaction"]
metrics = ["peak_acceleration", "peak_reaction", "peak_M_bal", "stroke"]

[sweep.variables]
link = { param = "RRR[2].L_AB", min = 36.0, max = 48.0 }
lever = { param = "RRR[2].L_CB", min = 26.0, max = 34.0 }
guide_y = { param = "P4.y", min = -44.0, max = -36.0 }

[sweep.constraints]
stroke = { min = 5.0 }
"""


def test_a_slider_input_in_the_lanes_and_the_force_lanes(studies):
    """The programmed slide (a slider input on a table law, an RRR, a lever
    with a load) as a sweep: the lanes against the careful path, and the force
    lanes (the input's stroke and its drive along the guide, the RRR to
    rounding) against the scalar force stage: the same statuses, joints and
    angles, the peaks within the lanes' agreement."""
    text = (studies / "actuator_slider_input.toml").read_text()
    # (the scene's mechanism as it is: its module, compiled for this file's scenes,
    # is the one the sweep's module imports from)
    text = text[:text.index("[output]")].replace('kind = "scene"', 'kind = "sweep"')
    study = parse_study(text + SLIDER_SWEEP, "actuator_sweep.toml")
    pb = build_problem(study, study.sweep)
    pars = parameter_rows(pb.plan, pb.spec, draw_candidates(pb.spec, 0))
    assert_lanes_agree(pb, pars, class3=False)
    assert_force_lanes_round(pb, pars, 500)
