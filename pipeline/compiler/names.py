"""Names of the generated source: Python identifiers derived from the plan's
point and parameter names, so a reader of a generated kernel sees ``P3`` and
``triad_L34`` rather than array offsets."""

from __future__ import annotations

import keyword
import re


def ident(label: str) -> str:
    """A Python identifier for a plan label: 'S[crank].length' -> 'S_crank_length'."""
    s = re.sub(r"[^0-9A-Za-z]+", "_", label).strip("_") or "x"
    if s[0].isdigit():
        s = "n" + s
    if keyword.iskeyword(s):
        s += "_"
    return s


class Names:
    """Unique identifiers for the points and parameters of one plan."""

    def __init__(self, plan):
        self.plan = plan
        taken: set[str] = set()

        def unique(base):
            name, k = base, 2
            while name in taken:
                name, k = f"{base}_{k}", k + 1
            taken.add(name)
            return name

        self.point = {p: unique(ident(p)) for p in plan.point_names}
        self.param = {p: unique(ident(p)) for p in plan.par_names}

    def I(self, point: str) -> str:
        """Name of the constant holding the index of ``point`` in pos/d1/d2."""
        return "I_" + self.point[point]

    def P(self, index: int) -> str:
        return self.I(self.plan.point_names[index])

    def K(self, group_label: str, key: str) -> str:
        """Local name of a per-candidate constant: a parameter of the row, or a
        constant derived from them (named after its group)."""
        label = f"{group_label}.{key}"
        return self.param[label] if label in self.param else ident(label)
