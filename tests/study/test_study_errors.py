"""Declaration errors stop with a message naming the file, the field and the reason."""

import math

import numpy as np
import pytest

from pipeline.study.reader import load_study, parse_study
from pipeline.base.errors import StudyError

BASE = (__import__("pathlib").Path(__file__).resolve().parents[2] / "studies"
        / "ov7_base.toml").read_text()


def broken(old, new, count=1):
    assert old in BASE, old
    return BASE.replace(old, new, count)


CASES = [
    # (change, field expected in the message, reason fragment)
    (('A = "P3"', 'A = "P33"'), "mechanism.groups[1].A", "unknown point 'P33'"),
    (('A = "P5"', 'A = "P9"'), "mechanism.groups[2].A", "solved later"),
    (("L_AB = 105.0", "L_AB = -105.0"), "mechanism.groups[0].L_AB", "must be positive"),
    (("L_AB = 105.0", "L_AB = 0"), "mechanism.groups[0].L_AB", "must be positive"),
    (("L_AB = 105.0", "L_AB = nan"), "mechanism.groups[0].L_AB", "must be finite"),
    (("L_AB = 105.0", "L_AB = inf"), "mechanism.groups[0].L_AB", "must be finite"),
    (("L_AB = 105.0", 'L_AB = "105"'), "mechanism.groups[0].L_AB", "expected a number"),
    (('B = "P5"', 'B = "P3"'), "mechanism.groups[1].B", "defined twice"),
    (("W = -1", "W = 2"), "mechanism.groups[0].W", "must be one of -1, 1"),
    (("W = -1", "Wmode = -1"), "mechanism.groups[0]", "W"),
    (("length = 14.9", "length = 14.9\nlenght = 3"), "mechanism.crank.lenght",
     "unknown key 'lenght'; did you mean 'length'?"),
    (("length = 14.9", "lenght = 14.9"), "mechanism.crank.length",
     "required field is missing ('lenght' is given: a misspelling of 'length'?)"),
    (('type = "RRR"', 'type = "RRRR"'), "mechanism.groups[0].type", "must be one of"),
    (('pivot = "P1"', 'pivot = "P2"'), "mechanism.crank.pivot", "must be a fixed point"),
    (("P4 = [26.0, 98.7]", "P4 = [26.0]"), "mechanism.fixed.P4", "expected 2 numbers"),
    (('kind = "scene"', 'kind = "movie"'), "study.kind", "must be one of"),
    (('links = ["2_3"', 'links = ["2_33"'), "output.links", "unknown point 'P33'"),
    (("table_positions = 12", "table_positions = 1"), "output.table_positions", "at least 2"),
    (('working_point = "P9"', 'working_point = "P99"'), "output.working_point", "unknown point"),
    (('analysis = "accelerations"', 'analysis = "forces"'), "output.analysis", "mass data"),
]


@pytest.mark.parametrize("change,field,reason", CASES, ids=[c[1] for c in CASES])
def test_declaration_error_names_file_field_reason(tmp_path, change, field, reason):
    path = tmp_path / "bad_study.toml"
    path.write_text(broken(*change))
    with pytest.raises(StudyError) as e:
        load_study(path)
    msg = str(e.value)
    assert str(path) in msg and field in msg and reason in msg, msg


def test_duplicate_group_names_and_bad_toml(tmp_path):
    with pytest.raises(StudyError, match="not valid TOML"):
        parse_study("[study\nkind=", "x.toml")
    text = BASE.replace('type = "RRR"', 'type = "RRR"\nname = "dyad"', 2)
    with pytest.raises(StudyError, match=r"groups\[1\].name: group name 'dyad' is used twice"):
        parse_study(text, "x.toml")


def test_missing_file_is_named(tmp_path):
    with pytest.raises(StudyError, match="nope.toml: file not found"):
        load_study(tmp_path / "nope.toml")


def test_impossible_ternary_triangle_is_a_declaration_error(studies):
    text = (studies / "ov7_class3.toml").read_text().replace("L45 = 104.5", "L45 = 300.0")
    with pytest.raises(StudyError, match=r"groups\[0\].L45: the ternary link 3-4-5 is not a triangle"):
        parse_study(text, "b.toml")


def test_load_expression_error_names_field(studies):
    text = (studies / "warp_feed_fourbar.toml").read_text().replace(
        'fy = "-150*(1 + 0.2*sin(2*phi))"', 'fy = "-150*(1 + 0.2*sin(2*x))"')
    with pytest.raises(ValueError) as e:
        parse_study(text, "d.toml")
    assert "d.toml" in str(e.value) and "loads[0].fy" in str(e.value) and "'x'" in str(e.value)


