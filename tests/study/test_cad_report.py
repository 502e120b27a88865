"""A body's mass data from a CAD report (``cad = { report, origin, x_axis }``):
reports written here from DOMAIN.md's mechanism B mass data (section 5), in
each unit system SolidWorks saves and as the neutral CSV, import to DOMAIN's
numbers; ov7_class3 run from them gives today's reactions; bad reports end in
one line naming the file and the line; a part not symmetric about the plane
is warned of."""

import logging
import math
import re

import h5py
import numpy as np
import pytest

from pipeline.cli import main
from pipeline.solve.scene import run_scene
from pipeline.study.cad_report import read_part, read_parts
from pipeline.study.reader import load_study, stored_study
from pipeline.base.errors import StudyError

# DOMAIN.md section 5, mechanism B: name, joints, base point and link vector (the part's
# origin and x axis), lS mm, US deg, m kg, J_S kg*m^2
MECH_B = [("crank 1-2", ("P1", "P2"), "P1", ("P1", "P2"), 26.21, 0.0, 0.91, 0.001189631),
          ("lead 2-3", ("P2", "P3"), "P2", ("P2", "P3"), 122.54, 0.0, 0.73, 0.008434849),
          ("ternary 3-4-5", ("P3", "P4", "P5"), "P3", ("P3", "P4"), 85.01, 15.13, 0.91,
           0.004456758),
          ("lead 4-6", ("P4", "P6"), "P6", ("P6", "P4"), 40.99, 0.0, 1.64, 0.005376871),
          ("rocker 5-7-8", ("P5", "P7"), "P7", ("P7", "P5"), 125.30, 37.56, 1.07,
           0.012826014)]

POUND = 0.45359237      # kg, exact
INCH = 25.4             # mm, exact
# SolidWorks' words: mass unit, kg per unit, length unit, mm per unit
SYSTEMS = {"g/mm": ("grams", 1e-3, "millimeters", 1.0),
           "kg/m": ("kilograms", 1.0, "meters", 1000.0),
           "lb/in": ("pounds", POUND, "inches", INCH)}
FORMATS = ("g/mm", "kg/m", "lb/in", "csv", "g/mm decimal comma")


def _num(v, comma=False):
    s = repr(float(v))
    return s.replace(".", ",") if comma else s


def solidworks_report(name, lS, US_deg, m, J, system="g/mm", comma=False, Lxz=0.0,
                      mass_line=True, mass_word=None):
    """A report laid out as SolidWorks' Mass Properties dialog saves it, with its
    optional lines and the block at the output coordinate system (whose Izz is
    not J_S: reading the wrong block fails)."""
    mw, mk, lw, lmm = SYSTEMS[system]
    x, y = lS * math.cos(math.radians(US_deg)), lS * math.sin(math.radians(US_deg))
    ik = mk * (lmm / 1000.0) ** 2                       # kg*m^2 per unit of the report
    n = lambda v: _num(v, comma)                        # noqa: E731
    izz = J + m * ((x ** 2 + y ** 2) / 1e6)
    lines = [f"Mass properties of {name}", "     Configuration: Default",
             "     Coordinate system: -- default --", "",
             f"Density = {n(0.00785 / mk * lmm ** 3)} {mw} per cubic {lw}", ""]
    if mass_line:
        lines += [f"Mass = {n(m / mk)} {mass_word or mw}", ""]
    lines += [f"Volume = {n(1.2e5 / lmm ** 3)} cubic {lw}", "",
              f"Surface area = {n(2.2e4 / lmm ** 2)}  square {lw}", "",
              f"Center of mass: ( {lw} )", f"\tX = {n(x / lmm)}", f"\tY = {n(y / lmm)}",
              f"\tZ = {n(4.0 / lmm)}", "",
              f"Principal axes of inertia and principal moments of inertia: ( {mw} *  "
              f"square {lw} )", "Taken at the center of mass.",
              f"\t Ix = ( 1.00,  0.00,  0.00)   \tPx = {n(0.3 * J / ik)}",
              f"\t Iy = ( 0.00,  1.00,  0.00)   \tPy = {n(1.1 * J / ik)}",
              f"\t Iz = ( 0.00,  0.00,  1.00)   \tPz = {n(J / ik)}", "",
              f"Moments of inertia: ( {mw} *  square {lw} )",
              "Taken at the center of mass and aligned with the output coordinate system. "
              "(Using positive tensor notation.)",
              f"\tLxx = {n(0.3 * J / ik)}\tLxy = {n(0.0)}\tLxz = {n(Lxz / ik)}",
              f"\tLyx = {n(0.0)}\tLyy = {n(1.1 * J / ik)}\tLyz = {n(0.0)}",
              f"\tLzx = {n(Lxz / ik)}\tLzy = {n(0.0)}\tLzz = {n(J / ik)}", "",
              f"Moments of inertia: ( {mw} *  square {lw} )",
              "Taken at the output coordinate system. (Using positive tensor notation.)",
              f"\tIxx = {n(0.5 * izz / ik)}\tIxy = {n(0.0)}\tIxz = {n(0.0)}",
              f"\tIyx = {n(0.0)}\tIyy = {n(1.3 * izz / ik)}\tIyz = {n(0.0)}",
              f"\tIzx = {n(0.0)}\tIzy = {n(0.0)}\tIzz = {n(izz / ik)}", ""]
    return "\r\n".join(lines)        # saved on Windows


