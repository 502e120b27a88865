"""Sweep throughput for the default study (issue: parallel Monte-Carlo sweeps).

Candidates per second of the kernel on the default study's candidates with
full metrics (positions, dwell, then forces for the still-feasible ones) and
with dwell-only metrics (no force stage), and the 1- vs all-thread scaling,
all in one process after a warm-up (compile time reported separately).  Then
the careful path alone (``evaluate_careful``, every candidate walked as the
lanes' failures are), on one thread, against the lanes' full metrics, the
rounds alternated: the rate a sweep could have on the plan path, whose kernels
have the careful path only (issue 53: whether a new mechanism's sweep could start
on them while its module compiles).

    python benchmarks/bench_sweep.py [--candidates 20000]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numba
import numpy as np

from common import STUDIES, best_of, first_call, hardware


def problem(study, full, n, staged=True):
    from pipeline.runs.sweep import build_problem
    from pipeline.study.sweep_spec import parameter_rows
    from pipeline.study.sampling import draw_candidates
    spec = study.sweep
    if not staged:  # constraints that never fail: forces for every assembled candidate
        spec = dataclasses.replace(spec, stroke_bounds=(-np.inf, np.inf), margin_min=-np.inf)
    if not full:
        spec = dataclasses.replace(spec, metrics=("dwell_error", "stroke", "singularity_margin"),
                                   objectives=("dwell_error",))
    spec = dataclasses.replace(spec, candidates=n, chunk_size=n)
    pb = build_problem(study, spec)
    return pb, parameter_rows(pb.plan, spec, draw_candidates(spec, 0))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", type=int, default=20_000)
    ap.add_argument("--smoke", action="store_true",
                    help="500 candidates, one timing each: that it runs (the test suite)")
    a = ap.parse_args(argv)
    repeat = 1 if a.smoke else 2
    if a.smoke:
        a.candidates = 500
    from pipeline.study.reader import load_study
    study = load_study(STUDIES / "ov7_synthesis.toml")
    print(f"hardware: {hardware()}")
    print(f"default study, {a.candidates:,} candidates x {study.sweep.positions} positions\n")
    full_pb, pars = problem(study, True, a.candidates)
    dwell_pb, _ = problem(study, False, a.candidates)
    unstaged_pb, _ = problem(study, True, a.candidates, staged=False)
    compile_s = first_call(lambda: full_pb.evaluate_rows(pars[:4], True))
    first_call(lambda: dwell_pb.evaluate_rows(pars[:4], True))
    threads = numba.get_num_threads()
    res = {}
    try:
        for n_thr in sorted({1, threads}):
            numba.set_num_threads(n_thr)
            for label, pb in (("full metrics", full_pb), ("dwell-only", dwell_pb),
                              ("no staging", unstaged_pb)):
                secs = best_of(lambda: pb.evaluate_rows(pars, True), repeat=repeat)
                res[(label, n_thr)] = a.candidates / secs
    finally:
        numba.set_num_threads(threads)
    status, metrics = full_pb.evaluate_rows(pars, True)
    from pipeline.kernels.sweep import M_FORCES_DONE
    forced = np.mean(metrics[:, M_FORCES_DONE] == 1.0)
    print(f"{'':<14}" + "".join(f"{f'{t} thread(s)':>16}" for t in sorted({1, threads})))
    for label in ("full metrics", "dwell-only", "no staging"):
        print(f"{label:<14}" + "".join(f"{res[(label, t)]:>12,.0f} c/s" for t in sorted({1, threads})))
    t = threads
    print(f"\nstatus OK {np.mean(status == 0):.1%}; force stage run for {forced:.1%} of candidates")
    print(f"dwell-only is x{res[('dwell-only', t)] / res[('full metrics', t)]:.2f} the speed of "
          "full metrics")
    print(f"staging (forces only for candidates meeting stroke and margin) is "
          f"x{res[('full metrics', t)] / res[('no staging', t)]:.2f} the speed of computing forces "
          "for every assembled candidate")
    if t > 1:
        print(f"scaling 1 -> {t} threads: x{res[('full metrics', t)] / res[('full metrics', 1)]:.2f} "
              f"(full), x{res[('dwell-only', t)] / res[('dwell-only', 1)]:.2f} (dwell-only)")
    print(f"first call (compile or cache load): {compile_s:.1f} s")
    careful_against_lanes(full_pb, pars[:max(50, a.candidates // 4)], repeat)


def careful_against_lanes(pb, pars, repeat):
    """Candidates/s on one thread of the careful path alone and of the lanes (the
    sweep's own ``evaluate``), alternated, and what the careful rate means for
    100,000 candidates."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
    from support.lanes import careful_rows      # (the lane tests' reference rows)
    careful_rows(pb, pars[:2])      # (compiled or loaded first)
    careful, lanes = [], []
    for _ in range(max(repeat, 2)):
        careful.append(len(pars) / best_of(lambda: careful_rows(pb, pars), repeat=1))
        lanes.append(len(pars) / best_of(lambda: pb.evaluate_rows(pars, True, 1), repeat=1))
    c, ln = max(careful), max(lanes)
    print(f"\ncareful path alone, 1 thread, {len(pars):,} candidates: {c:,.0f} c/s against "
          f"the lanes' {ln:,.0f} (x{ln / c:.1f}); 100,000 candidates on it take "
          f"{1e5 / c:.0f} s of one core")


if __name__ == "__main__":
    main()
