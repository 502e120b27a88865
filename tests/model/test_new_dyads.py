"""The slider dyads PRP (two blocks on two guides, joined by a revolute) and
RPP (Scotch yoke: a block pinned at a known point slides in the slot of a yoke
that slides on a guide): study format, kinematics against the 30-digit
reference of tests/support/naive.py and against closed forms, kinetostatics with the
slides' normal forces and couples, the between-sample watch, a sweep over a
PRP's guide and its Pareto analysis."""

import dataclasses
import math

import numpy as np
import pytest

from support import naive
from pipeline.compiler import kernels_for
from pipeline.compiler.emit import emitter_classes
from pipeline.solve.reactions import scene_forces
from pipeline.kernels import config as kc
from pipeline.group_types.prp import G_PRP
from pipeline.group_types.prp.model import PRP
from pipeline.group_types.rpp import G_RPP
from pipeline.group_types.rpp.model import RPP
from pipeline.solve.scene import revolution_angles, solve_curves
from pipeline.study.reader import load_study, parse_study
from pipeline.base.errors import StudyError
from pipeline.kernels import sweep as ks
from pipeline.runs.sweep import build_problem
from pipeline.study.sweep_spec import parameter_rows
from pipeline.study.sampling import draw_candidates
from support.lanes import (assert_force_lanes_round, assert_lanes_agree, packed_force_lane_ops,
                           widened_draws)
from support.power import virtual_power
from support.references import against_mp_reference
from support.tolerances import FAIL_ANGLE_RAD, MP_REFERENCE_REL, REACTION_MP_REL, SELF_FD_REL, VIRTUAL_POWER_REL

DEG = math.pi / 180.0
N_CYCLE = 36                    # positions of a full cycle compared with the reference


def _study(studies, name, **group_changes):
    """A study of studies/ with its slider dyad's fields replaced."""
    study = load_study(studies / f"{name}.toml")
    m = study.mechanism
    groups = tuple(dataclasses.replace(g, **group_changes) if isinstance(g, (PRP, RPP)) else g
                   for g in m.groups)
    return dataclasses.replace(study, mechanism=dataclasses.replace(m, groups=groups))


def _cycle(study, n=N_CYCLE, order=kc.ACCELERATIONS):
    crank = study.mechanism.crank
    plan = study.mechanism.compile()
    c = solve_curves(plan, revolution_angles(crank, n), order,
                     close_at=crank.phi0 + crank.rot * 2 * math.pi)
    return plan, c


# ------------------------------------------------------------------ study format
def _broken(studies, name, old, new):
    text = (studies / f"{name}.toml").read_text()
    assert old in text, old
    return text.replace(old, new, 1)


ERRORS = [
    # (study, change, field named in the message, reason fragment)
    ("slotted_rocker_prp", ('guide1_point = "P4"', 'guide1_point = "P9"'),
     "mechanism.groups[1].guide1_point", "unknown point 'P9'"),
    ("slotted_rocker_prp", ('guide1_link = ["P4", "P3"]', 'guide1_link = ["P4", "P4"]'),
     "mechanism.groups[1].guide1_link", "two different points"),
    ("slotted_rocker_prp", ('guide1_link = ["P4", "P3"]', 'guide1_link = ["P4"]'),
     "mechanism.groups[1].guide1_link", "expected 2 names"),
    ("slotted_rocker_prp", ("guide2_offset = 0.0", 'guide2_offset = "up"'),
     "mechanism.groups[1].guide2_offset", "expected a number"),
    ("slotted_rocker_prp", ("guide1_angle = 0.0", "guide1_angle = nan"),
     "mechanism.groups[1].guide1_angle", "must be finite"),
    ("slotted_rocker_prp", ('guide1_link = ["P4", "P3"]\n', ""),
     "mechanism.groups[1].guide2_angle", "the two guides are parallel"),
    ("slotted_rocker_prp", ('B = "P5"', 'B = "P3"'),
     "mechanism.groups[1].B", "defined twice"),
    ("slotted_rocker_prp", ("guide2_offset = 0.0", "guide2_offset = 0.0\nguide3_offset = 1.0"),
     "mechanism.groups[1].guide3_offset", "unknown key"),
    ("slotted_rocker_prp", ('guide2_point = "P6"', 'guide2_point = "P5"'),
     "mechanism.groups[1].guide2_point", "point 'P5' is solved later"),
    ("scotch_yoke_rpp", ("slot_angle = 90.0", "slot_angle = 180.0"),
     "mechanism.groups[0].slot_angle", "the slot runs along the guide"),
    ("scotch_yoke_rpp", ('A = "P2"', 'A = "P7"'),
     "mechanism.groups[0].A", "unknown point 'P7'"),
    ("scotch_yoke_rpp", ('A = "P2"', 'A = "P3"'),
     "mechanism.groups[0].A", "solved later"),
    ("scotch_yoke_rpp", ('guide_point = "P1"', "guide_point = 1"),
     "mechanism.groups[0].guide_point", "expected a string"),
    ("scotch_yoke_rpp", ("slot_offset = 0.0", "slot_offset = [0.0]"),
     "mechanism.groups[0].slot_offset", "expected a number"),
]


