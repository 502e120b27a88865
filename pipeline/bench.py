"""`pipeline bench`: the measurements live in benchmarks/ (next to the
package in a source checkout); this only finds and runs them."""

from __future__ import annotations

import importlib.util
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"


def run_benchmarks(quick=False, echo=print, out=None) -> Path:
    """Run benchmarks/run_all.py; its tables, plots and summary.md go into the
    folder ``out`` (default: results/bench/ of the checkout).  Returns the folder."""
    runner = BENCHMARKS / "run_all.py"
    if not runner.exists():
        raise FileNotFoundError(f"{runner}: the benchmarks come with the source checkout; "
                                "run `pipeline bench` from a clone of the repository")
    spec = importlib.util.spec_from_file_location("pipeline_benchmarks_run_all", runner)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.run(quick, echo=echo, out=out)
