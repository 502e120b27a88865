"""Compile every kernel ahead of time (fills numba's on-disk cache), so users
pay the compile cost once, not on every run."""

from __future__ import annotations

import time
from pathlib import Path

STUDIES = Path(__file__).resolve().parent.parent / "studies"


def compile_all() -> dict:
    """Run each kernel family once on a small problem; returns seconds per family."""
    from .scene import run_scene
    from .study import load_study
    times = {}
    for name in ("ov7_base", "ov7_class3"):
        path = STUDIES / f"{name}.toml"
        if path.exists():
            t = time.perf_counter()
            run_scene(load_study(path))
            times[f"scene {name}"] = time.perf_counter() - t
    return times