def csv_row(name, lS, US_deg, m, J):
    x, y = lS * math.cos(math.radians(US_deg)), lS * math.sin(math.radians(US_deg))
    return f"{name},{_num(m * 1000)},g,{_num(x / 10)},{_num(y / 10)},0.4,cm,{_num(J)},kg*m^2"


def write_report(folder, k, fmt):
    """Body k of mechanism B's report in format ``fmt``: its file name."""
    name, _, _, _, lS, US, m, J = MECH_B[k]
    folder.mkdir(exist_ok=True)
    if fmt == "csv":
        f = folder / f"body{k}.csv"
        f.write_text("name,mass,unit,x,y,z,length unit,Lzz,inertia unit\n"
                     + csv_row(name, lS, US, m, J) + "\n")
    else:
        system, comma = fmt.split(" ")[0], fmt.endswith("comma")
        f = folder / f"body{k}.txt"
        f.write_text(solidworks_report(name, lS, US, m, J, system, comma), newline="")
    return f


@pytest.mark.parametrize("fmt", FORMATS)
def test_each_unit_system_imports_domain_mass_data(tmp_path, fmt):
    for k, (name, _, _, _, lS, US, m, J) in enumerate(MECH_B):
        props = read_part(write_report(tmp_path, k, fmt))
        got_lS, got_US = props.link_frame()
        assert props.part == name
        assert props.mass == pytest.approx(m, rel=1e-12, abs=0)
        assert props.J_S == pytest.approx(J, rel=1e-12, abs=0)
        assert got_lS == pytest.approx(lS, rel=1e-12, abs=0)
        assert math.degrees(got_US) == pytest.approx(US, rel=1e-12, abs=1e-13)
        assert props.warning() is None


def cad_study(studies, tmp_path, formats=FORMATS, reports=None):
    """ov7_class3 with every body's mass data from a report (body k in
    formats[k]) in tmp_path/parts; ``reports``: {k: report text} instead."""
    text = (studies / "ov7_class3.toml").read_text()
    start, end = text.index("[[mechanism.bodies]]"), text.index("\n[output]")
    parts = tmp_path / "parts"
    bodies = []
    for k, (name, joints, origin, x_axis, *_) in enumerate(MECH_B):
        if reports and k in reports:
            parts.mkdir(exist_ok=True)
            f = parts / f"body{k}.txt"
            f.write_text(reports[k])
        else:
            f = write_report(parts, k, formats[k % len(formats)])
        j = ", ".join(f'"{p}"' for p in joints)
        bodies.append(f'[[mechanism.bodies]]\nname = "{name}"\njoints = [{j}]\n'
                      f'cad = {{ report = "parts/{f.name}", origin = "{origin}", '
                      f'x_axis = ["{x_axis[0]}", "{x_axis[1]}"] }}\n')
    p = tmp_path / "ov7_cad.toml"
    p.write_text(text[:start] + "\n".join(bodies) + text[end:])
    return p


def test_ov7_class3_from_reports_gives_todays_reactions(studies, tmp_path):
    today = load_study(studies / "ov7_class3.toml")
    cad = load_study(cad_study(studies, tmp_path))
    for b0, b1 in zip(today.mechanism.bodies, cad.mechanism.bodies):
        assert (b1.name, b1.joints, b1.com.base, b1.com.along) == \
               (b0.name, b0.joints, b0.com.base, b0.com.along)
    r0, r1 = run_scene(today), run_scene(cad)
    for c0, c1 in ((r0.table, r1.table), (r0.dense, r1.dense)):
        for a, b in ((c0.forces.R, c1.forces.R), (c0.forces.M_bal, c1.forces.M_bal)):
            scale = np.max(np.abs(a))
            assert scale > 0
            np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12 * scale)


