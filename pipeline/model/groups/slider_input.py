"""``slider_input``: a block moved along a fixed guide by a law of the cycle
angle: a linear actuator.

Study fields: ``guide_point`` (fixed), ``guide_angle`` (deg, absolute),
``block`` (solved: guide_point + the law's stroke along the guide), ``law``
(``pipeline.model.groups.law``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...base import limits as lim
from ..group_base import guide_words
from .law import Input, Law


@dataclass(frozen=True)
class SliderInput(Input):
    """A block moved along a fixed guide by ``law`` of the cycle angle: the
    guide runs through the fixed ``guide_point`` at the absolute direction
    ``guide_angle``; ``block`` = guide_point + q(phi1) e(guide_angle).  A
    linear actuator with a stroke law."""
    guide_point: str
    block: str
    guide_angle: float
    law: Law
    name: str = ""

    TYPE = "slider_input"
    ROTARY = False
    ENDS = ("guide_point", "block")
    SOLVES = ("block",)

    @classmethod
    def parse(cls, g, f, name):
        p0, p1, law = cls.parse_ends(g, f)
        angle = g.number("guide_angle", 0.0, within=lim.ANGLE)
        return cls(p0, p1, math.radians(angle), law, name)

    def first_parameters(self):
        return [("guide_angle", self.guide_angle)]

    def driven_body(self, mech):
        """The body that slides on the ground at the block."""
        for i, b in enumerate(mech.bodies):
            if self.block in b.joints and any(s.slider == b.name and s.guide is None
                                              for s in mech.slides):
                return i
        return -1

    def guides(self, fixed):
        return [(self.block, (None, self.guide_angle), None,
                 guide_words(None, self.guide_angle), ("guide_angle",))]

    def same_directions(self):
        return [((self.guide_point, self.block), (None, self.guide_angle))]
