"""The whole process against the C yardstick's ``triad_full``, per core, on 1 core and on all.

    python benchmarks/bench_yardstick.py [--smoke | --quick] [--rounds R] [-o DIR]

``triad_full`` (``../shared/yardstick/triad_full.c``, built here with the flags of
``run.sh``) is mechanism B's whole synthesis sweep in hand-written SIMD C: positions by
Newton in lock-step lanes, the status checks, stroke, dwell error and margin of every
candidate, then analogs, R1..R7, M_bal and their peaks for those that reach the force stage.
The project's side is the whole process a user runs: ``pipeline run
studies/ov7_synthesis.toml --candidates N`` in a fresh process (its kernels cached), timed
from the process's start to its exit, so it counts the interpreter's start-up, the imports,
the kernels' load from numba's cache, the reference design, the sampler, the journal and the
HDF5 file.  Both count candidate-positions (every candidate x 360 positions) per second.

"On k cores": the process runs its kernels on k threads (``-j k``, as issue 53 measured it;
the journal and the HDF5 file are written on the process's main thread, beside them), and
the yardstick runs k OpenMP threads pinned to cores.  ``--confined`` also confines the
process to k cores (CPU affinity), so that the main thread's writing shares them.  Each
round runs, for 1 core then all cores, the yardstick, the project and the yardstick again,
and holds the project against the mean of the two yardstick runs; the table gives each round
(the yardstick's runs before and after beside their mean) and the median ratio (the
machine's speed drifts, so only ratios taken side by side mean anything).  The run's own wall time (``wall_time_s``: the
chunks, from the first to the file complete) is shown beside, so the fixed cost of a process
is seen apart.

--smoke (the suite: that it runs): 2,000 candidates, one round, 1 core; the yardstick where
gcc is here.  --quick: 200,000 candidates, one round.  Default: 1,000,000 candidates, three
rounds.  Writes DIR/yardstick.md (default results/bench/).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from common import ROOT, STUDIES, hardware  # noqa: E402

YARDSTICK = ROOT.parent / "shared" / "yardstick"
STUDY = STUDIES / "ov7_synthesis.toml"
POSITIONS = 360
C_CANDIDATES = 40_000        # per thread, as run.sh runs triad_full


def build_triad_full(folder: Path) -> Path | None:
    """triad_full compiled into ``folder`` with run.sh's flags; None where the
    yardstick or gcc is not here."""
    src, script = YARDSTICK / "triad_full.c", YARDSTICK / "run.sh"
    if not (src.exists() and script.exists() and shutil.which("gcc")):
        return None
    m = re.search(r'^F="([^"]*)"', script.read_text(), re.M)
    flags = m.group(1).split() if m else ["-O3", "-march=native", "-fopenmp"]
    exe = folder / "triad_full"
    subprocess.run(["gcc", *flags, "-o", str(exe), str(src), "-lm"], check=True,
                   cwd=YARDSTICK, capture_output=True)
    return exe


def yardstick_rate(exe: Path, threads: int, candidates: int) -> float:
    """triad_full's candidate-positions per second on ``threads`` pinned threads."""
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), OMP_PROC_BIND="true",
               OMP_PLACES="cores")
    out = subprocess.run([str(exe), "simd", str(candidates)], env=env, check=True,
                         capture_output=True, text=True, timeout=600).stdout
    m = re.search(r"^RESULT .*pos_per_s=([0-9.e+]+)", out, re.M)
    if not m:
        raise RuntimeError(f"triad_full printed no RESULT line:\n{out[-2000:]}")
    return float(m.group(1))


def process_run(cores: list[int], candidates: int, out: Path, confined: bool
                ) -> tuple[float, float]:
    """(seconds from the process's start to its exit, the run's own wall_time_s)
    of ``pipeline run`` of the default study on len(cores) kernel threads, and
    confined to ``cores`` where ``confined``."""
    cmd = [sys.executable, "-m", "pipeline.cli", "run", str(STUDY), "--candidates",
           str(candidates), "-o", str(out), "--overwrite", "-q", "--no-pictures",
           "-j", str(len(cores))]
    every = sorted(os.sched_getaffinity(0))
    cores = cores if confined else every
    env = dict(os.environ, PIPELINE_COMPILE_BESIDE="0")
    t = time.perf_counter()
    r = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=1800,
                       preexec_fn=lambda: os.sched_setaffinity(0, set(cores)))
    wall = time.perf_counter() - t
    if r.returncode != 0:
        raise RuntimeError(f"pipeline run failed:\n{r.stderr[-2000:]}")
    import h5py
    with h5py.File(out, "r") as f:
        inner = float(f.attrs["wall_time_s"])
    return wall, inner


