"""`pipeline bench`: every speed and accuracy measurement in one run.

Accuracy against run time (a)-(e) from bench_accuracy, the throughput table
from bench_throughput, written into one folder (CSV tables, log-log plots,
summary.md): ``out``, default results/bench/ of the checkout (-o DIR on the
command line).  --quick shrinks every study so the whole run fits in CI
(under 2 minutes on 2 cores with the kernels' cache warm).
"""

from __future__ import annotations

from pipeline.base.files import write_text
from pipeline.base.progress import ticking

import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import bench_accuracy  # noqa: E402
from common import hardware  # noqa: E402

DEFAULT_OUT = bench_accuracy.DEFAULT_OUT


def run(quick=False, echo=print, out=None):
    """Every study and the throughput table, written into ``out`` (default
    DEFAULT_OUT); returns the folder."""
    out = Path(out) if out is not None else DEFAULT_OUT
    t0 = time.perf_counter()
    lines = [f"# Speed and accuracy ({'quick' if quick else 'full'} run)", "",
             f"hardware: {hardware()}", ""]

    def both(text=""):
        echo(text)
        lines.append(text)

    tables = bench_accuracy.run(quick, echo=echo, out=out)
    for name, df in tables.items():
        lines += [f"## {name}", "", df.attrs.get("note", ""), "",
                  df.to_markdown(index=False, floatfmt=".3g") if _has_tabulate()
                  else "```\n" + df.to_string(index=False) + "\n```", ""]
    try:
        import bench_throughput
    except ImportError:
        both("(throughput table: benchmarks/bench_throughput.py not available)")
    else:
        with ticking("bench throughput"):
            df = bench_throughput.run(quick, csv=out / "throughput.csv")
        echo("\nthroughput:\n" + df.to_string(index=False))
        lines += ["## throughput", "", "```", df.to_string(index=False), "```", ""]
    both(f"\nwritten to {out} in {time.perf_counter() - t0:.0f} s")
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "summary.md", "\n".join(lines) + "\n")
    return out


def _has_tabulate():
    try:
        import tabulate  # noqa: F401
        return True
    except ImportError:
        return False


def main(argv=None):
    import argparse
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small sizes (about a minute)")
    ap.add_argument("-o", "--output", metavar="DIR", default=str(DEFAULT_OUT),
                    help="folder for the tables, plots and summary.md (default: %(default)s)")
    a = ap.parse_args(argv)
    run(a.quick, out=a.output)


if __name__ == "__main__":
    main()
