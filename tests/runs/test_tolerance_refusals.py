"""`pipeline tolerance` refuses, in one line naming the file and the field,
what it cannot analyse (issue 58, case 7): a scene results file without its
stored study, a design that does not assemble (never a yield of 0 % with
every line NaN)."""

from __future__ import annotations

import h5py
import pytest

from pipeline.cli import main

from conftest import STUDIES


def fourbar_text(crank=15.0):
    """The four-bar of studies/warp_feed_fourbar.toml with its rocker DC
    declared, its crank ``crank`` mm long (45 mm: it cannot pass phi1 = 180 deg)."""
    text = (STUDIES / "warp_feed_fourbar.toml").read_text()
    text = text.replace('working_point = "P5"', 'working_point = "P5"\nrocker = ["P4", "P3"]')
    old = "length = 15.0              # AB"
    assert old in text
    return text.replace(old, f"length = {crank}              # AB")


def error_line(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in err[0], err
    return err[0]


def test_a_scene_file_without_its_stored_study_is_one_line(tmp_path, capsys):
    study = tmp_path / "fourbar.toml"
    study.write_text(fourbar_text())
    scene = tmp_path / "scene.h5"
    assert main(["run", str(study), "-o", str(scene), "--no-pictures", "-q"]) == 0
    with h5py.File(scene, "a") as f:
        del f.attrs["study_toml"]
    capsys.readouterr()
    assert main(["tolerance", str(scene), "-o", str(tmp_path / "t.h5"), "--samples", "16",
                 "--no-pictures"]) == 2
    line = error_line(capsys)
    assert str(scene) in line and "study_toml" in line and "no stored study" in line
    assert not (tmp_path / "t.h5").exists()


def test_a_design_that_does_not_assemble_is_refused_with_where_it_fails(tmp_path, capsys):
    study = tmp_path / "long_crank.toml"
    study.write_text(fourbar_text(crank=45.0))
    out = tmp_path / "t.h5"
    assert main(["tolerance", str(study), "-o", str(out), "--samples", "16",
                 "--no-pictures"]) == 2
    line = error_line(capsys)
    assert line.startswith(f"pipeline tolerance: error: {study}: ")
    assert "does not assemble" in line and "phi1 = " in line and "RRR[1]" in line
    assert "nan" not in line.lower() and not out.exists()


@pytest.mark.parametrize("crank", [15.0])
def test_a_design_that_assembles_is_analysed(tmp_path, crank, capsys):
    """The refusal is the failing design's alone."""
    study = tmp_path / "fourbar.toml"
    study.write_text(fourbar_text(crank))
    out = tmp_path / "t.h5"
    assert main(["tolerance", str(study), "-o", str(out), "--samples", "16", "-q",
                 "--no-pictures"]) == 0
    assert out.exists()
