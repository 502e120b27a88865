"""`pipeline bench`: every speed and accuracy measurement in one run.

Accuracy against run time (a)-(e) from bench_accuracy, the throughput table
from bench_throughput, written under results/bench/ (CSV tables, log-log
plots, summary.md).  --quick shrinks every study so the whole run fits in
CI (under 2 minutes on 2 cores with the kernels' cache warm).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import bench_accuracy  # noqa: E402
from common import hardware  # noqa: E402

OUT = bench_accuracy.OUT


def run(quick=False, echo=print):
    t0 = time.perf_counter()
    lines = [f"# Speed and accuracy ({'quick' if quick else 'full'} run)", "",
             f"hardware: {hardware()}", ""]

    def both(text=""):
        echo(text)
        lines.append(text)

    tables = bench_accuracy.run(quick, echo=echo)
    for name, df in tables.items():
        lines += [f"## {name}", "", df.attrs.get("note", ""), "",
                  df.to_markdown(index=False, floatfmt=".3g") if _has_tabulate()
                  else "```\n" + df.to_string(index=False) + "\n```", ""]
    try:
        import bench_throughput
    except ImportError:
        both("(throughput table: benchmarks/bench_throughput.py not available)")
    else:
        df = bench_throughput.run(quick)
        echo("\nthroughput:\n" + df.to_string(index=False))
        lines += ["## throughput", "", "```", df.to_string(index=False), "```", ""]
    both(f"\nwritten to {OUT} in {time.perf_counter() - t0:.0f} s")
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "summary.md").write_text("\n".join(lines) + "\n")
    return OUT


def _has_tabulate():
    try:
        import tabulate  # noqa: F401
        return True
    except ImportError:
        return False


if __name__ == "__main__":
    run("--quick" in sys.argv)
