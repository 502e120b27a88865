"""[cycle], the machine's cyclogram (issue 29 item 6): the OV-7's organs as the
studies declare them, and declaration errors in one line naming the file, the
field and the reason (phases that leave a gap, overlap or do not make one turn,
a misspelt key, an output organ that is not there or not shaped like the
design's phases)."""

from pathlib import Path

import pytest

from pipeline.study.reader import load_study
from pipeline.base.errors import StudyError

STUDIES = Path(__file__).resolve().parents[2] / "studies"
BASE = (STUDIES / "ov7_base.toml").read_text()
LAW = """
[output.motion_law]
phases = [{ from = 240, to = 30, law = "dwell" },
          { from = 30, to = 130, law = "cycloidal", level = 1 },
          { from = 130, to = 240, law = "cycloidal", level = 0 }]
"""

# DOMAIN.md section 9: the needle, sinker and presser phases "for the record"
OV7 = {"eyelet": [("dwell", 240, 30), ("forward", 30, 130), ("back", 130, 240)],
       "needle": [("rise", 0, 100), ("dwell", 100, 160), ("rise", 160, 200), ("fall", 200, 360)],
       "sinker": [("move", 0, 20), ("move", 20, 70), ("dwell", 70, 190), ("move", 190, 220),
                  ("move", 220, 310), ("move", 310, 360)],
       "presser": [("move", 0, 50), ("dwell", 50, 180), ("move", 180, 290),
                   ("move", 290, 360)]}


@pytest.mark.parametrize("name", ["ov7_base", "ov7_class3"])
def test_the_ov7_studies_declare_the_thesis_cyclogram(name):
    cyc = load_study(STUDIES / f"{name}.toml").cycle
    assert cyc.output == "eyelet" and cyc.align == "best"
    got = {o.name: [(p.kind, p.start, (p.start + p.length) % 360 or 360) for p in o.phases]
           for o in cyc.organs}
    want = {k: [(kd, a % 360, b % 360 or 360) for kd, a, b in v] for k, v in OV7.items()}
    assert got == want
    for o in cyc.organs:     # each covers the turn once
        assert sum(p.length for p in o.phases) == pytest.approx(360.0)


def _twice_round(text):
    return text.replace('{ from = 200, to = 360, kind = "fall" }]',
                        '{ from = 200, to = 360, kind = "fall" }, { from = 0, to = 100, kind = '
                        '"rise" }, { from = 100, to = 0, kind = "fall" }]')


CASES = [
    # (edit of ov7_base.toml, field named, reason fragment)
    (lambda t: t.replace('{ from = 100, to = 160, kind = "dwell" }',
                         '{ from = 105, to = 160, kind = "dwell" }'),
     "cycle.organs[1].phases[1].from", "the one before ends at 100 (a gap of 5 deg)"),
    (lambda t: t.replace('{ from = 160, to = 200, kind = "rise" }',
                         '{ from = 150, to = 200, kind = "rise" }'),
     "cycle.organs[1].phases[2].from", "(an overlap of 10 deg)"),
    (_twice_round, "cycle.organs[1].phases", "span 720 deg; they must cover the turn exactly once"),
    (lambda t: t.replace('name = "needle"', 'nmae = "needle"'), "cycle.organs[1].name",
     "('nmae' is given: a misspelling of 'name'?)"),
    (lambda t: t.replace('{ from = 0, to = 20, kind = "move" }',
                         '{ from = 0, to = 20, knid = "move" }'),
     "cycle.organs[2].phases[0].kind", "a misspelling of 'kind'?"),
    (lambda t: t.replace('output = "eyelet"', 'output = "eyelet"\nalgin = "fixed"'),
     "cycle.algin", "unknown key 'algin'; did you mean 'align'?"),
    (lambda t: t.replace('output = "eyelet"', 'output = "eyelets"'), "cycle.output",
     "no organ named 'eyelets'; did you mean 'eyelet'?"),
    (lambda t: t.replace('{ from = 130, to = 240, kind = "back" }',
                         '{ from = 130, to = 240, kind = "fall" }'), "cycle.output",
     "give it one each of dwell, forward, back, in that order"),
    (lambda t: t.replace('kind = "fall"', 'kind = "drop"'), "cycle.organs[1].phases[3].kind",
     "must be one of dwell, move, rise, fall, forward, back"),
    (lambda t: t.replace('name = "sinker"', 'name = "needle"'), "cycle.organs[2].name",
     "organ 'needle' is declared twice (first at cycle.organs[1].name)"),
]


@pytest.mark.parametrize("edit,field,reason", CASES, ids=[c[1] + f"-{i}"
                                                           for i, c in enumerate(CASES)])
def test_a_wrong_cycle_is_refused_in_one_line(tmp_path, edit, field, reason):
    text = edit(BASE)
    assert text != BASE
    path = tmp_path / "bad_cycle.toml"
    path.write_text(text)
    with pytest.raises(StudyError) as e:
        load_study(path)
    msg = str(e.value)
    assert "\n" not in msg and str(path) in msg and field in msg and reason in msg, msg


def test_the_declared_organ_is_the_cyclogram_s_even_with_a_motion_law():
    """A motion law is what the rocker must follow; the eyelet's phases of [cycle]
    stay the cyclogram's, placed by [cycle]."""
    from pipeline.solve.cyclogram import required_rings
    from pipeline.study.reader import parse_study
    law = LAW.replace("from = 240, to = 30", "from = 250, to = 30").replace(
        "from = 130, to = 240", "from = 130, to = 250")
    rings, turn, align = required_rings(parse_study(BASE + law, "law.toml"))
    assert rings[0].organ == "eyelet" and rings[0].phases[0] == ("dwell", 240.0, 390.0)
    assert turn is None and align == "best"


def test_the_motion_law_can_give_the_output_organs_phases(tmp_path):
    """Without the eyelet declared, [output.motion_law]'s phases are its ring; the
    law places the cycle, so [cycle] takes no align or phase of its own."""
    from pipeline.solve.cyclogram import required_rings
    start = BASE.index("[[cycle.organs]]\nname = \"eyelet\"")
    end = BASE.index("[[cycle.organs]]\nname = \"needle\"")
    text = BASE[:start] + BASE[end:] + LAW
    path = tmp_path / "law.toml"
    path.write_text(text)
    rings, turn, align = required_rings(load_study(path))
    assert [r.organ for r in rings] == ["eyelet", "needle", "sinker", "presser"]
    assert rings[0].output and [p[0] for p in rings[0].phases] == [
        "dwell", "forward (cycloidal)", "back (cycloidal)"]
    assert turn is None and align == "best"
    path.write_text(text.replace('output = "eyelet"', 'output = "eyelet"\nphase = 10'))
    with pytest.raises(StudyError, match=r"cycle\.phase: \[output\.motion_law\] places the cycle"):
        load_study(path)