@pytest.mark.parametrize("name,change,field,reason", ERRORS, ids=[f"{e[0]}-{e[2]}" for e in ERRORS])
def test_declaration_error_names_file_field_reason(studies, tmp_path, name, change, field, reason):
    path = tmp_path / "bad_study.toml"
    path.write_text(_broken(studies, name, *change))
    with pytest.raises(StudyError) as e:
        load_study(path)
    msg = str(e.value)
    assert str(path) in msg and field in msg and reason in msg, msg


def test_the_groups_are_declared_as_written(studies):
    prp = load_study(studies / "slotted_rocker_prp.toml").mechanism.groups[1]
    assert prp == PRP("P5", "P4", 0.0, "P6", 0.0, 0.0, 0.0, ("P4", "P3"), None, "slider")
    text = _broken(studies, "scotch_yoke_rpp", "slot_angle = 90.0", "slot_angle = 75.0")
    # the block's slide runs along the slot (a slide across it is refused)
    text = text.replace('guide = "yoke"\nangle = 90.0', 'guide = "yoke"\nangle = 75.0')
    rpp = parse_study(text.replace("guide_offset = 0.0", "guide_offset = 2.5"),
                      "x.toml").mechanism.groups[0]
    assert (rpp.A, rpp.B, rpp.guide_point, rpp.guide_link) == ("P2", "P3", "P1", None)
    assert rpp.slot_angle == math.radians(75.0) and rpp.guide_offset == 2.5
    plan = load_study(studies / "scotch_yoke_rpp.toml").mechanism.compile()
    assert [plan.par_names[i] for i in range(plan.param("yoke.guide_angle"),
                                             plan.param("yoke.slot_offset") + 1)] == \
        ["yoke.guide_angle", "yoke.guide_offset", "yoke.slot_angle", "yoke.slot_offset"]


# ------------------------------------------------------------------ kinematics
PRP_VARIANTS = {
    "study": {},
    "angles-offsets": dict(guide1_angle=10 * DEG, guide1_offset=4.0, guide2_angle=-15 * DEG,
                           guide2_offset=3.0),
}


@pytest.mark.parametrize("variant", list(PRP_VARIANTS))
def test_prp_matches_the_30_digit_reference(studies, variant):
    """A slot in the four-bar's rocker (a moving guide) and the frame's guide:
    every point over a full cycle."""
    ch = PRP_VARIANTS[variant]
    plan, c = _cycle(_study(studies, "slotted_rocker_prp", **ch))
    assert c.overall == kc.OK
    d = dict(naive.E_DATA, a1=ch.get("guide1_angle", 0.0), e1=ch.get("guide1_offset", 0.0),
             a2=ch.get("guide2_angle", 0.0), e2=ch.get("guide2_offset", 0.0))
    assert against_mp_reference(plan, c, naive.SliderChain("PRP", d))[0] > 0.0


RPP_VARIANTS = {
    "study": {},
    "angles-offsets": dict(guide_angle=20 * DEG, guide_offset=2.0, slot_angle=70 * DEG,
                           slot_offset=1.5),
}


