"""The checkout the tests run from: its benchmarks folder and their default
output folder, an environment in which a child process imports this
checkout's package, and a snapshot of a folder to show it was left alone."""

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BENCHMARKS = ROOT / "benchmarks"
BENCH_OUT = ROOT / "results" / "bench"      # the benchmarks' default output: a user's own


def child_env(**extra) -> dict:
    """os.environ with this checkout first on PYTHONPATH (and ``extra``)."""
    path = os.pathsep.join([str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p])
    return dict(os.environ, PYTHONPATH=path, **extra)


def snapshot(folder) -> dict:
    """{path: modification time} of everything under ``folder`` ({} if it is not there)."""
    folder = Path(folder)
    return {p: p.stat().st_mtime_ns for p in folder.rglob("*")} if folder.exists() else {}