# ------------------------------------------------------------------ slides against the guides
SLIDE_CASES = [
    # (study, change, field expected in the message, reason fragment)
    ("slotted_rocker_prp", ('along = ["P4", "P3"]\nangle = 0.0',
                            'along = ["P4", "P3"]\nangle = 30.0'),
     "mechanism.slides[0].angle", "the PRP group 'slider' guides P5 on guide 1 along P4->P3 + 0 "
     "deg; this slide says along P4->P3 + 30 deg"),
    ("slotted_rocker_prp", ('guide = "ground"\nangle = 0.0', 'guide = "ground"\nangle = 30.0'),
     "mechanism.slides[1].angle", "guides P5 on guide 2 at 0 deg (absolute); this slide says "
     "30 deg"),
    ("slotted_rocker_prp", ('along = ["P4", "P3"]\nangle = 0.0',
                            'along = ["P2", "P3"]\nangle = 0.0'),
     "mechanism.slides[0].along", "follows P2->P3, a link of neither the slider 'block' nor its "
     "guide 'rocker DC'"),
    ("slotted_rocker_prp", ('along = ["P4", "P3"]\nangle = 0.0', 'angle = 0.0'),
     "mechanism.slides[0].along", "turning with its body 'rocker DC'; this slide gives the fixed "
     "direction 0 deg"),
    ("scotch_yoke_rpp", ('guide = "yoke"\nangle = 90.0', 'guide = "yoke"\nangle = 0.0'),
     "mechanism.slides[0].angle", "the RPP group 'yoke' guides P2 along its slot, 90 deg from its "
     "guide at 0 deg (absolute); this slide says 0 deg"),
    ("scotch_yoke_rpp", ('guide = "ground"\nangle = 0.0', 'guide = "ground"\nangle = 10.0'),
     "mechanism.slides[1].angle", "guides P3 at 0 deg (absolute); this slide says 10 deg"),
    ("takeup_dynamics", ('guide = "ground"\nangle = 90.0', 'guide = "ground"\nangle = 0.0'),
     "mechanism.slides[0].angle", "the RRP group 'needle bar' guides P3 at 90 deg (absolute)"),
    ("takeup_dynamics", ('along = ["P5", "P4"]\nangle = 0.0', 'along = ["P5", "P4"]\nangle = 5.0'),
     "mechanism.slides[1].angle", "the RPR group 'coulisse' guides P4 along P5->P6"),
    # the take-up eye P7 is attached along P5->P6: P7->P5 is the guide turned 180 deg
    ("takeup_dynamics", ('along = ["P5", "P4"]\nangle = 0.0', 'along = ["P7", "P5"]\nangle = 1.0'),
     "mechanism.slides[1].angle", "lines 1 deg apart"),
]


@pytest.mark.parametrize("name,change,field,reason", SLIDE_CASES,
                         ids=[f"{c[0]}-{c[2]}-{c[1][1][-12:]}" for c in SLIDE_CASES])
def test_a_slide_against_its_groups_guide_is_an_error(studies, tmp_path, name, change, field,
                                                      reason):
    text = (studies / f"{name}.toml").read_text()
    assert change[0] in text
    path = tmp_path / "bad_slide.toml"
    path.write_text(text.replace(*change, 1))
    with pytest.raises(StudyError) as e:
        load_study(path)
    msg = str(e.value)
    assert str(path) in msg and field in msg and reason in msg, msg


SLIDE_AGREES = [
    # the same line modulo 180 deg, written another way
    ("slotted_rocker_prp", [('along = ["P4", "P3"]\nangle = 0.0',
                             'along = ["P3", "P4"]\nangle = 0.0')]),
    ("slotted_rocker_prp", [('along = ["P4", "P3"]\nangle = 0.0',
                             'along = ["P4", "P3"]\nangle = 180.0')]),
    ("slotted_rocker_prp", [('guide = "ground"\nangle = 0.0', 'guide = "ground"\nangle = -180.0')]),
    # a link of two fixed points is a fixed direction
    ("slotted_rocker_prp", [('guide = "ground"\nangle = 0.0',
                             'guide = "ground"\nalong = ["P1", "P4"]')]),
    # the coulisse's guide end, or the eye attached along it, instead of the block
    ("takeup_dynamics", [('along = ["P5", "P4"]\nangle = 0.0',
                          'along = ["P5", "P6"]\nangle = 0.0')]),
    ("takeup_dynamics", [('along = ["P5", "P4"]\nangle = 0.0',
                          'along = ["P7", "P5"]\nangle = 0.0')]),
    # both PRP guides fixed (60 and 0 deg): the slider on the ground carries the
    # sliding point of both, so which one it is cannot be told: not judged
    ("slotted_rocker_prp", [('guide1_link = ["P4", "P3"]\nguide1_angle = 0.0',
                             'guide1_angle = 60.0'),
                            ('guide = "ground"\nangle = 0.0', 'guide = "ground"\nangle = 30.0')]),
]