def test_a_results_file_keeps_the_reports(studies, tmp_path):
    """The study a results file keeps re-reads its bodies from the reports'
    copies beside it, not from files that may have moved or changed."""
    study = cad_study(studies, tmp_path)
    out = tmp_path / "cad.h5"
    assert main(["run", str(study), "-o", str(out), "-q", "--no-pictures"]) == 0
    before = load_study(study).mechanism.bodies
    for f in (tmp_path / "parts").iterdir():
        f.write_text("changed")
    with h5py.File(out, "r") as f:
        again = stored_study(f.attrs, out)
    assert again.mechanism.bodies == before


def _one_line_error(capsys, command):
    err = capsys.readouterr().err
    assert err.startswith(f"pipeline {command}: error: ") and err.count("\n") == 1, err
    return err


def _bad_reports(tmp_path):
    """(case, report text, the line it names, words of what it expected)"""
    name, _, _, _, lS, US, m, J = MECH_B[0]
    good = solidworks_report(name, lS, US, m, J).split("\r\n")
    mass_at = next(i for i, s in enumerate(good) if s.startswith("Mass ="))
    return [
        ("no mass line", solidworks_report(name, lS, US, m, J, mass_line=False), None,
         "no mass line: expected 'Mass = <number> grams'"),
        ("unknown unit", solidworks_report(name, lS, US, m, J, mass_word="ounces"),
         mass_at + 1, "mass unit 'ounces' is not one this reader knows: expected grams, "
                      "kilograms or pounds"),
        ("two parts", "\r\n".join(good + good), len(good) + 1,
         "a second part ('Mass properties of crank 1-2'; the first, 'crank 1-2', at line 1)"),
    ]


@pytest.mark.parametrize("case", ["no mass line", "unknown unit", "two parts"])
def test_a_bad_report_is_one_line_through_bodies_and_run(studies, tmp_path, capsys, case):
    _, text, line, expected = next(c for c in _bad_reports(tmp_path) if c[0] == case)
    report = tmp_path / "bad.txt"
    report.write_text(text)
    assert main(["bodies", str(report)]) == 2
    err = _one_line_error(capsys, "bodies")
    assert f"{report}: " + (f"line {line}: " if line else "") + expected in err
    study = cad_study(studies, tmp_path, reports={0: text})
    assert main(["run", str(study), "-o", str(tmp_path / "x.h5"), "-q"]) == 2
    err = _one_line_error(capsys, "run")
    assert f"{tmp_path / 'parts' / 'body0.txt'}: " + (f"line {line}: " if line else "") \
        + expected in err
    assert f"(the report of {study}: mechanism.bodies[0].cad.report)" in err


def test_a_centre_of_mass_far_outside_its_link_is_one_line_through_run(studies, tmp_path,
                                                                        capsys):
    """The crank's report in millimetres' numbers under the word 'inches': its
    centre of mass 666 mm from P1 on a 50 mm crank."""
    name, _, _, _, lS, US, m, J = MECH_B[0]
    text = solidworks_report(name, lS, US, m, J).replace("Center of mass: ( millimeters )",
                                                         "Center of mass: ( inches )")
    line = text.split("\r\n").index("\tX = 26.21") + 1
    study = cad_study(studies, tmp_path, reports={0: text})
    assert main(["run", str(study), "-o", str(tmp_path / "x.h5"), "-q"]) == 2
    err = _one_line_error(capsys, "run")
    assert f"{tmp_path / 'parts' / 'body0.txt'}: line {line}: the centre of mass (x, y) = " \
           "(665.734, 0) mm in the part's frame is 615.734 mm from the link's nearest point " \
           "(P2), farther than the link is long (50 mm)" in err
    assert not (tmp_path / "x.h5").exists()
    # pipeline bodies has no mechanism to place the part on: it prints what it read
    assert main(["bodies", str(tmp_path / "parts" / "body0.txt")]) == 0


def test_reading_a_study_places_no_body_and_each_run_of_it_refuses(studies, tmp_path, capsys):
    """Where a centre of mass lies needs the mechanism solved at phi0: reading the
    study (pipeline.study, below the solver) keeps what the reports say, and the
    run, the API's scene and a tolerance analysis refuse it, in the same line."""
    import pipeline
    name, _, _, _, lS, US, m, J = MECH_B[0]
    text = solidworks_report(name, lS, US, m, J).replace("Center of mass: ( millimeters )",
                                                         "Center of mass: ( inches )")
    study = cad_study(studies, tmp_path, reports={0: text})
    read = load_study(study)
    assert [b[0] for b in read.cad_bodies] == [b[0] for b in MECH_B]
    said = "farther than the link is long (50 mm)"
    with pytest.raises(StudyError, match=re.escape(said)):
        pipeline.solve_scene(read)
    assert main(["tolerance", str(study), "-o", str(tmp_path / "t.h5"), "-q"]) == 2
    assert said in _one_line_error(capsys, "tolerance")
    assert not (tmp_path / "t.h5").exists()