@pytest.mark.parametrize("variant", list(RPP_VARIANTS))
def test_rpp_matches_the_30_digit_reference(studies, variant):
    ch = RPP_VARIANTS[variant]
    plan, c = _cycle(_study(studies, "scotch_yoke_rpp", **ch))
    assert c.overall == kc.OK
    d = dict(naive.F_DATA, a1=ch.get("guide_angle", 0.0), e1=ch.get("guide_offset", 0.0),
             slot=ch.get("slot_angle", 90 * DEG), e_s=ch.get("slot_offset", 0.0))
    against_mp_reference(plan, c, naive.SliderChain("RPP", d), rename={"P5": "P3"})


YOKE_ON_ROCKER = """
[study]
kind = "scene"
name = "yoke_on_rocker"

[mechanism.fixed]
P1 = [0.0, 0.0]
P4 = [38.0, 0.0]

[mechanism.crank]
pivot = "P1"
tip = "P2"
length = 15.0
omega1 = 60.0
eps1 = 0.0

[[mechanism.groups]]
type = "RRR"
A = "P2"
C = "P4"
B = "P3"
L_AB = 41.0
L_CB = 40.0
W = 1

[[mechanism.groups]]       # a yoke sliding along the rocker, its slot on the crank tip
type = "RPP"
name = "yoke"
A = "P2"
B = "P5"
guide_point = "P4"
guide_link = ["P4", "P3"]
guide_angle = 5.0
guide_offset = -3.0
slot_angle = 70.0
slot_offset = 2.0

[output]
working_point = "P5"
analysis = "accelerations"
"""


def test_rpp_on_a_moving_guide_matches_the_30_digit_reference():
    """The yoke slides on the four-bar's rocker: the guide and the slot turn."""
    study = parse_study(YOKE_ON_ROCKER, "yoke_on_rocker.toml")
    plan, c = _cycle(study)
    assert c.overall == kc.OK
    d = dict(L12=15.0, phiM0=0.0, fourbar=True, P4=(38.0, 0.0), L23=41.0, L43=40.0, W=1,
             g1_rocker=True, a1=5 * DEG, e1=-3.0, slot=70 * DEG, e_s=2.0)
    against_mp_reference(plan, c, naive.SliderChain("RPP", d))


TANGENT = """
[study]
kind = "scene"
name = "tangent"

[mechanism.fixed]
P1 = [0.0, 0.0]
P6 = [{h!r}, 0.0]

[mechanism.crank]
pivot = "P1"
tip = "P2"
length = 10.0
omega1 = 1.0
phi0 = {phi0!r}

[[mechanism.groups]]       # a slot in the crank and a vertical guide at x = h
type = "PRP"
name = "tangent"
B = "P5"
guide1_point = "P1"
guide1_link = ["P1", "P2"]
guide2_point = "P6"
guide2_angle = 90.0

[output]
working_point = "P5"
analysis = "accelerations"
"""


def test_prp_closed_form_tangent_mechanism():
    """Slot through the crank pivot, vertical guide x = h: B = (h, h tan phi),
    B' = (0, h / cos^2 phi), B'' = (0, 2 h tan phi / cos^2 phi)."""
    h = 40.0
    plan = parse_study(TANGENT.format(h=h, phi0=0.0), "t.toml").mechanism.compile()
    phis = np.linspace(-70 * DEG, 70 * DEG, 57)
    c = solve_curves(plan, phis, kc.ACCELERATIONS)
    assert c.overall == kc.OK
    i = plan.point("P5")
    t, sec2 = np.tan(phis), 1.0 / np.cos(phis) ** 2
    for got, want in ((c.pos[:, i], np.c_[np.full_like(t, h), h * t]),
                      (c.d1[:, i], np.c_[np.zeros_like(t), h * sec2]),
                      (c.d2[:, i], np.c_[np.zeros_like(t), 2 * h * t * sec2])):
        np.testing.assert_allclose(got, want, rtol=0, atol=MP_REFERENCE_REL * np.abs(want).max())
    # the margin is |sin| of the angle between the guides: |cos phi| here
    np.testing.assert_allclose(c.margin[:, plan.group_names.index("tangent")], np.cos(phis),
                               rtol=1e-14)


