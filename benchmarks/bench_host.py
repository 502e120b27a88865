"""A GPU sweep's host side alone, on any machine (no GPU needed).

``run_sweep`` of the default study where each chunk's evaluation answers at
once with real rows (the CPU kernels' status and metrics of the first drawn
candidates, tiled to a chunk, copied once per chunk as a device's rows arrive).
What is left is the host's own work: drawing the next chunk, feasibility, the
journal and the HDF5 rows.  Its candidates/s is the ceiling of any device's end
to end rate on this host: 10^8 candidates a minute (issue 54) needs 1,666,667/s,
and the table gives the host's rate against it.  The drawing of one chunk is
timed apart (the thread that draws the next chunk while the device evaluates
one).  The first, compiling, evaluation is outside the timed runs.  The
process's peak memory (its largest resident size so far, the evaluation of
the rows it answers with included) is reported with each size.

    python benchmarks/bench_host.py [--sizes 10000000] [--chunk-size 1000000]
                                    [--store feasible] [-o DIR]

Writes DIR/host.md (default results/bench/).
"""

from __future__ import annotations

import argparse
import resource
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import ROOT, STUDIES, hardware  # noqa: E402
from pipeline.runs import problem as problem_module  # noqa: E402
from pipeline.runs.sweep import build_problem, run_sweep  # noqa: E402
from pipeline.study.reader import load_study  # noqa: E402

A_MINUTE_OF_1E8 = 1e8 / 60.0        # candidates/s


def _answered(status, metrics, real):
    """SweepProblem.evaluate_rows for the timed runs: a copy of the tiled rows
    per chunk, as a device's rows arrive (the reference design, one row, by
    ``real``)."""
    def evaluate_rows(problem, pars, parallel=True, n_jobs=None, watch=None):
        n = len(pars)
        if n == 1:
            return real(problem, pars, parallel, n_jobs, watch)
        return status[:n].copy(), metrics[:n].copy()
    return evaluate_rows


def measure(sizes, chunk_size, store, echo=print):
    study = load_study(STUDIES / "ov7_synthesis.toml")
    spec = replace(study.sweep.with_candidates(max(sizes)), chunk_size=chunk_size)
    problem = build_problem(study, spec)
    t = time.perf_counter()
    problem.draw_chunk(0)
    draw_first = time.perf_counter() - t
    t = time.perf_counter()
    _, _, pars = problem.draw_chunk(1 % spec.n_chunks)
    draw_s = time.perf_counter() - t
    rows = pars[:min(len(pars), 30_000)]
    status, metrics = problem.evaluate_rows(np.ascontiguousarray(rows))
    tile = np.arange(chunk_size) % len(rows)
    echo(f"drawing a chunk of {chunk_size:,}: {draw_s:.3f} s (the first, with the sampler's "
         f"import: {draw_first:.2f} s)")
    real = problem_module.SweepProblem.evaluate_rows
    out = []
    problem_module.SweepProblem.evaluate_rows = _answered(status[tile], metrics[tile], real)
    try:
        with tempfile.TemporaryDirectory() as tmp:
            for n in sizes:
                path = Path(tmp) / f"host{n}.h5"
                t, cpu = time.perf_counter(), time.thread_time()
                run_sweep(study, path, candidates=n, chunk_size=min(chunk_size, n),
                          progress=False, store=store)
                wall, main = time.perf_counter() - t, time.thread_time() - cpu
                peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024   # MiB
                out.append(dict(n=n, wall=wall, main=main, rate=n / wall, peak=peak))
                echo(f"host alone, {n:,} candidates, store {store}: {wall:.2f} s, "
                     f"{n / wall:,.0f}/s, main thread {main:.2f} s of CPU, the process's "
                     f"peak memory {peak:,.0f} MiB")
                path.unlink()
    finally:
        problem_module.SweepProblem.evaluate_rows = real
    return out, draw_s


def table(rows, draw_s, chunk_size, store):
    lines = ["# A GPU sweep's host side alone", "", hardware(), "",
             f"The default study, chunks of {chunk_size:,}, store {store}; each chunk's rows "
             "answered at once (real rows, copied as a device's arrive). Drawing one chunk: "
             f"{draw_s:.3f} s.", "",
             "| candidates | host alone s | candidates/s | main thread CPU s | "
             "against 10^8 a minute | peak memory MiB |", "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['n']:,} | {r['wall']:.2f} | {r['rate']:,.0f} | {r['main']:.2f} | "
                     f"{r['rate'] / A_MINUTE_OF_1E8:.2f}x | {r['peak']:,.0f} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10_000_000])
    ap.add_argument("--chunk-size", type=int, default=1_000_000)
    ap.add_argument("--store", choices=("all", "feasible"), default="feasible")
    ap.add_argument("--smoke", action="store_true", help="2,000 candidates in chunks of 500")
    ap.add_argument("-o", "--output", help="folder for host.md (default results/bench/)")
    a = ap.parse_args(argv)
    if a.smoke:
        a.sizes, a.chunk_size = [2_000], 500
    rows, draw_s = measure(a.sizes, a.chunk_size, a.store)
    folder = Path(a.output) if a.output else ROOT / "results" / "bench"
    folder.mkdir(parents=True, exist_ok=True)
    from pipeline.base.files import write_text
    text = table(rows, draw_s, a.chunk_size, a.store)
    write_text(folder / "host.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
