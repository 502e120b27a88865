"""`pipeline bench --quick -o DIR` runs and writes its tables and plots into DIR.
Times are measurements, not assertions; the accuracy it reports is held to the
README's figures (tests/support/tolerances.py), and the values it measures at
12, 360 and 720 positions to naive.py's.  The test writes only under tmp_path,
never into results/bench/."""

import sys
from pathlib import Path

import pandas as pd
import pytest

from pipeline.cli import main
from support import naive
from support.checkout import BENCH_OUT, BENCHMARKS, child_env, snapshot
from support.terminal import longest_silence, run_on_terminal
from support.tolerances import (CLOSURE_MM, DWELL_360_ABS, DWELL_720_ABS, DWELL_VS_NAIVE_REL,
                                FD_ACCELERATION_REL, FD_VELOCITY_REL, NEWTON_ITERATIONS,
                                NEWTON_TOL, PEAK_12_REL, REACTION_FD_REL)

SILENCE_S = 2.0        # tests/base/test_progress.py


def test_bench_quick_writes_tables_and_plots(capsys, tmp_path):
    """On a pseudo-terminal (where the platform has one), as a person runs it: it
    says something at least every 2 s of its own pace (support.terminal: less its
    waits for a processor on a loaded machine; tests/base/test_progress.py holds the
    other commands to that); elsewhere in this process, -q printing only the folder."""
    out = tmp_path / "bench"
    before = snapshot(BENCH_OUT)
    argv = ["bench", "--quick", "-o", str(out), "--benchmarks", str(BENCHMARKS)]
    if sys.platform.startswith("linux"):
        code, times, end, text = run_on_terminal([sys.executable, "-m", "pipeline.cli"] + argv,
                                                 env=child_env())
        assert code == 0, text
        assert longest_silence(times, end) <= SILENCE_S, (times, end, text)
        assert f"written to {out} in" in text and "bench e_fastmath: " in text, text
    else:
        assert main(argv + ["-q"]) == 0
        assert Path(capsys.readouterr().out.strip().splitlines()[-1]) == out   # the folder
    assert snapshot(BENCH_OUT) == before      # a user's own benchmark output is left alone
    for name in ("a_positions", "b_newton", "c_analogs", "d_rk4", "e_fastmath", "throughput"):
        assert (out / f"{name}.csv").exists(), name
    assert (out / "summary.md").exists()
    for png in ("a_positions.png", "b_newton.png", "c_analogs.png", "d_rk4.png"):
        assert (out / png).read_bytes()[:4] == b"\x89PNG"
    a = pd.read_csv(out / "a_positions.csv").set_index("positions")
    # (a) what it measures, against naive.py at the same positions (mechanism B at the
    # synthesis speed, omega1 = -97.2 rad/s) ...
    peak12, _, _ = naive.naive_mech_b_peak(12, omega1=-97.2)
    assert a.peak_reaction_N[12] == pytest.approx(peak12, rel=REACTION_FD_REL)
    for n in (360, 720):
        assert a.dwell_error[n] == pytest.approx(naive.naive_mech_b_motion(n)[0],
                                                 rel=DWELL_VS_NAIVE_REL)
    # ... and its convergence, against the README's figures
    assert a.peak_rel_error[12] <= PEAK_12_REL
    assert a.dwell_abs_error[360] <= DWELL_360_ABS and a.dwell_abs_error[720] <= DWELL_720_ABS
    # (b) Newton at the default tolerance: two steps per position, the converged positions
    b = pd.read_csv(out / "b_newton.csv").set_index("setting")
    assert b.mean_iterations[f"tol {NEWTON_TOL:g}"] == NEWTON_ITERATIONS
    assert b.position_error_mm[f"tol {NEWTON_TOL:g}"] <= CLOSURE_MM
    # (c) the best a finite difference does, to one significant digit (README)
    c = pd.read_csv(out / "c_analogs.csv")
    fd = c[c.setting != "exact"]
    assert float(f"{fd.velocity_rel_error.min():.0e}") == FD_VELOCITY_REL
    assert float(f"{fd.acceleration_rel_error.min():.0e}") == FD_ACCELERATION_REL
    d = pd.read_csv(out / "d_rk4.csv")
    assert (d.order.dropna() > 3.5).all()           # RK4 is fourth order
    e = pd.read_csv(out / "e_fastmath.csv")
    assert e.status_agreement.min() > 0.99


def test_bench_and_compile_outside_a_checkout_say_what_to_name(tmp_path, monkeypatch, capsys):
    """The installed package carries neither benchmarks nor studies: in a folder
    without them, `bench` and `compile` fail in one line that says what to name,
    instead of reaching for files beside the package."""
    monkeypatch.chdir(tmp_path)
    assert main(["bench", "--quick", "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--benchmarks DIR" in err, err
    assert main(["compile", "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "pipeline compile STUDY.toml" in err, err
    assert not any(tmp_path.iterdir())                  # nothing written


@pytest.mark.parametrize("name, written", [("bench_tolerance", "tolerance.md"),
                                           ("bench_robust", "robust.md")])
def test_benchmark_smoke_modes_run(name, written, tmp_path, monkeypatch):
    """A benchmark that breaks fails the suite: each runs at tiny sizes."""
    import importlib
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    mod = importlib.import_module(name)
    res = mod.run(smoke=True, out=tmp_path, echo=lambda *a: None)
    assert (tmp_path / written).read_text().startswith("#")
    if name == "bench_tolerance":
        assert res["builds"] == 256 and res["build_rate"] > 0 and res["sweep_rate"] > 0
    else:
        assert res["rows"] and all(n > 0 for n in res["fronts"].values())


def test_report_benchmark_smoke_mode_runs(synthesis_sweep, tmp_path, monkeypatch):
    """bench_report at tiny sizes, on a copy of the session's sweep (no sweep of its
    own): the explorer and the whole report timed, the page measured."""
    import importlib

    from support.sweep_helpers import copy_of
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    mod = importlib.import_module("bench_report")
    src = copy_of(synthesis_sweep, tmp_path / "sweep")
    res = mod.run(smoke=True, out=tmp_path, echo=lambda *a: None, source=src)
    text = (tmp_path / "report.md").read_text()
    assert text.startswith("#") and "explorer, steady state" in text
    assert res["explorer_s"] > 0 and res["report_s"] > 0 and res["designs"] >= 2
    from pipeline.views.page import plotly_js
    assert res["page_bytes"] > len(str(plotly_js()))    # plotly.js inline: one offline file
