"""Kinematics and forces throughput (issues: kinematics kernels, kinetostatics).

Prints candidate-positions per second of full kinematics (positions + both
analogs) of mechanism B for N candidates x 360 positions on all cores, the same
for a four-bar (mechanism D) for comparison, the cost of forces on top of
kinematics as a ratio, and compile times separately: cold (empty numba cache,
in a fresh process) and with the cache warm.

    python benchmarks/bench_kernels.py [--candidates 100000] [--positions 360]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile

from common import STUDIES, batch_runner, best_of, first_call, hardware, perturbed_rows

B_VARS = ("crank.length", "P6.x", "P6.y", "triad.L23", "triad.L34", "triad.L45", "triad.L35",
          "triad.L46", "triad.L57")
D_VARS = ("crank.length", "RRR[1].L_AB", "RRR[1].L_CB", "P4.x")


def compile_times():
    """Seconds to the first result in a fresh process: with empty caches (cold:
    the mechanism's module generated and compiled) and with the caches that run
    filled (warm)."""
    code = ("import time; t=time.perf_counter();"
            "from pipeline.study.reader import load_study; from pipeline.solve.scene import run_scene;"
            f"run_scene(load_study({str(STUDIES / 'ov7_class3.toml')!r}));"
            "import benchmarks_probe" if False else
            "import time, sys; t=time.perf_counter();"
            "sys.path.insert(0, %r);" % os.path.dirname(__file__) +
            "from common import *; from pipeline.study.reader import load_study;"
            f"s=load_study({str(STUDIES / 'ov7_class3.toml')!r}); p=s.mechanism.compile();"
            "r=batch_runner(s, perturbed_rows(p, (), 4), 36, 2, True); r();"
            "print(time.perf_counter()-t)")
    with tempfile.TemporaryDirectory() as cache:
        # cold: no generated module (PIPELINE_CACHE_DIR) and no compiled kernel
        # (NUMBA_CACHE_DIR); warm: both as the cold run left them
        env = dict(os.environ, NUMBA_CACHE_DIR=os.path.join(cache, "numba"),
                   PIPELINE_CACHE_DIR=os.path.join(cache, "pipeline"))
        out = []
        for _ in range(2):
            r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                               text=True, check=True)
            out.append(float(r.stdout.strip().splitlines()[-1]))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", type=int, default=100_000)
    ap.add_argument("--positions", type=int, default=360)
    ap.add_argument("--no-compile", action="store_true", help="skip the cold/warm compile timing")
    ap.add_argument("--smoke", action="store_true",
                    help="200 candidates x 36 positions, no compile timing: that it runs "
                         "(the test suite)")
    a = ap.parse_args(argv)
    if a.smoke:
        a.candidates, a.positions, a.no_compile = 200, 36, True
    from pipeline.study.reader import load_study
    print(f"hardware: {hardware()}")
    print(f"{a.candidates:,} candidates x {a.positions} positions per revolution\n")
    rows = []
    b = load_study(STUDIES / "ov7_class3.toml")
    d = load_study(STUDIES / "warp_feed_fourbar.toml")
    cases = [("mechanism B, full kinematics", b, B_VARS, False),
             ("mechanism B, kinematics + forces", b, B_VARS, True),
             ("four-bar D, full kinematics", d, D_VARS, False),
             ("four-bar D, kinematics + forces", d, D_VARS, True)]
    for label, study, names, forces in cases:
        pars = perturbed_rows(study.mechanism.compile(), names, a.candidates, spread=0.02)
        run = batch_runner(study, pars, a.positions, 2, forces)
        warm = first_call(batch_runner(study, pars[:2], a.positions, 2, forces))
        secs = best_of(run, repeat=2)
        status = run()[0]
        rate = a.candidates * a.positions / secs
        rows.append((label, secs, rate, (status == 0).mean()))
        print(f"{label:<36} {secs:7.2f} s  {rate / 1e6:7.2f} M candidate-positions/s "
              f"(OK {100 * (status == 0).mean():.0f}%, first small call {warm:.2f} s)")
    kin_b, frc_b = rows[0][1], rows[1][1]
    kin_d = rows[2][1]
    print(f"\nforces on top of kinematics, mechanism B: x{frc_b / kin_b:.2f} the time of "
          "kinematics alone")
    print(f"mechanism B (class III Newton) vs four-bar (closed form): x{kin_b / kin_d:.2f} the time")
    if not a.no_compile:
        cold, warm = compile_times()
        print(f"\ncompile (fresh process to first result): cold cache {cold:.1f} s, "
              f"warm cache {warm:.1f} s")


if __name__ == "__main__":
    main()