def test_rpp_closed_form_scotch_yoke(studies):
    """The yoke's point is L cos(phi1) on the guide, and the margin is |sin| of
    the slot's angle at every position."""
    study = load_study(studies / "scotch_yoke_rpp.toml")
    plan, c = _cycle(study, 72)
    L, phi = study.mechanism.crank.length, c.phi
    i = plan.point("P3")
    np.testing.assert_allclose(c.pos[:, i, 0], L * np.cos(phi), rtol=0, atol=MP_REFERENCE_REL * L)
    np.testing.assert_allclose(c.d1[:, i, 0], -L * np.sin(phi), rtol=0, atol=MP_REFERENCE_REL * L)
    np.testing.assert_allclose(c.d2[:, i, 0], -L * np.cos(phi), rtol=0, atol=MP_REFERENCE_REL * L)
    assert (c.pos[:, i, 1] == 0).all() and (c.d1[:, i, 1] == 0).all()
    assert (c.margin[:, plan.group_names.index("yoke")] == 1.0).all()


@pytest.mark.parametrize("name", ["slotted_rocker_prp", "scotch_yoke_rpp"])
def test_velocity_is_derivative_of_position(studies, name):
    """A central difference of the kernel's own positions reproduces its analogs."""
    plan = load_study(studies / f"{name}.toml").mechanism.compile()
    h = 1e-5
    nv = plan.n_visible
    for phi in np.deg2rad([17.0, 133.0, 251.0]):
        c = solve_curves(plan, np.array([phi - h, phi, phi + h]), kc.ACCELERATIONS)
        fd1 = (c.pos[2] - c.pos[0]) / (2 * h)
        fd2 = (c.pos[2] - 2 * c.pos[1] + c.pos[0]) / h ** 2
        assert np.abs(fd1[:nv] - c.d1[1, :nv]).max() <= SELF_FD_REL * np.abs(c.d1[1, :nv]).max()
        assert np.abs(fd2[:nv] - c.d2[1, :nv]).max() <= 1e-4 * np.abs(c.d2[1, :nv]).max()


# ------------------------------------------------------------------ kinetostatics
def _with_eps1(study, eps1):
    m = study.mechanism
    return dataclasses.replace(study, mechanism=dataclasses.replace(
        m, crank=dataclasses.replace(m.crank, eps1=eps1)))


@pytest.mark.parametrize("name,eps1", [("slotted_rocker_prp", 0.0), ("slotted_rocker_prp", -350.0),
                                       ("scotch_yoke_rpp", 0.0), ("scotch_yoke_rpp", 420.0)])
def test_virtual_power_identity(studies, name, eps1):
    study = _with_eps1(load_study(studies / f"{name}.toml"), eps1)
    plan, c = _cycle(study, 72)
    fr = scene_forces(study.mechanism, plan, c)
    total, scale = virtual_power(study, plan, c, fr)
    assert np.isfinite(total).all()
    assert (np.abs(total) / scale).max() <= VIRTUAL_POWER_REL


@pytest.mark.parametrize("name,reference,eps1", [
    ("slotted_rocker_prp", naive.naive_forces_e, -350.0),
    ("scotch_yoke_rpp", naive.naive_forces_f, 420.0)])
def test_reactions_and_slide_forces_match_the_dense_solve(studies, name, reference, eps1):
    """Every revolute reaction, every slide's normal force N and couple C, and
    M_bal against tests/support/naive.py's dense solve on the 30-digit kinematics."""
    study = _with_eps1(load_study(studies / f"{name}.toml"), eps1)
    plan, c = _cycle(study, 12)
    fr = scene_forces(study.mechanism, plan, c)
    crank = study.mechanism.crank
    assert fr.slide_names == ("slide[block]", f"slide[{plan.body_names[-1]}]")
    for k in range(0, 12, 2):
        ref = reference(c.phi[k], crank.omega1, eps1)
        scale = max(max(np.abs(ref[n]).max() for n in fr.joint_names),
                    max(abs(ref[n][0]) for n in fr.slide_names))
        for j, n in enumerate(fr.joint_names):
            assert np.abs(fr.R[k, j] - ref[n]).max() <= REACTION_MP_REL * scale, (k, n)
        for j, n in enumerate(fr.slide_names):
            assert abs(fr.slide[k, j, 0] - ref[n][0]) <= REACTION_MP_REL * scale, (k, n, "N")
            # a couple is a force times a lever: N*m against N at 1 mm
            assert abs(fr.slide[k, j, 1] - ref[n][1]) <= REACTION_MP_REL * scale * 1e-3, (k, n, "C")
        assert abs(fr.M_bal[k] - ref["M_bal"]) <= REACTION_MP_REL * max(abs(ref["M_bal"]), 1)


