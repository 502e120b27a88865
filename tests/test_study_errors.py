"""Declaration errors stop with a message naming the file, the field and the reason."""

import pytest

from pipeline.study import StudyError, load_study, parse_study

BASE = (__import__("pathlib").Path(__file__).resolve().parent.parent / "studies"
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
    (("length = 14.9", "length = 14.9\nlenght = 3"), "mechanism.crank.lenght", "unknown key"),
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
