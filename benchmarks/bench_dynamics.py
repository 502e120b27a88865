"""Crank dynamics benchmark: RK4 accuracy against the step size and its speed.

Correct first, then timed.  The reference is scipy's DOP853 at rtol = atol =
1e-12 over the same compiled right-hand side (the run-up case of
studies/takeup_dynamics.toml, 10 s, about 160 revolutions).  Prints the RK4
error in phi1 at 10 s for a series of steps, the observed order
log(err(dt_prev) / err(dt)) / log(dt_prev / dt) (4 for RK4), then the time per simulated second
with the compile time reported separately (the first call, warm-up).

    python benchmarks/bench_dynamics.py [--study PATH] [--smoke]

--smoke: the cases cut to 0.4 s and the three largest steps, timed once (that
it runs: the test suite; its orders mean little at that length).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import hardware  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
STEPS = (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4)
SAMPLE_DT = 0.04            # a whole number of every step above
REPEATS = 3


def _order(err_prev, err, dt_prev, dt):
    """Observed order between two steps."""
    return math.log(err_prev / err) / math.log(dt_prev / dt) if err > 0 else math.nan


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", default=str(ROOT / "studies" / "takeup_dynamics.toml"))
    ap.add_argument("--smoke", action="store_true", help="short cases, few steps (test suite)")
    a = ap.parse_args(argv)
    steps, repeats = (STEPS[:3], 1) if a.smoke else (STEPS, REPEATS)

    from pipeline.solve import crank_motion as dy
    from pipeline.study.reader import load_study

    study = load_study(a.study)
    plan = study.mechanism.compile()
    mech = study.mechanism
    case = next(c for c in study.dynamics.cases if c.name == "runup")
    if a.smoke:
        case = dy.with_changes(case, t_end=10 * SAMPLE_DT)
    print(f"hardware: {hardware()}")
    print(f"case {case.name}: phi_start = {math.degrees(case.phi_start):g} deg, "
          f"M1 = {case.M1.text} N m, b = {case.damping:g} N m s, t_end = {case.t_end:g} s")

    # warm-up: the first call compiles (or loads numba's on-disk cache)
    t = time.perf_counter()
    dy.integrate(plan, mech, dy.with_changes(case, t_end=SAMPLE_DT, sample_dt=SAMPLE_DT),
                 checked=False)
    print(f"compile / cache load (first RK4 call): {time.perf_counter() - t:.2f} s")

    t = time.perf_counter()
    ref = dy.integrate(plan, mech, dy.with_changes(case, sample_dt=SAMPLE_DT, dt=1e-3),
                       "dop853")
    t_ref = time.perf_counter() - t
    phi_ref = ref.phi1[-1]
    print(f"reference DOP853 (rtol = atol = {dy.DOP853_TOL:g}): {t_ref:.2f} s, "
          f"phi1({case.t_end:g} s) = {phi_ref:.12f} rad ("
          f"{phi_ref / (2 * math.pi):.1f} revolutions in all)")

    print()
    print(f"{'dt [s]':>9} {'|phi err| at t_end [rad]':>25} {'max |err| [rad]':>16} "
          f"{'order':>6} {'delta':>9} {'s per sim. s':>13}")
    prev = None
    for i, dt in enumerate(steps):
        c = dy.with_changes(case, dt=dt, sample_dt=SAMPLE_DT)
        best = math.inf
        for _ in range(repeats):
            res = dy.integrate(plan, mech, c, checked=False)   # the integrator at this dt
            best = min(best, res.seconds)
        err = abs(res.phi1[-1] - phi_ref)
        err_max = float(np.max(np.abs(res.phi1 - ref.phi1)))
        order = _order(prev, err, steps[i - 1], dt) if i else math.nan
        s = res.steady()
        print(f"{dt:9.1e} {err:25.3e} {err_max:16.3e} {order:6.2f} "
              f"{s['delta'] if s else math.nan:9.6f} {best / case.t_end:13.4f}")
        prev = err

    # the same on the conservative oscillation (b = 0, M1 = 0, from 280 deg): a clean h^4
    free = next(c for c in study.dynamics.cases if c.name == "free")
    free = dy.with_changes(free, damping=0.0, M1=0.0, sample_dt=SAMPLE_DT,
                           **({"t_end": 10 * SAMPLE_DT} if a.smoke else {}))
    ref_free = dy.integrate(plan, mech, dy.with_changes(free, dt=1e-3), "dop853")
    print()
    print("conservative oscillation (b = 0, M1 = 0, phi_start = 280 deg), max |phi err| "
          f"over {free.t_end:g} s:")
    prev = None
    for i, dt in enumerate(steps[:4]):
        res = dy.integrate(plan, mech, dy.with_changes(free, dt=dt), checked=False)
        err = float(np.max(np.abs(res.phi1 - ref_free.phi1)))
        order = _order(prev, err, steps[i - 1], dt) if i else math.nan
        print(f"{dt:9.1e} {err:25.3e} {order:6.2f}")
        prev = err

    dt = case.dt
    c = dy.with_changes(case, sample_dt=case.sample_dt)
    best = min(dy.integrate(plan, mech, c, checked=False).seconds for _ in range(repeats))
    checked = min(dy.integrate(plan, mech, c).seconds for _ in range(repeats))
    steps = case.t_end / dt
    print()
    print(f"study step dt = {dt:g} s: {best / case.t_end * 1e3:.1f} ms per simulated second "
          f"({best / steps * 1e6:.2f} us per step, {best / (4 * steps) * 1e9:.0f} ns per "
          f"right-hand side evaluation); {t_ref / best:.1f}x faster than the DOP853 "
          f"reference in this process; with its error estimate (the run at dt/2 beside it, "
          f"as a study runs it) {checked / case.t_end * 1e3:.1f} ms per simulated second, "
          f"{checked / best:.1f}x the integration alone")


if __name__ == "__main__":
    main()
