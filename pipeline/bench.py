"""`pipeline bench`: the measurements live in the folder benchmarks/ of a
source checkout (they are not part of the installed package); this finds that
folder, the one named by ``--benchmarks`` or benchmarks/ in the current folder,
and runs it."""

from __future__ import annotations

import importlib.util
from pathlib import Path

BENCHMARKS = Path("benchmarks")     # of the current folder (a checkout's root)


def run_benchmarks(quick=False, echo=print, out=None, benchmarks=None) -> Path:
    """Run ``benchmarks``/run_all.py (default: benchmarks/ of the current
    folder); its tables, plots and summary.md go into the folder ``out``
    (default: results/bench/ beside the benchmarks).  Returns the folder."""
    folder = Path(benchmarks) if benchmarks is not None else BENCHMARKS
    runner = folder / "run_all.py"
    if not runner.exists():
        raise FileNotFoundError(
            f"{runner.resolve()}: no benchmarks here; they come with the source checkout: "
            "run `pipeline bench` in a clone of the repository or name its folder with "
            "--benchmarks DIR")
    spec = importlib.util.spec_from_file_location("pipeline_benchmarks_run_all", runner)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.run(quick, echo=echo, out=out)
