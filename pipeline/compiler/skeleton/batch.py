"""The scene's batch of a generated module: ``batch`` (full kinematics, and forces,
of many candidates, reduced to peaks).

The text below the marker line is pasted into the generated module
(``pipeline.compiler.generate``); the imports above it declare, for linters and
readers, the names the generated module gives it."""

from .header import (math, np, njit, JIT_ALLOC, OK, work, force_work)
from ._mechanism import (N_POINTS, N_GROUPS, N_TRIADS, N_BODIES, N_JOINTS, N_SLIDES,
                         N_INPUTS, N_WATCH, WATCH_G, constants, advance, forces_at)
from ...kernels.walk import walk_start, watch, watch_work

# ---- the skeleton: from here on, pasted into the generated module ----
@njit(**JIT_ALLOC)
def batch(pars, lo, hi, phis, order, tols, point, with_forces, omega1, eps1, loads, status,
          peak_acc, peak_reaction):
    """For each parameter row: status over the revolution (watched between
    positions, without the closing position), the peak acceleration analog
    |r''| of ``point`` (mm/rad^2) and, with_forces, the peak joint reaction
    (N).  NaN peaks with an OK status would be an unflagged failure (the
    stress suite checks there are none).  Rows lo .. hi - 1; the caller runs
    ranges on threads."""
    pos, d1, d2, margins, state, _ = work(N_POINTS, N_GROUPS, N_TRIADS)
    work_a, work_b, loads_out, r_out, slide_out = force_work(N_BODIES, N_JOINTS,
                                                             N_SLIDES + N_INPUTS)
    ww = watch_work(N_WATCH, N_TRIADS)
    for i in range(lo, hi):
        par = pars[i]
        K = constants(par)
        phi_prev = walk_start(K, phis[0], state)
        st = OK
        acc = 0.0
        peak = 0.0
        finite = True
        for k in range(phis.shape[0]):
            s = advance(K, phi_prev, phis[k], order, tols, state, pos, d1, d2, margins,
                        np.bool_(True))
            phi_prev = phis[k]
            if s != OK:
                st = s
                break
            a = math.hypot(d2[point, 0], d2[point, 1])
            finite = finite and math.isfinite(a)
            acc = max(acc, a)
            if with_forces:
                forces_at(par, pos, d1, d2, omega1, eps1, loads[k], work_a, work_b,
                          loads_out, r_out, slide_out)
                for j in range(N_JOINTS):
                    r = math.hypot(r_out[j, 0], r_out[j, 1])
                    finite = finite and math.isfinite(r)
                    peak = max(peak, r)
            s = watch(K, WATCH_G, k, phis[k], tols, state, pos, d1, d2, margins, ww)
            if s != OK:     # a failure between positions
                st = s
                break
        status[i] = st
        peak_acc[i] = acc if (st == OK and finite) else math.nan
        peak_reaction[i] = peak if (st == OK and with_forces) else math.nan