def _slide_directions(study, pos, plan):
    """Each slide's direction (rad), from the README's rule: ``angle``, absolute
    or relative to the link ``along``, at the positions ``pos`` (points named as
    in ``plan``)."""
    out = []
    for s in study.mechanism.slides:
        a = s.angle
        if s.along is not None:
            pa, pb = (pos[plan.point(n)] for n in s.along)
            a += math.atan2(pb[1] - pa[1], pb[0] - pa[0])
        out.append(a)
    return out


def _same_line(a, b):
    return abs(math.remainder(a - b, math.pi)) < 1e-12


@pytest.mark.parametrize("name,changes", SLIDE_AGREES)
def test_slides_that_agree_or_cannot_be_judged_load(studies, name, changes):
    """Each variant loads; one written another way runs along the same line as
    the shipped study's slides at every crank angle tried; the two fixed PRP
    guides give the ground slide the absolute 30 deg written."""
    text = (studies / f"{name}.toml").read_text()
    for old, new in changes:
        assert old in text
        text = text.replace(old, new, 1)
    from pipeline.kernels import config as kc
    from pipeline.solve.scene import solve_curves
    variant = parse_study(text, "ok.toml")
    shipped = load_study(studies / f"{name}.toml")
    assert len(variant.mechanism.slides) == len(shipped.mechanism.slides)
    # the shipped mechanism's positions (a slide moves no point; the variants'
    # kernels need not be compiled for this)
    plan = shipped.mechanism.compile()
    curves = solve_curves(plan, np.array([0.3, 1.7, 4.0]), kc.POSITIONS)
    for k, phi in enumerate(curves.phi):
        got = _slide_directions(variant, curves.pos[k], plan)
        want = _slide_directions(shipped, curves.pos[k], plan)
        if len(changes) == 1:
            assert all(_same_line(g, w) for g, w in zip(got, want)), (phi, got, want)
        else:
            ground = [i for i, s in enumerate(variant.mechanism.slides) if s.guide is None]
            assert ground and all(_same_line(got[i], math.radians(30.0)) for i in ground)


def test_every_shipped_study_loads(studies):
    """Every study file loads, as the kind it says, and the guide's table of
    studies (docs/guide/studies.md) names exactly the files shipped."""
    import re
    page = (studies.parent / "docs" / "guide" / "studies.md").read_text()
    table = page.split("Studies (`studies/*.toml`):", 1)[1].split("\n\n", 2)[1]
    listed = set(re.findall(r"^\| `([\w.]+\.toml)` \|", table, re.M))
    paths = sorted(studies.glob("*.toml"))
    assert {p.name for p in paths} == listed
    for path in paths:
        s = load_study(path)
        kind = re.search(r'^kind = "(\w+)"', path.read_text(), re.M).group(1)
        assert s.path == path and s.kind == kind
        assert (s.sweep is not None) == (kind == "sweep"), path.name


