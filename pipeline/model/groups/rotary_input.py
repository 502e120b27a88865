"""``rotary_input``: a link turned about a fixed pivot by a law of the cycle
angle: an oscillating rocker on a cam, or a second crank geared to the first.

Study fields: ``pivot`` (fixed), ``tip`` (solved: pivot + ``length`` (mm) at
the law's absolute angle), ``length``, ``law`` (``pipeline.model.groups.law``)."""

from __future__ import annotations

from dataclasses import dataclass

from ...base import limits as lim
from .law import Input, Law


@dataclass(frozen=True)
class RotaryInput(Input):
    """A link turned about the fixed ``pivot`` to the absolute angle given by
    ``law`` of the cycle angle: ``tip`` = pivot + length e(q(phi1)).  An
    oscillating rocker driven by a cam, or a second crank geared to the
    first (linear law)."""
    pivot: str
    tip: str
    length: float
    law: Law
    name: str = ""

    TYPE = "rotary_input"
    ROTARY = True
    ENDS = ("pivot", "tip")
    SOLVES = ("tip",)

    @classmethod
    def parse(cls, g, f, name):
        p0, p1, law = cls.parse_ends(g, f)
        return cls(p0, p1, g.number("length", positive=True, within=lim.LENGTH), law, name)

    def first_parameters(self):
        return [("length", self.length)]

    def driven_body(self, mech):
        """The body jointed at the pivot and the tip."""
        for i, b in enumerate(mech.bodies):
            if self.pivot in b.joints and self.tip in b.joints:
                return i
        return -1
