"""Compile a sweep module's stand-alone kernels in a process of their own, beside
the run that compiles the rest.

numba compiles one function at a time in a process, and a new sweep
mechanism's ``evaluate`` reaches its lane walk (``walk``) and its force lanes
(``force_lanes``) only after the careful stages, 15 s into a 30 s compile.
Those two call nothing of the module's and take plain arrays, so a second
process (a second core) compiles them from the start, with the argument types
``evaluate`` gives them, into numba's cache; the run then loads them from
there instead of compiling them (``pipeline.compiler.kernels_for`` starts
this where a new module has force lanes and their cache is empty).  The
numbers are the same either way: the same source, the same flags.

    python -m pipeline.compiler.beside MODULE FOLDER
"""

from __future__ import annotations

import importlib
import sys

import numpy as np


def compile_standalone(mod) -> None:
    """Compile (or load) ``walk`` and ``force_lanes`` of the generated module
    ``mod`` for the argument types ``evaluate`` passes them, running each on a
    few positions of dummy data."""
    lanes = mod.LANES
    npos = 4
    if getattr(mod, "HAS_LANE_FORCES", False):
        fs = np.ones(mod.N_FROWS * lanes)
        ft = np.ones((npos, mod.FT_COLS * lanes))
        rb = np.zeros((npos, mod.N_RCOLS * lanes))
        loads = np.zeros((npos, len(mod.LOAD_BODY), 3))
        mod.force_lanes(fs, ft, rb, lanes, npos, 1e-12, 1e-6, 1.0, 0.0, loads, np.int64(0))
    if getattr(mod, "HAS_LANES", False):
        s = np.ones((mod.N_LANE_ROWS, lanes))
        theta = np.zeros((npos, lanes * mod.THETA_COLS))
        c = np.cos(np.arange(float(npos)))
        mod.walk(s.reshape(-1), lanes, theta, c, c, 2, 1, 1e-12, 0.1, 0.05, 1e-3, 1e-7, 1e-6)


def main(argv=None) -> int:
    name, folder = (argv or sys.argv[1:])[:2]
    sys.path.insert(0, folder)
    compile_standalone(importlib.import_module(name))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
