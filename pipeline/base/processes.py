"""A process of this package's own beside the running one (the compile beside a
sweep, the workers of a refinement): ``python -P -m MODULE`` on the package this
process runs; and how the package's own processes, the program among them,
collect their garbage (``collect_seldom``).

``-P`` keeps the working folder off the new interpreter's path, and the folder
that holds this ``pipeline`` goes first on its PYTHONPATH: a ``pipeline`` folder
or ``pipeline.py`` where the user works shadows nothing, and a package found
through a script's own path (an uninstalled checkout) is found there too."""

from __future__ import annotations

import os
import sys
from pathlib import Path

_HOME = str(Path(__file__).resolve().parents[2])     # the folder that holds pipeline/


def module_command(module: str, *args: str) -> tuple[list[str], dict]:
    """(argv, environment) of ``python -P -m module args`` on this package."""
    path = os.pathsep.join([_HOME] + [p for p in [os.environ.get("PYTHONPATH")] if p])
    return [sys.executable, "-P", "-m", module, *args], dict(os.environ, PYTHONPATH=path)


# the youngest generation collected every 50,000 allocations net instead of Python's 700,
# the older two at Python's ratios (the cycles a process leaves are still collected,
# 50,000 objects at most waiting)
GC_THRESHOLDS = (50_000, 10, 10)


def collect_seldom() -> None:
    """This process's garbage collections made rarer (``GC_THRESHOLDS``): the imports,
    numba's loads and its compiles make objects that live as long as the process, and
    at Python's default the collector walked them again and again: 0.13 s of a scene's
    1.5 s (0.03 s so); while a new sweep mechanism compiles, 1.6 s of the run's CPU
    (0.5 s so) and 2.1 s of the process's beside it (0.8 s so).  For a process of the
    package's own (the program, the compile beside a sweep, a refinement's workers); a
    notebook or a test session keeps its own settings."""
    import gc
    gc.set_threshold(*GC_THRESHOLDS)