# ------------------------------------------------------------------ the between-sample watch
def test_the_new_groups_are_watched(studies):
    assert emitter_classes()[G_PRP].watched and emitter_classes()[G_RPP].watched
    for name in ("slotted_rocker_prp", "scotch_yoke_rpp"):
        study = load_study(studies / f"{name}.toml")
        plan = study.mechanism.compile()
        k = kernels_for(plan)
        g = next(i for i, code in enumerate(plan.codes) if code in (G_PRP, G_RPP))
        assert g in list(k.WATCH_G), name


@pytest.mark.parametrize("phi0_deg,rot,n", [(5.0, 1, 36), (-3.1, -1, 36), (30.0, 1, 7)])
def test_parallel_guides_between_positions_are_found(phi0_deg, rot, n):
    """The crank's slot turns parallel to the vertical guide at phi1 = +-90 deg,
    never on a sampled position: SINGULAR at the first of them met from phi0 in
    the direction of travel, located to 1e-10 rad, in the PRP group."""
    study = parse_study(TANGENT.format(h=40.0, phi0=phi0_deg).replace(
        "omega1 = 1.0", f"omega1 = {float(rot)}"), "t.toml")
    crank = study.mechanism.crank
    plan = study.mechanism.compile()
    phis = revolution_angles(crank, n)
    assert np.abs(np.cos(phis)).min() > 0.05          # no sample near a parallel position
    for order in (kc.POSITIONS, kc.VELOCITIES, kc.ACCELERATIONS):
        c = solve_curves(plan, phis, order, close_at=crank.phi0 + crank.rot * 2 * math.pi)
        assert c.overall == kc.SINGULAR, kc.STATUS_NAMES[c.overall]
        want = 90.0 if rot > 0 else -90.0
        err = abs(math.remainder(c.fail_phi - math.radians(want), 2 * math.pi))
        assert err <= FAIL_ANGLE_RAD, (math.degrees(c.fail_phi), want, err)
        assert c.fail_group == plan.group_names.index("tangent")


def test_an_oscillating_slot_that_never_turns_parallel_stays_ok(studies):
    """The slotted rocker swings between 88 and 141 deg, its slot 38 deg or more
    from the horizontal guide: OK at every position, and the margin is |sin| of
    the rocker's angle (the angle between the two guides) at each."""
    study = load_study(studies / "slotted_rocker_prp.toml")
    plan, c = _cycle(study, 360, kc.POSITIONS)
    assert c.overall == kc.OK and (c.status == kc.OK).all()
    rocker = c.pos[:, plan.point("P3")] - c.pos[:, plan.point("P4")]
    want = np.abs(np.sin(np.arctan2(rocker[:, 1], rocker[:, 0])))
    np.testing.assert_allclose(c.margin[:, plan.group_names.index("slider")], want, rtol=1e-13)


# ------------------------------------------------------------------ a sweep over a PRP's guide
SWEEP_N = 160


@pytest.fixture(scope="module")
def prp_sweep(studies, tmp_path_factory):
    from support.sweep_helpers import run_and_analyze
    return run_and_analyze(studies / "slotted_rocker_prp_sweep.toml",
                           tmp_path_factory.mktemp("prp_sweep") / "prp.h5", SWEEP_N)


