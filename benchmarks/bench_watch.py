"""The cost of the between-sample watch on the default sweep, same process.

Runs the default study's sweep evaluator (positions, dwell, stroke, margin and
the force stage, all cores or -j) on the same drawn candidates with the
product's kernels and with kernels generated without the watch
(``kernels_for(..., watch=False)``, failures left at the sample where they
were met: tols[T_LOCATE] = inf).  Reports compile time apart from steady
state, the steady-state ratio (the watch's cost), and what the watch changed:
candidates whose status differs and failures whose angle was located.

    python benchmarks/bench_watch.py [--candidates 100000] [-j 2] [--repeat 5]
                                     [--study studies/ov7_synthesis.toml]

The smoke run (--smoke, the test suite) takes a smaller sweep, the cam input's
(``cam_rocker_input_sweep``): its kernels without the watch compile in half
the time of the default study's.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import STUDIES, hardware  # noqa: E402
from pipeline.compiler import kernels_for  # noqa: E402
from pipeline.compiler.parallel import run_rows  # noqa: E402
from pipeline.kernels import config as kc  # noqa: E402
from pipeline.kernels import sweep as ks  # noqa: E402
from pipeline.study.reader import load_study  # noqa: E402
from pipeline.runs.sweep import build_problem  # noqa: E402
from pipeline.study.sweep_spec import parameter_rows  # noqa: E402
from pipeline.study.sampling import draw_checked  # noqa: E402


def candidates(pb, n):
    """n drawn candidates of the study (the sweep's own draws, chunk by chunk)."""
    rows, chunk = [], 0
    while sum(len(r) for r in rows) < n:
        x, _ = draw_checked(pb.spec, chunk)
        rows.append(parameter_rows(pb.plan, pb.spec, x))
        chunk += 1
    return np.ascontiguousarray(np.concatenate(rows)[:n])


def evaluator(pb, watch, n_jobs):
    kern = kernels_for(pb.plan, pb.rocker, watch=watch)
    tols = pb.tols.copy()
    if not watch:
        tols[kc.T_LOCATE] = math.inf      # a failure stays at the sample where it was met

    def run(pars):
        n = pars.shape[0]
        status = np.zeros(n, np.int8)
        metrics = np.full((n, ks.N_METRICS), np.nan)
        run_rows(kern.evaluate, pars, pb.phis, pb.phi_close, tols, pb.settings(), pb.loads,
                 status, metrics, n_jobs=n_jobs)
        return status, metrics
    return run


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", type=int, default=100_000)
    ap.add_argument("-j", "--jobs", type=int, default=None, help="threads (default: all cores)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--study", type=Path, default=None,
                    help="a sweep study (default: studies/ov7_synthesis.toml)")
    ap.add_argument("--smoke", action="store_true",
                    help="500 candidates of the cam input's sweep, timed once: that it runs "
                         "(the test suite)")
    args = ap.parse_args(argv)
    if args.smoke:
        args.candidates, args.repeat = 500, 1
    name = "cam_rocker_input_sweep.toml" if args.smoke else "ov7_synthesis.toml"
    study = load_study(args.study or STUDIES / name)
    pb = build_problem(study, study.sweep)
    pars = candidates(pb, args.candidates)
    small = pars[:64]
    print(f"# {hardware()}")
    print(f"# study {study.path.name}: {len(pars):,} drawn candidates, "
          f"{pb.spec.positions} positions, forces {'on' if pb.spec.wants_forces else 'off'}")
    runs = {}
    for label, watch in (("with the watch", True), ("without", False)):
        t = time.perf_counter()
        run = evaluator(pb, watch, args.jobs)
        run(small)
        print(f"compile + first call, {label}: {time.perf_counter() - t:.2f} s")
        runs[label] = run
    best = {k: math.inf for k in runs}
    out = {}
    for _ in range(args.repeat):        # alternate: drifts of the machine hit both alike
        for label, run in runs.items():
            t = time.perf_counter()
            out[label] = run(pars)
            best[label] = min(best[label], time.perf_counter() - t)
    for label in runs:
        print(f"steady state, {label}: {best[label]:.3f} s "
              f"({len(pars) / best[label]:,.0f} candidates/s, best of {args.repeat})")
    ratio = best["with the watch"] / best["without"]
    print(f"cost of the watch: {100 * (ratio - 1):+.2f} % (ratio {ratio:.4f})")
    (s1, m1), (s0, m0) = out["with the watch"], out["without"]
    changed = s1 != s0
    print(f"status changed by the watch: {int(changed.sum()):,} of {len(pars):,}")
    for a, b in sorted(set(zip(s0[changed].tolist(), s1[changed].tolist()))):
        k = int(((s0 == a) & (s1 == b)).sum())
        print(f"  {kc.STATUS_NAMES[a]} -> {kc.STATUS_NAMES[b]}: {k:,}")
    failed = ((s1 != kc.OK) & (s0 != kc.OK) & np.isfinite(m1[:, ks.M_FAIL_PHI])
              & np.isfinite(m0[:, ks.M_FAIL_PHI]))
    moved = np.degrees(np.abs(m1[failed, ks.M_FAIL_PHI] - m0[failed, ks.M_FAIL_PHI]))
    if moved.size:
        print(f"failure angles: {int((moved > 0).sum()):,} of {int(failed.sum()):,} differ "
              f"from the kernels without the watch (whose angle is the walk's failing step, "
              f"not bisected), median {np.median(moved):.4f} deg, up to {moved.max():.4f} deg")
    return 0


if __name__ == "__main__":
    sys.exit(main())
