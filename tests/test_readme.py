"""The README's commands, in order, as written, on a copy of the checkout's
studies: the main job first, then every line of "Using it" (smaller candidate
counts, and a local Dask cluster in place of tcp://host:8786)."""

import re
import shlex
import shutil
from pathlib import Path


from pipeline.cli import main

ROOT = Path(__file__).resolve().parent.parent
SMALL = "3000"


def readme_commands():
    text = (ROOT / "README.md").read_text()
    setup = re.search(r"^    pip install -e \. && (pipeline .*)$", text, re.M).group(1)
    using = text.split("## Using it", 1)[1].split("\n\n", 2)[1]
    lines = [ln.split("  #")[0].strip() for ln in using.splitlines() if ln.startswith("    ")]
    return [setup] + lines


def smaller(argv):
    """The same command with a test-sized candidate count; every run of the main
    job's study in chunks of 1000 (so that its files draw the same candidates)."""
    argv = list(argv)
    if "--candidates" in argv:
        argv[argv.index("--candidates") + 1] = SMALL
    elif argv[:2] == ["run", "studies/ov7_synthesis.toml"] and "--resume" not in argv:
        argv += ["--candidates", SMALL]
    if argv[:2] == ["run", "studies/ov7_synthesis.toml"] and "--resume" not in argv:
        argv += ["--chunk-size", "1000"]
    return argv


def test_readme_commands_run_in_order(tmp_path, monkeypatch, capsys):
    """Every command succeeds, and what they write holds: the main job's file, the
    bigger sweep (interrupted after its first chunk, then continued by the README's
    --resume line), the cluster run and the feasible-only run have the same
    candidates and numbers; the scene's tables give the crank tip of DOMAIN.md
    section 5 and naive.py's eyelet."""
    import distributed
    import h5py
    import numpy as np
    import pandas as pd

    import pipeline.runs.sweep as sw
    from support import naive
    from support.sweep_helpers import assert_same_results
    shutil.copytree(ROOT / "studies", tmp_path / "studies")
    monkeypatch.chdir(tmp_path)
    commands = readme_commands()
    assert commands[0] == "pipeline run studies/ov7_synthesis.toml"
    assert any("--scheduler" in c for c in commands) and any("--resume" in c for c in commands)
    real_run_sweep = sw.run_sweep
    results = tmp_path / "results"
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  protocol="tcp", dashboard_address=None) as cluster:
        for cmd in commands:
            argv = shlex.split(cmd)
            assert argv[0] == "pipeline", cmd
            argv = smaller(argv[1:])
            argv = [cluster.scheduler_address if a == "tcp://host:8786" else a for a in argv]
            if argv[0] == "compile" and "--show" not in argv:
                # in this process: the suite's other worker has the second core, and two
                # compile workers beside it slow the terminal tests there past their 2 s
                # (tests/compiler/test_compiler.py runs compile in worker processes)
                argv += ["-q", "-j", "1"]
            interrupt = "results/big_sweep.h5" in argv and "--resume" not in argv
            if interrupt:      # as if stopped after its first chunk: the next line resumes it
                monkeypatch.setattr(sw, "run_sweep", lambda *a, **k: real_run_sweep(
                    *a, **k, stop_after_chunks=1))
            rc = main(argv)
            monkeypatch.setattr(sw, "run_sweep", real_run_sweep)
            captured = capsys.readouterr()
            if interrupt:
                assert rc == 130 and "1 of 3 chunks saved" in captured.err, (cmd, captured.err)
                assert (results / "big_sweep.h5.parts").exists()
            else:
                assert rc == 0, (cmd, captured.err)
    main_job = results / "ov7_synthesis.h5"
    with h5py.File(main_job, "r") as f:
        assert f.attrs["complete"] and f["candidates/status"].shape == (int(SMALL),)
        feasible = f["candidates/feasible"][()]
        params = f["candidates/params"][()]
        dwell = f["metrics/dwell_error"][()]
    assert_same_results(main_job, results / "big_sweep.h5")      # interrupted, then resumed
    assert not (results / "big_sweep.h5.parts").exists()
    assert_same_results(main_job, results / "cluster.h5")
    with h5py.File(results / "cluster.h5", "r") as f:
        assert f.attrs["engine"] == "dask"
    # --store feasible: exactly the main job's feasible rows, with their sweep index
    with h5py.File(results / "huge.h5", "r") as f:
        np.testing.assert_array_equal(f["candidate"][()], np.flatnonzero(feasible))
        np.testing.assert_array_equal(f["candidates/params"][()], params[feasible])
        np.testing.assert_array_equal(f["metrics/dwell_error"][()], dwell[feasible])
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

    import pipeline.runs.problem as pr
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
    monkeypatch.setattr(pr, "time", clock)       # compile_notice's clock (runs/problem.py)
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
