"""Friction in a sweep: throughput of mechanism B's synthesis sweep with
[mechanism.friction] (objective friction_loss) against the same sweep without
friction (objective peak_reaction), run alternately in one process.

The candidates that reach the force stage (status OK, stroke and margin
constraints met) go the careful path with friction (``runs.sweep_friction``:
the kinematics again with second analogs, then Newton's iteration of the
reactions with friction at every position), the rest as without friction; so
the ratio depends on the share that reaches the force stage, printed with it.
Correct first: the friction run's candidates are checked to carry a finite
positive loss where their forces were evaluated.  Compile and first-call
times are printed apart from the steady state.

    python benchmarks/bench_friction.py [--candidates N] [--smoke]
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import STUDIES, hardware  # noqa: E402

FRICTION = """[mechanism.friction]
revolute = 0.08
pin_diameter = 10.0
pins = { P1 = 14.0, P2 = 12.0 }
pin_length = 12.0

"""


def _study(friction: bool):
    from pipeline.study.reader import parse_study
    text = (STUDIES / "ov7_synthesis.toml").read_text()
    objective = "friction_loss" if friction else "peak_reaction"
    text = re.sub(r"(?m)^objectives = .*$", f'objectives = ["dwell_error", "{objective}"]',
                  text, count=1)
    if friction:
        text = text.replace("[output]", FRICTION + "[output]", 1)
    return parse_study(text, f"ov7_synthesis{'_friction' if friction else ''}.toml")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", type=int, default=20000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--smoke", action="store_true", help="tiny sizes (the test suite)")
    a = ap.parse_args(argv)
    n, repeats = (400, 1) if a.smoke else (a.candidates, a.repeats)

    from pipeline.kernels import config as kc
    from pipeline.kernels import sweep as ks
    from pipeline.model.metric_catalogue import FRICTION_COLUMN
    from pipeline.runs.sweep import build_problem
    from pipeline.study.sampling import draw_checked
    from pipeline.study.sweep_spec import parameter_rows

    print(f"hardware: {hardware()}")
    runs = {}
    for friction in (False, True):
        study = _study(friction)
        spec = study.sweep.with_candidates(n)
        spec = replace(spec, chunk_size=n)
        problem = build_problem(study, spec)
        x, _ = draw_checked(spec, 0)
        pars = parameter_rows(problem.plan, spec, x)
        t = time.perf_counter()
        problem.evaluate_rows(pars[:50])        # compile or load the kernels
        runs[friction] = (problem, pars, time.perf_counter() - t)
    for friction in (False, True):
        print(f"first call ({'with' if friction else 'without'} friction, compile or cache "
              f"load): {runs[friction][2]:.2f} s")
    best = {False: np.inf, True: np.inf}
    out = {}
    for _ in range(repeats):
        for friction in (False, True):          # alternately, in the same minutes
            problem, pars, _ = runs[friction]
            t = time.perf_counter()
            out[friction] = problem.evaluate_rows(pars)
            best[friction] = min(best[friction], time.perf_counter() - t)
    status, rows = out[True]
    forces = (status == kc.OK) & (rows[:, ks.M_FORCES_DONE] == 1.0)
    loss = rows[forces, FRICTION_COLUMN["friction_loss"]]
    if not (np.isfinite(loss).all() and (loss > 0).all()):
        print("FAILED: a candidate of the force stage without a finite positive loss")
        return 1
    print(f"{n:,} candidates, {forces.sum():,} in the force stage "
          f"({100 * forces.mean():.1f}%), best of {repeats}:")
    print(f"{'sweep':>18} {'s':>8} {'candidates/s':>14} {'ratio':>7}")
    for friction in (False, True):
        s = best[friction]
        print(f"{'with friction' if friction else 'without friction':>18} {s:8.3f} "
              f"{n / s:14,.0f} {best[False] / s:7.3f}")
    per = (best[True] - best[False]) / max(forces.sum(), 1)
    print(f"careful path with friction: {1e3 * per:.2f} ms per candidate of the force stage "
          f"({len(runs[True][0].phis)} positions)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
