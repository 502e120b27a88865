"""Compile every kernel ahead of time (fills numba's on-disk cache), so users
pay the compile cost once, not on every run: `pipeline compile`."""

from __future__ import annotations

import time
from pathlib import Path

STUDIES = Path(__file__).resolve().parent.parent / "studies"


def compile_all() -> dict:
    """Run each kernel family once on a tiny problem; returns seconds per family."""
    import dataclasses

    import numpy as np

    from .scene import batch_revolutions, run_scene
    from .study import load_study
    times = {}

    def timed(label, fn):
        t = time.perf_counter()
        fn()
        times[label] = time.perf_counter() - t

    for name in ("ov7_base", "ov7_class3", "warp_feed_fourbar"):
        study = load_study(STUDIES / f"{name}.toml")
        timed(f"scene {name}", lambda: run_scene(study))
    b = load_study(STUDIES / "ov7_class3.toml")
    timed("batch revolutions", lambda: batch_revolutions(
        b, b.mechanism.compile().par[None, :].copy(), 12, 2, True))
    syn = load_study(STUDIES / "ov7_synthesis.toml")

    def sweep_kernels():
        from .sweep import build_problem
        pb = build_problem(syn, dataclasses.replace(syn.sweep, positions=36))
        rows = np.ascontiguousarray(pb.plan.par[None, :])
        pb.evaluate_rows(rows, parallel=True)
        pb.evaluate_rows(rows, parallel=False)
    timed("sweep kernels", sweep_kernels)
    takeup = load_study(STUDIES / "takeup_dynamics.toml")

    def dynamics():
        from .dynamics import integrate, with_changes
        case = takeup.dynamics.cases[0]
        integrate(takeup.mechanism.compile(), takeup.mechanism,
                  with_changes(case, t_end=case.sample_dt))
    timed("crank dynamics", dynamics)
    return times
