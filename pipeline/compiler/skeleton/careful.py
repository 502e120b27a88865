"""The careful path of a generated module: the scene's revolution and forces
(the walks and the watch are pipeline.kernels.walk's, pasted before this; the
sweep's careful stages are in ``sweep_stages``).

The text below the marker line is pasted into the generated module
(``pipeline.compiler.generate``, after the walk); the imports above it declare,
for linters and readers, the names the generated module gives it."""


from .header import (np, njit, JIT_ALLOC, JIT_FIRST_CLASS, force_work, scene_revolution)
from ._mechanism import (N_BODIES, N_JOINTS, N_SLIDES, N_INPUTS, N_TRIADS, WATCH_G, constants,
                         start, advance, forces_at)

# ---- the skeleton: from here on, pasted into the generated module ----
# the scene's advance and start: the same functions with the C wrapper whose
# address numba's first-class functions call (pipeline.kernels.walk); the
# sweep's, which other kernels only call directly, have none (compile time)
advance_first_class = njit(**JIT_FIRST_CLASS)(getattr(advance, "py_func", advance))
start_first_class = njit(**JIT_FIRST_CLASS)(getattr(start, "py_func", start))


def constants_array(par):
    """``constants(par)`` as an array: the constants of the scene's kernels (the
    walk's first-class ``advance`` and ``start``, crank dynamics), for which
    numba compiles the mechanism's positions once, whatever the scene asks."""
    return np.array(constants(par), dtype=np.float64)


def revolution(par, phis, phi_close, order, tols, pos_out, d1_out, d2_out, status_out,
               margin_out, iters_out, fail_out):
    """The mechanism at the crank angles ``phis`` (rad) by continuation, watched
    between positions (pipeline.kernels.walk.walk_revolution: its outputs and
    status).  The walk is compiled once per installation; this module gives it
    ``advance`` and ``start`` as first-class functions and the constants of
    ``par`` as an array (for which numba compiles them once per mechanism)."""
    return scene_revolution(advance_first_class, start_first_class, constants_array(par),
                            WATCH_G, N_TRIADS, phis, phi_close, order, tols, pos_out, d1_out,
                            d2_out, status_out, margin_out, iters_out, fail_out)


@njit(**JIT_ALLOC)
def forces_curve(par, pos, d1, d2, omega1, eps1, loads, loads_out, r_out, slide_out, m_out):
    """forces_at every position k of pos/d1/d2 (n, n_points, 2); loads (n, n_loads, 3)."""
    work_a, work_b, _l, _r, _s = force_work(N_BODIES, N_JOINTS, N_SLIDES + N_INPUTS)
    for k in range(pos.shape[0]):
        m_out[k] = forces_at(par, pos[k], d1[k], d2[k], omega1, eps1, loads[k], work_a,
                             work_b, loads_out[k], r_out[k], slide_out[k])
