"""A sweep whose bodies read CAD reports is the study's text AND the reports:
a resume after a report changed would mix two mechanisms' results, so it is
refused (journal and finished file alike), and the same reports resume."""

from __future__ import annotations

import re

import pytest

from pipeline.results.storage import study_digest
from pipeline.base.errors import ResultsError
from pipeline.runs.lifecycle import SweepInterrupted
from pipeline.runs.sweep import run_sweep
from pipeline.study.reader import load_study

N, CHUNK = 300, 100

CRANK = """Mass properties of crank 1-2
Mass = {mass} kilograms

Center of mass: ( millimeters )
\tX = 26.21
\tY = 0
\tZ = 0

Moments of inertia: ( kilograms * square meters )
Taken at the center of mass and aligned with the output coordinate system.
\tLxx = 0.0001\tLxy = 0\tLxz = 0
\tLyx = 0\tLyy = 0.001\tLyz = 0
\tLzx = 0\tLzy = 0\tLzz = 0.001189631
"""


def cad_sweep(studies, folder, mass="0.91"):
    """The main job's study with its crank's mass data from a report."""
    text = (studies / "ov7_synthesis.toml").read_text()
    crank = re.search(r'\[\[mechanism\.bodies\]\]\nname = "crank 1-2"\n.*?(?=\n\[\[)', text,
                      re.S)
    assert crank, "the main job's study names its crank body 'crank 1-2'"
    text = text.replace(crank.group(0), '[[mechanism.bodies]]\nname = "crank 1-2"\n'
                        'joints = ["P1", "P2"]\ncad = { report = "crank.txt", origin = "P1", '
                        'x_axis = ["P1", "P2"] }\n')
    (folder / "crank.txt").write_text(CRANK.format(mass=mass))
    path = folder / "cad_sweep.toml"
    path.write_text(text)
    return path


def test_the_digest_sees_a_changed_report(studies, tmp_path):
    a = study_digest(load_study(cad_sweep(studies, tmp_path)))
    b = study_digest(load_study(cad_sweep(studies, tmp_path, mass="0.95")))
    assert a["study_sha256"] == b["study_sha256"]
    assert a["cad_reports_sha256"] != b["cad_reports_sha256"] != ""
    assert study_digest(load_study(studies / "ov7_synthesis.toml"))["cad_reports_sha256"] == ""


def test_a_resume_after_a_report_changed_is_refused(studies, tmp_path):
    path, out = cad_sweep(studies, tmp_path), tmp_path / "r.h5"
    with pytest.raises(SweepInterrupted):
        run_sweep(load_study(path), out, candidates=N, chunk_size=CHUNK, progress=False,
                  stop_after_chunks=1)
    cad_sweep(studies, tmp_path, mass="0.95")
    with pytest.raises(ResultsError, match="belongs to another run .*cad_reports_sha256"):
        run_sweep(load_study(path), out, progress=False, resume=True)
    cad_sweep(studies, tmp_path)                       # the reports as they were: resumes
    run_sweep(load_study(path), out, progress=False, resume=True)
    cad_sweep(studies, tmp_path, mass="0.95")          # a finished file: another study's
    with pytest.raises(ResultsError, match="holds another study's results"):
        run_sweep(load_study(path), out, progress=False, resume=True)
