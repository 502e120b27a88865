"""Names of the generated source.

A study's names (points, groups, bodies, inputs) are the user's text: they
are data, never code.  Every identifier of a generated module is therefore
made from the plan's indices and the emitters' own keys: point ``i`` is
``I_i`` (its index constant) and ``p{i}x``/``p{i}y`` (its coordinates in the
lane path); parameter ``key`` of group ``g`` is ``g{g}_key`` (``PAR_g{g}_key``
its column); the coordinates of fixed point ``i`` are ``fix{i}_x``/``fix{i}_y``,
the mass data of body ``b`` ``body{b}_mass``/``body{b}_J_S``.  A user's name
appears only in comments, written by ``text`` (``ascii()``: one line of
printable ASCII, whatever the name holds), next to the definition it names,
so a reader of a generated kernel still sees which point ``I_3`` is.

The text helpers every writer of generated lines uses are here too: ``lane``
(a per-candidate constant in the lane path), ``literal`` (a float that reads
back to the same double) and ``wrap_line``.
"""

from __future__ import annotations

import math


# the point index constant of no point (a guide, line or link of fixed direction):
# an int64 value, like I_i, so that no library kernel compiles for a literal -1
NO_POINT = "NO_POINT"


def text(name) -> str:
    """A user's name as it may appear in the generated source: in a comment,
    quoted and escaped by ``ascii()`` (no line break, no quote that could end a
    string, no non-ASCII character such as U+2028 that some readers take for a
    line break)."""
    return ascii(str(name))


class Names:
    """Identifiers for the points, parameters and groups of one plan, from
    their indices (never from the names the user gave them)."""

    def __init__(self, plan):
        self.plan = plan
        par_names = plan.par_names
        owner: dict[int, str] = {}             # parameter index -> local identifier
        for i, off in zip(plan.fixed_idx, plan.fixed_off):
            owner[int(off)] = f"fix{int(i)}_x"
            owner[int(off) + 1] = f"fix{int(i)}_y"
        for b, off in enumerate(plan.body_mass_off):
            owner[int(off)] = f"body{b}_mass"
            owner[int(off) + 1] = f"body{b}_J_S"
        # each group's parameters: from its offset to the next group's, less the
        # bodies' mass data that follow a centre of mass; the key is the emitter's
        # (after "label."), checked to be an identifier of the code's own
        self.group_keys: list[list[str]] = []
        self._group_param: dict[tuple[int, str], str] = {}
        n_groups = len(plan.codes)
        for g in range(n_groups):
            lo = int(plan.goff[g])
            hi = int(plan.goff[g + 1]) if g + 1 < n_groups else len(par_names)
            prefix = plan.group_names[g] + "."
            keys = []
            for j in range(lo, hi):
                if j in owner:
                    continue
                name = par_names[j]
                key = name[len(prefix):] if name.startswith(prefix) else ""
                if not key.isidentifier() or not key.isascii():
                    raise ValueError(f"parameter {j} of group {g} ({text(name)}) has no "
                                     "key of the emitters")
                owner[j] = f"g{g}_{key}"
                self._group_param[(g, key)] = owner[j]
                keys.append(key)
            self.group_keys.append(keys)
        self.par_local = [owner.get(j, f"par{j}") for j in range(len(par_names))]

    # -- points
    def I(self, point: int) -> str:
        """Name of the constant holding the row of point ``point`` (its index) in
        pos/d1/d2."""
        return f"I_{int(point)}"

    def xy(self, point: int) -> str:
        """Stem of the lane path's locals of point ``point``: ``p3`` (p3x, p3y)."""
        return f"p{int(point)}"

    # -- parameters
    def par(self, j: int) -> str:
        """Local name of parameter ``j`` of the row (``PAR_`` + it: its column)."""
        return self.par_local[int(j)]

    def K(self, g: int, key: str) -> str:
        """Local name of a per-candidate constant of group ``g``: its parameter
        ``key``, or a constant derived from them (``key`` is the emitter's)."""
        if not (key.isidentifier() and key.isascii()):
            raise ValueError(f"{key!r} is not an emitter's key")
        return self._group_param.get((int(g), key), f"g{int(g)}_{key}")


def lane(name: str) -> str:
    """A per-candidate constant in the lane path: row R_name of the block's
    constants, this lane."""
    return f"S[R_{name}, l]"


def literal(x: float) -> str:
    """A float as Python source that reads back to the same double."""
    if math.isnan(x):
        return "math.nan"
    if math.isinf(x):
        return "math.inf" if x > 0 else "-math.inf"
    return repr(float(x))


def wrap_line(s, width=95):
    """Break a long tuple line at commas (inside the parentheses)."""
    if len(s) <= width:
        return s
    parts = s.split(", ")
    lines, cur = [], ""
    for p in parts:
        if cur and len(cur) + len(p) + 2 > width:
            lines.append(cur + ",")
            cur = "        " + p
        else:
            cur = p if not cur else cur + ", " + p
    lines.append(cur)
    return "\n".join(lines)
