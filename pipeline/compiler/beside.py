"""Compile a sweep module's stand-alone kernels in a process of their own, beside
the run that compiles the rest.

numba compiles one function at a time in a process, and a new sweep
mechanism's run compiles the careful stages (``settle_cpu``) first and reaches
the lane walk (``walk``), the force lanes (``force_lanes``) and the kernels
around them only after them, 15 s into a 30 s compile.  Those call nothing of
``settle_cpu``'s, so a second process (a second core) compiles them from the
start, with the argument types ``evaluate_lanes`` gives them, into numba's
cache; the run then loads them from there instead of compiling them
(``pipeline.compiler.kernels_for`` starts this where a new module has force
lanes and their cache is empty).  The numbers are the same either way: the
same source, the same flags.

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


def compile_standalone(mod) -> None:
    """Compile (or load) the kernels of the generated sweep module ``mod`` that
    ``evaluate_lanes`` and ``flush_forces`` call, for the argument types they
    give them, while the run compiles the careful walk's kernels (advance, the
    watch, locate), the force stage and ``settle_cpu``, and then those two:
    first the ones that call nothing the run compiles (the force lanes, the lane
    walk, the library's metrics:
    ``compile_metrics``; the kernels round the force lanes), then, once the run
    has compiled ``position``, ``advance``, the watch and ``locate`` (numba's
    cache), ``setup_lane`` and the careful tail, which the run reaches last.  Not
    the force stage: the run reaches it before this process could have it, and a
    run that finds a kernel missing compiles it itself.  ``walk`` and
    ``force_lanes`` by running them on a few positions of dummy data, the others
    (no Python wrapper) by ``compile`` with the types of such data."""
    from numba import typeof
    lanes, npos = mod.LANES, 4
    if not getattr(mod, "HAS_LANES", False):
        return
    a1, a2 = np.zeros(4), np.zeros((4, 4))
    par = np.ones(mod.N_PARAMS)
    samples = mod.callee_samples()      # (the types evaluate_lanes passes, as the run's)

    def compile_(name, *args):
        getattr(mod, name).compile(tuple(typeof(x) for x in args or samples[name]))

    forces = getattr(mod, "HAS_LANE_FORCES", False)
    if forces:
        fs = np.ones(mod.N_FROWS * lanes)
        ft = np.ones((npos, mod.FT_COLS * lanes))
        rb = np.zeros((npos, mod.N_RCOLS * lanes))
        mod.force_lanes(fs, ft, rb, lanes, npos, 1e-12, 1e-6, 1.0, 0.0,
                        np.zeros((npos, len(mod.LOAD_BODY), 3)), np.int64(0))
    s = np.ones((mod.N_LANE_ROWS, lanes))
    theta = np.zeros((npos, lanes * mod.THETA_COLS))
    c = np.cos(np.arange(float(npos)))
    mod.walk(s.reshape(-1), lanes, theta, c, c, 2, 1, 1e-12, 0.1, 0.05, 1e-3, 1e-7, 1e-6)
    compile_metrics()
    mod.lane_callees()      # (block_walk and force_flush call them through their addresses)
    compile_("block_walk")
    if forces:
        compile_("force_flush")
        compile_("force_lane_in", par, np.int64(0), a2, a1, a2, a1, a2)
    # (by now the run has usually compiled position, advance and the watch: numba's cache)
    mod.tail_callees()      # (setup_lane and careful_tail call advance, the watch, locate so)
    compile_("setup_lane")
    compile_("careful_tail")


def compile_metrics() -> None:
    """Compile (or load) the library's metric kernels that ``settle_cpu`` and
    ``evaluate`` call, for the argument types they give them (the law's column
    is a literal constant there): the dwell error, in lanes and alone, and the
    law error.  They call nothing of the mechanism's, so the process beside has
    them in numba's cache before the run reaches them."""
    from numba import typeof, types
    from pipeline.kernels import metrics
    from pipeline.kernels.sweep import SET_LAW0
    f1, i1 = typeof(np.zeros(1)), typeof(np.zeros(1, np.int64))
    metrics.dwell_error.compile((f1, types.int64, i1, i1))
    metrics.law_error.compile((f1, f1, types.literal(SET_LAW0), types.boolean, f1))
    metrics.dwell_lanes.compile((typeof(np.zeros((1, 1))), types.int64, types.int64,
                                 types.int64, typeof(np.zeros((1, 1, 1))), f1, i1, f1))


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
