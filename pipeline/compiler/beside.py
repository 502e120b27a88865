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
run compiles the careful stages meanwhile (``compile_run_side``) and compiles
``evaluate``, which links everything, only once this process has printed
STANDALONE_DONE (``pipeline.compiler.ready_to_evaluate``): before, it reached
the force stage a second before the process beside had it, and compiled it
again.  The numbers are the same either way: the same source, the same flags.

A scene off the plan path (``pipeline.compiler.plan_path``: a mechanism whose
force system the tape cannot say) likewise: its ``forces_curve`` compiles in
the process beside while the run compiles the mechanism's positions
(``compile_scene_forces``).  After a sweep's kernels, the process beside
compiles, at the lowest priority, the library once per installation, the plan
path included (``compile_library``): every later scene compiles nothing.

    python -m pipeline.compiler.beside MODULE FOLDER [scene]
"""

from __future__ import annotations

import importlib
import os
import sys

import numpy as np

STANDALONE_DONE = "standalone kernels compiled"     # the line the process beside prints


def compile_standalone(mod) -> None:
    """Compile (or load) the kernels of the generated sweep module ``mod`` that
    the run's ``evaluate`` calls besides ``settle`` and ``flush_forces`` (which
    the run compiles meanwhile: ``compile_run_side``), for the argument types
    ``evaluate`` and ``settle`` give them, in the order the run needs them: the
    force lanes first (they call nothing the run compiles), the library's
    metrics (``compile_metrics``), then, once the run has compiled ``position``
    and ``advance`` (numba's cache), the force stage, which ``settle`` reaches
    about halfway through the run's compile; the kernels around the force lanes
    (``flush_forces`` calls them), the lane walk and the careful tail, which
    only ``evaluate`` calls.  ``walk`` and ``force_lanes`` by running them on a
    few positions of dummy data, the others (no Python wrapper) by ``compile``
    with the types of such data."""
    from numba import typeof
    lanes, npos = mod.LANES, 4
    if not getattr(mod, "HAS_LANES", False):
        return
    a1, a2 = np.zeros(4), np.zeros((4, 4))
    par = np.ones(mod.N_PARAMS)
    # the constants and the work arrays by the kernels' Python (the same types): their
    # compile (0.9 s, which the run does too) would hold back the force lanes
    K = mod.constants.py_func(par)
    wk = mod.work.py_func(mod.N_POINTS, mod.N_GROUPS, mod.N_TRIADS)
    fw = mod.force_work.py_func(mod.N_BODIES, mod.N_JOINTS, mod.N_SLIDES + mod.N_INPUTS)
    ww = mod.watch_work.py_func(mod.N_WATCH, mod.N_TRIADS)
    i64, b = np.int64(0), True
    loads = np.zeros((npos, 1, 3))
    status = np.zeros(4, np.int8)       # (the run's status array: pipeline.runs.problem)
    ix = np.zeros(4, np.int64)

    def compile_(name, *args):
        getattr(mod, name).compile(tuple(typeof(x) for x in args))

    forces = getattr(mod, "HAS_LANE_FORCES", False)
    if forces:
        fs = np.ones(mod.N_FROWS * lanes)
        ft = np.ones((npos, mod.FT_COLS * lanes))
        rb = np.zeros((npos, mod.N_RCOLS * lanes))
        mod.force_lanes(fs, ft, rb, lanes, npos, 1e-12, 1e-6, 1.0, 0.0,
                        np.zeros((npos, len(mod.LOAD_BODY), 3)), np.int64(0))
    compile_metrics(mod)
    # (by now the run has usually compiled position and advance: numba's cache)
    compile_("force_stage", par, K, a1, a1, a1, loads, a1, a2, b, wk, fw)
    if forces:
        compile_("force_flush", ix, i64, a1, a2, a2, a1, a1, a1, loads, status, a2)
        compile_("force_lane_in", par, i64, a2, a1, a2, a1, a2)
    s = np.ones((mod.N_LANE_ROWS, lanes))
    theta = np.zeros((npos, lanes * mod.THETA_COLS))
    c = np.cos(np.arange(float(npos)))
    mod.walk(s.reshape(-1), lanes, theta, c, c, 2, 1, 1e-12, 0.1, 0.05, 1e-3, 1e-7, 1e-6)
    compile_("block_walk", a2, a2, a1, a1, a1, a1, a1)
    compile_("careful_tail", K, a1, i64, i64, a2, a1, a1, a1, wk, ww)


def compile_run_side(mod) -> None:
    """Compile (or load) what the run's ``evaluate`` calls that the process
    beside does not compile (``compile_standalone``), for ``evaluate``'s
    argument types: ``setup_lane`` (with the mechanism's positions, which the
    force stage beside then loads), ``settle`` (the careful walk, the watch,
    the metrics; the force stage from the process beside) and ``flush_forces``
    (the force lanes' kernels from there).  ``evaluate`` itself, which links
    all of them, compiles last (``pipeline.compiler.ready_to_evaluate``)."""
    from numba import typeof
    if not getattr(mod, "HAS_LANES", False):
        return
    n = 4
    a1, a2, i1 = np.zeros(n), np.zeros((n, n)), np.zeros(n, np.int64)
    i64, f64 = np.int64(0), 0.0
    wk = mod.work(mod.N_POINTS, mod.N_GROUPS, mod.N_TRIADS)
    fw = mod.force_work(mod.N_BODIES, mod.N_JOINTS, mod.N_SLIDES + mod.N_INPUTS)
    ww = mod.watch_work(mod.N_WATCH, mod.N_TRIADS)
    loads = np.zeros((n, 1, 3))
    status = np.zeros(n, np.int8)       # (the run's status array: pipeline.runs.problem)

    def compile_(name, *args):
        getattr(mod, name).compile(tuple(typeof(x) for x in args))

    compile_("setup_lane", a2, i64, i64, a1, f64, a1, a2, a2, a2, a2, a2, a1, a2)
    compile_("settle", a1, i64, a1, f64, a1, a1, loads, a1, a2, i1, i1, f64, i64, f64, f64,
             wk, fw, ww, a1, a1)
    if getattr(mod, "HAS_LANE_FORCES", False):
        compile_("flush_forces", a2, i1, i64, a1, a2, a2, a1, f64, a1, a1, loads, a1, a2, i1,
                 i1, wk, fw, ww, a1, status, a2)


def compile_metrics(mod) -> None:
    """Compile (or load) the library's metric kernels that ``settle`` and
    ``evaluate`` call, for the argument types they give them (the lane width
    and the law's column are literal constants there): the dwell error, in
    lanes and alone, and the law error.  They call nothing of the mechanism's,
    so the process beside has them in numba's cache before the run reaches
    them."""
    from numba import typeof, types
    from pipeline.kernels import metrics
    from pipeline.kernels.sweep import SET_LAW0
    f1, i1 = typeof(np.zeros(1)), typeof(np.zeros(1, np.int64))
    metrics.dwell_error.compile((f1, types.int64, i1, i1))
    metrics.law_error.compile((f1, f1, types.literal(SET_LAW0), types.boolean, f1))
    metrics.dwell_lanes.compile((typeof(np.zeros((1, 1))), types.int64, types.int64,
                                 types.literal(mod.LANES), typeof(np.zeros((1, 1, 1))), f1, i1,
                                 f1))


def compile_library() -> None:
    """Compile (or load) what no mechanism's code is in, once per installation:
    the scene's walk (``pipeline.kernels.walk``), the crank dynamics'
    integrators (``pipeline.kernels.dynamics``, ``.dynamics_friction``) and the
    plan path with the kernels of every group type and those a scene calls from
    Python (``pipeline.compiler.plan_path``).  A scene, of a
    design of the sweep or of a new mechanism, then compiles nothing."""
    import warnings

    from numba.core.errors import NumbaExperimentalFeatureWarning

    from pipeline.compiler.plan_path import compile_plan_path
    from pipeline.kernels.dynamics import compile_integrator
    from pipeline.kernels.dynamics_friction import compile_friction_integrator
    with warnings.catch_warnings():     # (numba's note on first-class functions, which the
        warnings.simplefilter("ignore", NumbaExperimentalFeatureWarning)   # walk passes)
        # what most scenes need first: a scene that comes meanwhile compiles the rest itself
        compile_integrator()
        compile_plan_path()             # (the walk too)
        compile_friction_integrator()   # (30 s from an empty cache, for friction with dynamics)


def compile_scene_forces(mod) -> None:
    """Compile (or load) the generated module ``mod``'s ``forces_curve`` for the
    argument types a scene's forces pass it (``pipeline.solve.reactions``): it
    calls nothing of the walk's, so it compiles while the scene's run compiles
    its positions and walks the revolution."""
    from numba import typeof
    n = 2
    pos = np.zeros((n, mod.N_POINTS, 2))
    args = (np.ones(mod.N_PARAMS), pos, pos, pos, 1.0, 0.0,
            np.zeros((n, len(mod.LOAD_BODY), 3)), np.zeros((n, mod.N_BODIES, 3)),
            np.zeros((n, mod.N_JOINTS, 2)), np.zeros((n, mod.N_SLIDES + mod.N_INPUTS, 2)),
            np.zeros(n))
    mod.forces_curve.compile(tuple(typeof(x) for x in args))


def main(argv=None) -> int:
    name, folder, *what = (argv or sys.argv[1:])
    sys.path.insert(0, folder)
    mod = importlib.import_module(name)
    if what == ["scene"]:
        compile_scene_forces(mod)
        return 0
    compile_standalone(mod)
    print(STANDALONE_DONE, flush=True)      # (the run waits for it: ready_to_evaluate)
    # then, at the lowest priority (the run's sweep, on every core, goes first),
    # the library: the plan path that every scene runs on
    if hasattr(os, "nice"):
        os.nice(19)
    compile_library()
    return 0


if __name__ == "__main__":
    from ..base.processes import collect_seldom
    collect_seldom()
    raise SystemExit(main())