# ------------------------------------------------------------------ plausible ranges
# (study, change, field, reason fragment): an absurd finite number is refused where it
# is read, naming the field and the range (pipeline.limits)
RANGE_CASES = [
    ("feed_fivebar", ("ratio = 1,", "ratio = 1e300,"), "groups[0].law.ratio",
     "a gear ratio is -100 to 100"),
    ("slotted_rocker_prp", ("guide2_offset = 0.0", "guide2_offset = 1e300"),
     "groups[1].guide2_offset", "is -10,000 to 10,000 mm"),
    ("scotch_yoke_rpp", ("slot_offset = 0.0", "slot_offset = 1e300"), "groups[0].slot_offset",
     "is -10,000 to 10,000 mm"),
    ("warp_feed_fourbar", ("phiM0 = 0.0", "phiM0 = 1e300"), "crank.phiM0",
     "an angle is -3,600 to 3,600 deg"),
    ("ov7_base", ("L_AB = 105.0", "L_AB = 1e-300"), "groups[0].L_AB",
     "a length is 0.001 to 10,000 mm"),
    ("ov7_base", ("L_AB = 105.0", "L_AB = 2e4"), "groups[0].L_AB", "a length is"),
    ("ov7_base", ("P4 = [26.0, 98.7]", "P4 = [26.0, -1e9]"), "fixed.P4", "number 2: -1e+09 mm"),
    ("warp_feed_fourbar", ("eps1 = 0.0", "eps1 = 1e9"), "crank.eps1", "rad/s²"),
    ("takeup_dynamics", ("omega1 = 125.0", "omega1 = 1e6"), "crank.omega1",
     "an angular speed is -10,000 to 10,000 rad/s"),
    ("takeup_dynamics", ("mass = 0.200", "mass = 1e9"), "bodies[0].mass", "a mass is more than 0"),
    ("takeup_dynamics", ("J_S = 325e-6", "J_S = 1e300"), "bodies[0].J_S", "a moment of inertia"),
    ("takeup_dynamics", ("phi_start = 269.18", "phi_start = 1e300"), "cases[0].phi_start",
     "an angle"),
    ("takeup_dynamics", ("damping = 2e-4 ", "damping = 1e300 "), "cases[0].damping",
     "a damping coefficient"),
    ("takeup_dynamics", ("t_end = 10.0 ", "t_end = 1e300 "), "cases[0].t_end", "a duration"),
    ("takeup_dynamics", ("dt = 1e-4 ", "dt = 1e-11 "), "cases[0].t_end",
     "integration steps; at most 100,000,000"),
    ("cam_rocker_input", ("travel = 40.0", "travel = 1e300"), "groups[0].law.travel",
     "an angle"),
    ("actuator_slider_input", ("24.0, 24.0, 24.0", "24.0, 1e300, 24.0"), "groups[0].law.values",
     "number 7: 1e+300 mm is out of range"),
    ("ov7_synthesis", ('P6x = { param = "P6.x" }', 'P6x = { param = "P6.x", min = -1e9, max = 0 }'),
     "sweep.variables.P6x.min", "P6.x: -1e+09 mm is out of range"),
    ("ov7_synthesis", ('P6x = { param = "P6.x" }',
                       'P6x = { param = "P6.x", min = 0, max = 1e300 }'),
     "sweep.variables.P6x.max", "out of range"),
]


@pytest.mark.parametrize("name,change,field,reason", RANGE_CASES,
                         ids=[f"{c[0]}:{c[2]}:{c[1][1][-8:]}" for c in RANGE_CASES])
def test_an_absurd_number_is_refused_naming_the_field_and_the_range(studies, name, change,
                                                                     field, reason):
    text = (studies / f"{name}.toml").read_text()
    assert change[0] in text, change[0]
    with pytest.raises(StudyError) as e:
        parse_study(text.replace(change[0], change[1], 1), "r.toml")
    msg = str(e.value)
    assert field in msg and reason in msg and len(msg.splitlines()) == 1, msg


def test_a_huge_table_law_and_a_huge_study_file_are_refused(studies, tmp_path):
    text = (studies / "actuator_slider_input.toml").read_text()
    old = text[text.index("cycle = ["):text.index("] }", text.index("cycle = ["))]
    n = 10_001
    cycle = ", ".join(f"{360.0 * k / n:.6f}" for k in range(n))
    values = ", ".join("0.0" for _ in range(n))
    with pytest.raises(StudyError, match=r"law.cycle: a table law has at most 10,000 points "
                                         r".*got 10,001"):
        parse_study(text.replace(old, f"cycle = [{cycle}], values = [{values}"), "t.toml")
    big = tmp_path / "big.toml"
    big.write_text(text + "#" * 1_000_001 + "\n")
    with pytest.raises(StudyError, match=r"big.toml: a study file is at most 1,000,000 bytes"):
        load_study(big)
    # a results file's stored copy is held to the same bound
    with pytest.raises(StudyError, match="at most 1,000,000 bytes"):
        parse_study(text + "#" * 1_000_001, "stored")


def test_a_results_file_given_as_a_study_says_so(tmp_path, capsys):
    import h5py

    from pipeline.cli import main
    path = tmp_path / "x.h5"
    with h5py.File(path, "w") as f:
        f.attrs["kind"] = "scene"
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "is an HDF5 file (a results file?)" in err, err
