"""Compile a sweep module's stand-alone kernels in a process of their own, beside
the run that compiles the rest.

numba compiles one function at a time in a process, and a new sweep
mechanism's ``evaluate`` reaches its lane walk (``walk``), its force lanes
(``force_lanes``) and the kernels around them only after the careful stages,
15 s into a 30 s compile.  Those call nothing of ``settle``'s, so a second
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
    """Compile (or load) the kernels of the generated sweep module ``mod`` that
    call nothing of ``settle``'s careful stages (``walk``, ``force_lanes``,
    ``force_stage``, ``setup_lane``, ``block_walk``, ``force_lane_in``) and
    ``careful_tail``, for the argument types ``evaluate`` and ``settle`` give
    them: ``walk`` and ``force_lanes`` by running them on a few positions of
    dummy data, the others (no Python wrapper) by ``compile`` with the types of
    such data."""
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
        _compile_callees(mod, npos)


def _compile_callees(mod, npos):
    """``compile`` the kernels ``evaluate`` and ``settle`` call that have no
    Python wrapper, for the numba types of arrays, tuples and numbers like the
    ones those pass (C-contiguous float64 arrays, int64 indices)."""
    from numba import typeof
    a1, a2 = np.zeros(4), np.zeros((4, 4))
    par = np.ones(mod.N_PARAMS)
    K = mod.constants(par)
    wk = mod.work(mod.N_POINTS, mod.N_GROUPS, mod.N_TRIADS)
    fw = mod.force_work(mod.N_BODIES, mod.N_JOINTS, mod.N_SLIDES + mod.N_INPUTS)
    ww = mod.watch_work()
    i64, f64, b = np.int64(0), 0.0, True
    loads = np.zeros((npos, 1, 3))
    jobs = [("force_stage", (par, K, a1, a1, a1, loads, a1, a2, b, wk, fw)),
            ("setup_lane", (a2, i64, i64, a1, f64, a1, a2, a2, a2, a2, a2, a1, a2)),
            ("block_walk", (a2, a2, a1, a1, a1, a1, a1)),
            ("force_lane_in", (par, i64, a2, a1, a2, a1, a2)),
            ("careful_tail", (K, a1, i64, i64, a2, a1, a1, wk, ww))]
    for name, args in jobs:
        fn = getattr(mod, name, None)
        if fn is not None and hasattr(fn, "compile"):
            fn.compile(tuple(typeof(x) for x in args))


def main(argv=None) -> int:
    name, folder = (argv or sys.argv[1:])[:2]
    sys.path.insert(0, folder)
    compile_standalone(importlib.import_module(name))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
