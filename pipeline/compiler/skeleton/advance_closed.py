"""``advance`` of a mechanism without class III groups: one closed-form solve.

The text below the marker line is pasted into the generated module
(``pipeline.compiler.generate``); the imports above it declare, for linters and
readers, the names the generated module gives it."""

from .header import (njit, JIT_INNER)
from ._mechanism import (N_GROUPS, position)

# ---- the skeleton: from here on, pasted into the generated module ----
@njit(**JIT_INNER)
def advance(K, phi_from, phi_to, order, tols, state, pos, d1, d2, margins, with_com):
    """Closed form (no class III group): one solve at ``phi_to`` (margins[N_GROUPS
    + 1], margins[N_GROUPS + 2]: where the walk was and where it went)."""
    margins[N_GROUPS + 1] = phi_from
    margins[N_GROUPS + 2] = phi_to
    return position(K, phi_to, order, tols, state, pos, d1, d2, margins, with_com)