def measure(candidates: int, rounds: int, core_counts: list[int], confined=False,
            echo=print) -> list[dict]:
    """One row per round and core count: the yardstick's and the process's rates."""
    rows = []
    all_cores = sorted(os.sched_getaffinity(0))
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        exe = build_triad_full(d)
        out = d / "syn.h5"
        process_run(all_cores, 2_000, out, False)  # the kernels in numba's cache, imports warm
        for r in range(rounds):
            for k in core_counts:
                # the yardstick right before and right after the process, their mean
                # its rate: the machine's pace drifts within a round
                def c_run():
                    return (yardstick_rate(exe, k, min(C_CANDIDATES, candidates) * k)
                            if exe is not None else float("nan"))
                before = c_run()
                wall, inner = process_run(all_cores[:k], candidates, out, confined)
                after = c_run()
                c_rate = 0.5 * (before + after)
                rate = candidates * POSITIONS / wall
                rows.append({"round": r + 1, "cores": k, "yardstick": c_rate,
                             "yardstick_span": (before, after), "process": rate,
                             "wall": wall, "run_wall": inner, "ratio": rate / c_rate})
                echo(f"round {r + 1}, {k} core(s): triad_full {c_rate / 1e6:.1f} M/s "
                     f"({before / 1e6:.1f} before, {after / 1e6:.1f} after), pipeline run "
                     f"{rate / 1e6:.1f} M/s ({wall:.1f} s, chunks {inner:.1f} s): "
                     f"{rate / c_rate:.2f}x")
    return rows


def table(rows: list[dict], candidates: int, confined=False) -> str:
    how = ("confined to k cores (CPU affinity), its kernels on k threads" if confined else
           "its kernels on k threads (-j k), its main thread writing beside them")
    lines = [f"# The whole process against triad_full ({candidates:,} candidates)", "",
             f"Machine: {hardware()}.", "",
             "Million candidate-positions per second (every candidate x 360 positions); the "
             f"process timed from its start to its exit; on k cores: {how} "
             "(the yardstick: k pinned threads).", "",
             "| round | cores | triad_full (before, after) | pipeline run | ratio | process s "
             "| chunks s |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        b, a = r["yardstick_span"]
        lines.append(f"| {r['round']} | {r['cores']} | {r['yardstick'] / 1e6:.1f} "
                     f"({b / 1e6:.1f}, {a / 1e6:.1f}) | "
                     f"{r['process'] / 1e6:.1f} | {r['ratio']:.2f}x | {r['wall']:.1f} | "
                     f"{r['run_wall']:.1f} |")
    lines += ["", "Median ratio per core count:", ""]
    for k in sorted({r["cores"] for r in rows}):
        rs = [r["ratio"] for r in rows if r["cores"] == k]
        lines.append(f"- {k} core(s): {statistics.median(rs):.2f}x "
                     f"(rounds {min(rs):.2f}-{max(rs):.2f}x)")
    return "\n".join(lines) + "\n"


def run(smoke=False, quick=False, rounds=None, out=None, confined=False, echo=print):
    candidates = 2_000 if smoke else 200_000 if quick else 1_000_000
    rounds = rounds or (1 if smoke or quick else 3)
    n = len(os.sched_getaffinity(0))
    core_counts = [1] if smoke else sorted({1, n})
    rows = measure(candidates, rounds, core_counts, confined, echo)
    folder = Path(out) if out else ROOT / "results" / "bench"
    folder.mkdir(parents=True, exist_ok=True)
    from pipeline.base.files import write_text
    text = table(rows, candidates, confined)
    write_text(folder / "yardstick.md", text)
    echo(text)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    size = ap.add_mutually_exclusive_group()
    size.add_argument("--smoke", action="store_true", help="2,000 candidates, 1 round, 1 core")
    size.add_argument("--quick", action="store_true", help="200,000 candidates, 1 round")
    ap.add_argument("--rounds", type=int, help="rounds (default 3; 1 with --smoke or --quick)")
    ap.add_argument("--confined", action="store_true",
                    help="confine the process to k cores (its writing shares them)")
    ap.add_argument("-o", "--output", help="folder for yardstick.md (default results/bench/)")
    a = ap.parse_args(argv)
    run(a.smoke, a.quick, a.rounds, a.output, a.confined)


if __name__ == "__main__":
    main()
