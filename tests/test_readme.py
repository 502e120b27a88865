"""The README's commands, in order, as written, on a copy of the checkout's
studies: the main job first, then every line of "Using it" (smaller candidate
counts, and a local Dask cluster in place of tcp://host:8786)."""

import re
import shlex
import shutil
from pathlib import Path

import pytest

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
    """The same command with a test-sized candidate count."""
    argv = list(argv)
    if "--candidates" in argv:
        argv[argv.index("--candidates") + 1] = SMALL
    elif argv[:2] == ["run", "studies/ov7_synthesis.toml"] and "--resume" not in argv:
        argv += ["--candidates", SMALL]
    return argv


def test_readme_commands_run_in_order(tmp_path, monkeypatch, capsys):
    distributed = pytest.importorskip("distributed")
    shutil.copytree(ROOT / "studies", tmp_path / "studies")
    monkeypatch.chdir(tmp_path)
    commands = readme_commands()
    assert commands[0] == "pipeline run studies/ov7_synthesis.toml"
    assert any("--scheduler" in c for c in commands) and any("--resume" in c for c in commands)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  protocol="tcp", dashboard_address=None) as cluster:
        for cmd in commands:
            argv = shlex.split(cmd)
            assert argv[0] == "pipeline", cmd
            argv = smaller(argv[1:])
            argv = [cluster.scheduler_address if a == "tcp://host:8786" else a for a in argv]
            if argv[0] == "compile" and "--show" not in argv:
                argv += ["-q"]
            rc = main(argv)
            captured = capsys.readouterr()
            assert rc == 0, (cmd, captured.err)
    assert (tmp_path / "results" / "ov7_synthesis.h5").exists()
    assert (tmp_path / "results" / "big_sweep.h5").exists()
    assert (tmp_path / "results" / "cluster.h5").exists()
    assert (tmp_path / "tables" / "points.csv").exists()
    assert (tmp_path / "report.html").exists()


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
    """A run whose kernels take more than a second to be ready says so while
    it waits, and reports the compile time apart from the wall time."""
    import logging
    import time

    import pipeline.sweep as sw
    real = sw.SweepFile.create

    def slow_create(self):
        time.sleep(1.6)          # as a first compile would
        return real(self)
    monkeypatch.setattr(sw.SweepFile, "create", slow_create)
    study = pipeline_load(studies)
    with caplog.at_level(logging.INFO, logger="pipeline"):
        out = sw.run_sweep(study, tmp_path / "s.h5", candidates=300, progress=False)
    text = caplog.text
    assert "compiling the kernels of this mechanism" in text and "kernels ready after" in text
    assert "compile_time" in out.summary and float(out.summary["wall_time"].split()[0]) < 1.6


def pipeline_load(studies):
    from pipeline.study import load_study
    return load_study(studies / "ov7_synthesis.toml")