def test_a_part_not_symmetric_about_the_plane_is_warned_of(studies, tmp_path, capsys,
                                                           caplog):
    name, _, _, _, lS, US, m, J = MECH_B[2]
    text = solidworks_report(name, lS, US, m, J, "kg/m", Lxz=0.05 * J)
    report = tmp_path / "ternary.txt"
    report.write_text(text)
    assert read_part(report).product_ratio() == pytest.approx(0.05, rel=1e-12)
    assert main(["bodies", str(report)]) == 0
    out = capsys.readouterr().out
    warning = re.search(r"warning: (.*)", out)[1]
    assert f"part {name!r}" in warning and "Lxz, Lyz are 5% of Lzz" in warning
    study = cad_study(studies, tmp_path, reports={2: text})
    with caplog.at_level(logging.WARNING):
        load_study(study)
    said = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(said) == 1 and f"part {name!r}" in said[0] and "5% of Lzz" in said[0]
    # symmetric (a CAD's rounding of Lxz: 1e-6 of Lzz): no warning
    report.write_text(solidworks_report(name, lS, US, m, J, "kg/m", Lxz=1e-6 * J))
    assert read_part(report).warning() is None


def test_bodies_prints_what_it_read_in_the_studys_units(tmp_path, capsys):
    name, _, _, _, lS, US, m, J = MECH_B[4]
    report = write_report(tmp_path, 4, "lb/in")
    assert main(["bodies", str(report), "--format", "json"]) == 0
    import json
    (info,) = json.loads(capsys.readouterr().out)
    assert info["part"] == name and info["units read"] == \
        "pounds, inches, pounds * square inches"
    assert info["m"] == f"{m:.10g} kg" and info["J_S"].startswith(f"{J:.10g} kg*m^2")
    x, y = lS * math.cos(math.radians(US)), lS * math.sin(math.radians(US))
    assert info["centre of mass"].startswith(f"x = {x:.10g} mm, y = {y:.10g} mm")
    assert "warning" not in info


def test_csv_of_several_parts_semicolons_and_decimal_commas(studies, tmp_path):
    rows = [csv_row(*b[:1], *b[4:]).replace(",", ";") for b in MECH_B]
    rows = [";".join(f.replace(".", ",") for f in r.split(";")) for r in rows]
    f = tmp_path / "parts" / "all.csv"
    f.parent.mkdir()
    f.write_text("# exported by some CAD\n" + "\n".join(rows) + "\n")
    parts = read_parts(f)
    assert [p.part for p in parts] == [b[0] for b in MECH_B]
    for p, (_, _, _, _, lS, US, m, J) in zip(parts, MECH_B):
        assert p.mass == pytest.approx(m, rel=1e-12) and p.J_S == pytest.approx(J, rel=1e-12)
        assert p.link_frame()[0] == pytest.approx(lS, rel=1e-12)
    with pytest.raises(StudyError, match=r"all\.csv: line 3: a second part \(5 parts: "
                                         r"'crank 1-2', .*name the part to read \(cad.part\)"):
        read_part(f)
    assert read_part(f, "lead 4-6").mass == pytest.approx(1.64, rel=1e-12)
    # a study picks its row with cad.part
    text = (studies / "ov7_class3.toml").read_text()
    text = text.replace('mass = 0.73\nJ_S = 0.008434849\n'
                        'com = { base = "P2", along = ["P2", "P3"], lS = 122.54, US = 0.0 }',
                        'cad = { report = "parts/all.csv", part = "lead 2-3", origin = "P2", '
                        'x_axis = ["P2", "P3"] }')
    (tmp_path / "one.toml").write_text(text)
    body = load_study(tmp_path / "one.toml").mechanism.bodies[1]
    assert body.mass == pytest.approx(0.73, rel=1e-12)
    assert body.com.lS == pytest.approx(122.54, rel=1e-12) and body.com.US == 0.0


def test_cad_and_numbers_together_are_refused(studies, tmp_path):
    study = cad_study(studies, tmp_path)
    text = study.read_text().replace('name = "lead 2-3"\n', 'name = "lead 2-3"\nmass = 0.73\n')
    study.write_text(text)
    with pytest.raises(StudyError, match=r"mechanism\.bodies\[1\]\.mass: a body takes its mass "
                                         r"data from cad = \{ report = \.\.\. \} or from mass"):
        load_study(study)
