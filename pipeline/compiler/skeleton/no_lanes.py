"""The lane kernels of a generated module without a lane path (no output rocker
declared, or a group without a lane form): ``setup_lane`` sends every candidate
to the careful path.  ``pipeline.compiler.lanes`` fills in {why}.

The text below the marker line is pasted into the generated module
(``pipeline.compiler.generate``); the imports above it declare, for linters and
readers, the names the generated module gives it."""

from .header import (njit, JIT, JIT_INNER)

# ---- the skeleton: from here on, pasted into the generated module ----
@njit(**JIT)
def setup_lane(pars, i, l, phis, close, tols, S, theta, pos, d1, d2, margins, state,
               called):
    """{why}: every candidate takes the careful path."""
    return -1


@njit(**JIT)
def block_walk(S, theta, cph_tab, sph_tab, phis, tols, settings, called):
    return


@njit(**JIT_INNER)
def lanes_apply(phis, tols):
    return False
