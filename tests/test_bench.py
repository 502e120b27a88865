"""`pipeline bench --quick -o DIR` runs and writes its tables and plots into DIR
(the numbers themselves are measurements, not assertions; their consistency is
checked).  The test writes only under tmp_path, never into results/bench/."""

from pathlib import Path

import pandas as pd

from pipeline.bench import BENCHMARKS
from pipeline.cli import main

DEFAULT_OUT = BENCHMARKS.parent / "results" / "bench"


def _snapshot(folder):
    return {p: p.stat().st_mtime_ns for p in folder.rglob("*")} if folder.exists() else {}


def test_bench_quick_writes_tables_and_plots(capsys, tmp_path):
    out = tmp_path / "bench"
    before = _snapshot(DEFAULT_OUT)
    assert main(["bench", "--quick", "-q", "-o", str(out)]) == 0
    assert _snapshot(DEFAULT_OUT) == before      # a user's own benchmark output is left alone
    assert Path(capsys.readouterr().out.strip().splitlines()[-1]) == out   # -q prints the folder
    for name in ("a_positions", "b_newton", "c_analogs", "d_rk4", "e_fastmath", "throughput"):
        assert (out / f"{name}.csv").exists(), name
    assert (out / "summary.md").exists()
    for png in ("a_positions.png", "b_newton.png", "c_analogs.png", "d_rk4.png"):
        assert (out / png).read_bytes()[:4] == b"\x89PNG"
    a = pd.read_csv(out / "a_positions.csv")
    assert (a.peak_rel_error < 1e-3).all()          # the peak reaction converges
    c = pd.read_csv(out / "c_analogs.csv")
    fd = c[c.setting != "exact"]
    assert fd.velocity_rel_error.min() > 1e-11      # finite differences are never exact
    d = pd.read_csv(out / "d_rk4.csv")
    assert (d.order.dropna() > 3.5).all()           # RK4 is fourth order
    e = pd.read_csv(out / "e_fastmath.csv")
    assert e.status_agreement.min() > 0.99
