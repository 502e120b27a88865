"""The force lanes of a generated module whose force stage has no lane form
(``pipeline.compiler.lane_forces`` or, without an output rocker,
``generate`` fills in {why}): every candidate takes the scalar force stage.

The text below the marker line is pasted into the generated module
(``pipeline.compiler.lane_forces``); the imports above it declare, for linters
and readers, the names the generated module gives it."""

from .header import (njit, JIT)

# ---- the skeleton: from here on, pasted into the generated module ----
# ---- the force stage in lanes: none ({why}) ----
HAS_LANE_FORCES = False
SAME_BITS = False
N_FROWS = 1
FT_COLS = 1
N_RCOLS = 1


@njit(**JIT)
def lane_forces_apply(settings):
    return False


@njit(**JIT)
def force_lane_in(par, l, trail, FS, FT, phis, crank_tab):
    return


@njit(**JIT)
def force_flush(fidx, filled, FS, FT, RB, phis, tols, settings, loads, status, metrics,
                called):
    return


@njit(**JIT)
def force_refused(pars, fidx, filled, FS, FT, phis, phi_close, tols, settings, loads, col,
                  trail, qmax, qmin, wk, fw, ww, corr, status, metrics, settle_at,
                  called):
    return