def test_sweep_over_the_prp_guide_matches_the_scene_path(prp_sweep):
    """The guide's tilt (deg in the study and the file, rad in the plan), its
    height and the pin's offset are design variables: each candidate's peaks
    are those of its own scene."""
    import h5py
    from pipeline.study.sweep_spec import apply_design
    from support.tolerances import SWEEP_VS_SCENE_REL
    study, path = prp_sweep
    with h5py.File(path, "r") as f:
        x = f["candidates/params"][()]
        status = f["candidates/status"][()]
        units = [u.decode() if isinstance(u, bytes) else str(u)
                 for u in np.atleast_1d(f["candidates/params"].attrs["units"])]
        m = {k: f[f"metrics/{k}"][()] for k in ("peak_reaction", "peak_acceleration",
                                                "peak_M_bal")}
    assert (status == kc.OK).all()
    assert np.ptp(x[:, 0]) > 20.0 and np.abs(x[:, 0]).max() <= 20.0   # degrees
    for i in (0, 7, 101):
        mech = apply_design(study.mechanism, study.sweep, x[i])
        prp = next(g for g in mech.groups if isinstance(g, PRP))
        assert (prp.guide2_angle, prp.guide2_offset, prp.guide1_offset) == \
            (x[i, 0] * DEG, x[i, 1], x[i, 2])
        plan = mech.compile()
        crank = mech.crank
        c = solve_curves(plan, revolution_angles(crank, study.sweep.positions), kc.ACCELERATIONS,
                         close_at=crank.phi0 + crank.rot * 2 * math.pi)
        fr = scene_forces(mech, plan, c)
        acc = np.hypot(*c.d2[:, plan.point("P5")].T) * crank.omega1 ** 2 / 1000.0
        for key, want in (("peak_reaction", fr.magnitude.max()),
                          ("peak_M_bal", np.abs(fr.M_bal).max()), ("peak_acceleration", acc.max())):
            assert m[key][i] == pytest.approx(want, rel=SWEEP_VS_SCENE_REL), (i, key)
    assert "deg" in units[0]


def test_pareto_analysis_of_the_prp_sweep(prp_sweep):
    """The fronts of the stored analysis are those of a brute-force dominance
    test over the feasible candidates."""
    from support.sweep_helpers import assert_fronts_are_the_brute_force_rank
    assert_fronts_are_the_brute_force_rank(prp_sweep[1])


# ----------------------------------------------------------------- the force lanes
@pytest.fixture(scope="module")
def prp_problem(studies):
    """The slotted rocker's sweep as shipped (tests/model/test_new_dyads runs it too)."""
    study = load_study(studies / "slotted_rocker_prp_sweep.toml")
    pb = build_problem(study, study.sweep)
    x = np.concatenate([draw_candidates(pb.spec, c) for c in range(2)])
    return pb, np.ascontiguousarray(parameter_rows(pb.plan, pb.spec, x))


def test_the_force_lanes_of_dyads_and_slides_agree_with_the_scalar_force_stage(prp_problem):
    """The slotted rocker (an RRR, a PRP whose slot turns with the rocker, a
    guide of fixed direction, a block that only translates) in the force
    lanes: its groups and its turning slide by their forms without a library
    call (the cosine law without acos, guide directions as link vectors turned
    by hoisted cos/sin), so the scalar force stage's numbers to rounding, not
    its bits."""
    pb, pars = prp_problem
    assert pb.settings()[ks.SET_WANT_PEAKS]
    assert_force_lanes_round(pb, pars, 1500)


def test_the_force_lanes_of_dyads_and_slides_are_vectorized(prp_problem):
    """Packed (SIMD) floating-point instructions in the slotted rocker's force
    lanes (the working point's select over the points, the clamped square root
    of the cosine law)."""
    ops = packed_force_lane_ops(prp_problem[0])
    assert sum(ops.values()) > 300, ops


# a lane the force lanes cannot vouch for, made so in numba's Python mode: every
# other lane's verdict set after the force lanes ran, and the fallbacks counted


def test_prp_lanes_agree_with_the_careful_path(studies):
    """The slotted rocker's PRP in the lanes: its guides from the rocker's link
    vector and the hoisted angles, B where they meet.  Bounds widened so that a
    third of the draws turn the frame's guide parallel to the slot somewhere in
    the revolution: the lanes hand those over, and the careful path finds the
    fold where it finds it alone.  The force stage's peaks (the block's and the
    slider's loads, the slides) hold the lanes' B and its analogs to the careful
    path's; the study's own mechanism and rocker, so its module is this file's."""
    pb, pars = widened_draws(studies, "slotted_rocker_prp_sweep",
                             [("min = -20.0, max = 20.0", "min = -90.0, max = 90.0"),
                              ("min = -5.0, max = 5.0", "min = -30.0, max = 30.0"),
                              ("min = -10.0, max = 10.0", "min = 5.0, max = 30.0")], 2000)
    status = assert_lanes_agree(pb, pars, class3=False)
    assert (status == kc.SINGULAR).sum() > 300
