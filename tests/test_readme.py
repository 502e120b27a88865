"""The README's commands, in order, as written, on a copy of the checkout's
studies: the set-up's main job first, then every command of "The first hour"
(test-sized: tests/support/shell_blocks.py).  The guide's commands:
tests/test_guide.py."""

import re

from pipeline.cli import main
from support.shell_blocks import (MAIN_JOB, README, SMALL, copy_studies, python_blocks,
                                  run_commands, runs_in_ci, shell_blocks, unfenced_commands)

MAX_LINES = 200                 # issue 55: what it is, set-up, the first hour, where to read on


def readme_commands():
    return [c for block in shell_blocks(README.read_text()) for c in block]


def test_the_readme_is_a_first_hour():
    """At most 200 lines; its two set-up commands, the main job's and the tests' (the
    one .ci/run runs); every command it shows in an sh block, where its test sees it."""
    text = README.read_text()
    assert len(text.splitlines()) <= MAX_LINES, len(text.splitlines())
    setup = shell_blocks(text.split("## Set-up", 1)[1].split("\n## ", 1)[0])
    assert setup == [[f"pip install -e . && {MAIN_JOB}"],
                     ['pip install --no-compile -e ".[test]" && python -m pytest -q']]
    assert runs_in_ci(setup[1][0])
    assert not unfenced_commands(text)


def test_readme_commands_run_in_order(tmp_path, monkeypatch, capsys):
    """Every command succeeds, then the Python it shows, and what they write holds: the
    main job's file, the scene's tables (the crank tip of DOMAIN.md section 5 and
    naive.py's eyelet), the report, and the knee exported as a study of its own and run."""
    import h5py
    import numpy as np
    import pandas as pd

    from support import naive
    copy_studies(tmp_path)
    monkeypatch.chdir(tmp_path)
    commands = readme_commands()
    assert commands[0] == f"pip install -e . && {MAIN_JOB}"
    run_commands(commands, monkeypatch, capsys)
    for code in python_blocks(README.read_text()):      # from Python, on the same files
        exec(compile(code, str(README), "exec"), {})
    results = tmp_path / "results"
    with h5py.File(results / "ov7_synthesis.h5", "r") as f:
        assert f.attrs["complete"] and f["candidates/status"].shape == (int(SMALL),)
    import pipeline
    assert "points" in pipeline.open(results / "knee.h5")      # the knee, run as a scene
    # the scene's tables: the crank tip P2 = 50 e(phi1 + 173 deg), the eyelet P8 by naive.py
    pts = pd.read_csv(tmp_path / "tables" / "points.csv")
    phi = np.radians(pts["phi1 [deg]"].to_numpy())
    np.testing.assert_allclose(pts["P2_x [mm]"], 50.0 * np.cos(phi + np.radians(173.0)),
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(pts["P2_y [mm]"], 50.0 * np.sin(phi + np.radians(173.0)),
                               rtol=0, atol=1e-9)
    for k in (0, 90, 200):
        p8 = naive.mech_b_positions(phi[k])[0]["P8"]
        np.testing.assert_allclose(pts.loc[k, ["P8_x [mm]", "P8_y [mm]"]].to_numpy(float), p8,
                                   rtol=0, atol=1e-9)
    assert (tmp_path / "tables" / "candidates_feasible.csv").exists()
    assert list((tmp_path / "cad").glob("ov7_synthesis_candidate*.dxf"))
    page = (tmp_path / "report.html").read_text()
    assert page.startswith("<!DOCTYPE html>") and "knee" in page


def test_a_finished_sweep_says_what_comes_next(tmp_path, capsys, studies):
    out = tmp_path / "s.h5"
    assert main(["run", str(studies / "ov7_synthesis.toml"), "--candidates", "500", "-o",
                 str(out)]) == 0
    text = capsys.readouterr().out
    assert f"pipeline analyze {out}" in text and f"pipeline report {out}" in text
    # every figure with its unit (dimensionless ones without a stray "1")
    best = [ln for ln in text.splitlines() if "best peak_reaction" in ln]
    assert best and best[0].rstrip().endswith(" N"), best
    assert not re.search(r"best dwell_error: \S+ 1$", text, re.M)
    ref = [ln for ln in text.splitlines() if "reference design" in ln][0]
    assert "peak_reaction" in ref and ref.rstrip().endswith(" N")


def test_dynamics_summary_is_a_table_with_units(tmp_path, capsys, studies):
    assert main(["run", str(studies / "takeup_dynamics.toml"), "-o", str(tmp_path / "t.h5"),
                 "--no-pictures"]) == 0
    lines = capsys.readouterr().out.splitlines()
    row = {ln.split(":", 1)[0].strip(): ln.split(":", 1)[1].strip() for ln in lines if ":" in ln}
    assert row["runup omega_mean"].endswith(" rad/s") and row["runup rpm"].endswith(" 1/min")
    assert row["free period_s"].endswith(" s") and row["free amplitude_deg"].endswith(" deg")
    assert not any("{" in ln for ln in lines)


def test_a_first_run_says_it_is_compiling(tmp_path, studies, monkeypatch, caplog):
    """A run whose kernels take more than a second to be ready says so while it
    waits, and reports the compile time apart from the wall time.  No clock is
    trusted: the preparation waits for the notice itself, and the sweep's clock
    is moved 1000 s on while it prepares, so the compile time must hold those
    1000 s and the wall time none of them."""
    import logging
    import threading
    import time
    import types

    import pipeline.compiler.notice as pr
    import pipeline.runs.sweep as sw
    real = sw.SweepFile.create
    noticed = threading.Event()
    offset = [0.0]

    class Notice(logging.Handler):
        def emit(self, record):
            if "compiling the kernels" in record.getMessage():
                noticed.set()

    def slow_create(self):
        assert noticed.wait(600), "no compile notice"      # a hang guard, not a timing
        offset[0] += 1000.0                                 # as a long first compile would
        from numba import njit
        assert njit(lambda x: x + 1)(1) == 2    # and a compile (numba's event), whatever
        return real(self)                       # the cache holds: the record is kept

    clock = types.SimpleNamespace(perf_counter=lambda: time.perf_counter() + offset[0],
                                  monotonic=lambda: time.monotonic() + offset[0])
    monkeypatch.setattr(sw.SweepFile, "create", slow_create)
    monkeypatch.setattr(sw, "time", clock)
    monkeypatch.setattr(pr, "time", clock)       # compile_notice's clock (compiler/notice.py)
    # the 1000 s it measures go to this test's record, not the session's compile cache
    monkeypatch.setattr(pr, "compile_record", lambda: tmp_path / "last_compile_s.txt")
    handler = Notice()
    logging.getLogger("pipeline").addHandler(handler)
    try:
        study = pipeline_load(studies)
        with caplog.at_level(logging.INFO, logger="pipeline"):
            out = sw.run_sweep(study, tmp_path / "s.h5", candidates=300, progress=False)
    finally:
        logging.getLogger("pipeline").removeHandler(handler)
    text = caplog.text
    assert "compiling the kernels of this mechanism" in text and "kernels ready after" in text
    compile_s = float(out.summary["compile_time"].split()[0])
    wall_s = float(out.summary["wall_time"].split()[0])
    assert compile_s >= 1000.0 and wall_s < 1000.0
    assert pr.last_compile_s() >= 1000.0             # the next notice's estimate


def pipeline_load(studies):
    from pipeline.study.reader import load_study
    return load_study(studies / "ov7_synthesis.toml")
