"""The RPP dyad's (the Scotch yoke's, and PPR's: the same chain, the same plan
row) lines of the generated module (the hooks of
``pipeline.compiler.emit.Emitter``): the careful path by its library kernel,
the lane form (where the guide and the slot meet), the force lanes' lines, and
its instances in the library's warm-up mechanism."""

from __future__ import annotations

import math

from ...compiler.emit import TO_ROUNDING, Emitter, guide_link, guide_words
from ...compiler.lane_force_groups import direction_lines, from_position_lanes, meet_lines
from ...compiler.lane_geometry import hoisted_cos_sin, lane_direction, lane_meet
from ...compiler.names import lane
from . import G_RPP
from .model import PPR, RPP


class RPPEmitter(Emitter):
    watched = True
    code = G_RPP
    force_lanes = TO_ROUNDING
    fast = True

    def derived(self):
        return hoisted_cos_sin(self, "guide_angle", "slot_angle")

    def lanes(self):
        # kernels.rpp: the guide's line through G at guide_offset, and the
        # slot's line through A (the guide's direction turned by slot_angle) at
        # -slot_offset
        cs, ss = lane(f"{self.k('slot_angle')}_cos"), lane(f"{self.k('slot_angle')}_sin")
        return ([f"# {self.title()}: {self.xy(4)} where the guide and the slot through "
                 f"{self.xy(0)} meet"]
                + lane_direction(self, "u1", "guide_angle", 2)
                + [f"u2x = {cs} * u1x - {ss} * u1y", f"u2y = {ss} * u1x + {cs} * u1y"]
                + lane_meet(self.xy(1), lane(self.k("guide_offset")), self.xy(0),
                             f"-{lane(self.k('slot_offset'))}", self.xy(4)))

    def careful(self):
        ga, gb = guide_link(self, 2)
        k = self.k
        return [f"# {self.title()}: yoke point {self.pname(4)} on the guide",
                f"# {guide_words(self, 1, 2, 'guide_angle')}, its slot through the block "
                f"at {self.pname(0)}",
                f"st, m = rpp(pos, d1, d2, {self.p(0)}, {self.p(1)}, {ga}, {gb}, {self.p(4)}, "
                f"{k('guide_angle')}, {k('guide_offset')}, {k('slot_angle')}, "
                f"{k('slot_offset')}, order, sing)"]

    def transmission_items(self):
        ga, gb, g = self.ix[2], self.ix[3], self.k("guide_angle")
        return "the angle between the slot and the guide", [
            ("lines", (ga, gb, g, ga, gb, f"{g} + {self.k('slot_angle')}"))]

    def force_lines(self, c, t):
        cs, ss = lane(f"{self.k('slot_angle')}_cos"), lane(f"{self.k('slot_angle')}_sin")
        return (direction_lines(self, "u1", "t1", "guide_angle", 2)
                + from_position_lanes([f"u2x = {cs} * u1x - {ss} * u1y",
                                       f"u2y = {ss} * u1x + {cs} * u1y"])
                + ["t21 = t11", "t22 = t12"]
                + meet_lines(self.ix[1], lane(self.k("guide_offset")), self.ix[0],
                             f"-{lane(self.k('slot_offset'))}", self.ix[4]))


EMITTERS = (RPPEmitter,)


def warmup(tip):
    """Its groups in the library's warm-up mechanism (``pipeline.compiler.warmup``),
    on points of its own and the crank's ``tip``, declared either way: (fixed
    points, groups)."""
    return {"RPP_G": (0.0, 60.0)}, (
        RPP(A=tip, B="RPP_B", guide_point="P1", guide_angle=0.0, slot_angle=math.radians(90.0)),
        PPR(pin=tip, B="PPR_B", guide_point="RPP_G", guide_angle=0.0,
            slot_angle=math.radians(60.0)))
