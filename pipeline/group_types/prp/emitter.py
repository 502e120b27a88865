"""The PRP dyad's lines of the generated module (the hooks of
``pipeline.compiler.emit.Emitter``): the careful path by its library kernel,
the lane form (where the two guide lines meet), the force lanes' lines, and
its instance in the library's warm-up mechanism."""

from __future__ import annotations

from ...compiler.emit import TO_ROUNDING, Emitter, guide_link, guide_words
from ...compiler.lane_force_groups import direction_lines, meet_lines
from ...compiler.lane_geometry import hoisted_cos_sin, lane_direction, lane_meet
from ...compiler.names import lane
from . import G_PRP
from .model import PRP


class PRPEmitter(Emitter):
    watched = True
    code = G_PRP
    force_lanes = TO_ROUNDING
    fast = True

    def derived(self):
        # the lane form turns unit vectors by the guides' angles: their cos/sin, hoisted
        return hoisted_cos_sin(self, "guide1_angle", "guide2_angle")

    def lanes(self):
        return ([f"# {self.title()}: {self.xy(6)} where the two guide lines meet"]
                + lane_direction(self, "u1", "guide1_angle", 1)
                + lane_direction(self, "u2", "guide2_angle", 4)
                + lane_meet(self.xy(0), lane(self.k("guide1_offset")), self.xy(3),
                             lane(self.k("guide2_offset")), self.xy(6)))

    def careful(self):
        a1, b1 = guide_link(self, 1)
        a2, b2 = guide_link(self, 4)
        k = self.k
        return [f"# {self.title()}: {self.pname(6)} where the guide lines of two blocks meet",
                "# (linear: B from a 2x2 system);",
                f"# guide 1 {guide_words(self, 0, 1, 'guide1_angle')},",
                f"# guide 2 {guide_words(self, 3, 4, 'guide2_angle')}",
                f"st, m = prp(pos, d1, d2, {self.p(0)}, {a1}, {b1}, {self.p(3)}, {a2}, {b2}, "
                f"{self.p(6)}, {k('guide1_angle')}, {k('guide1_offset')}, {k('guide2_angle')}, "
                f"{k('guide2_offset')}, order, sing)"]

    def transmission_items(self):
        return "the angle between the two guides", [
            ("lines", (self.ix[1], self.ix[2], self.k("guide1_angle"), self.ix[4], self.ix[5],
                       self.k("guide2_angle")))]

    def force_lines(self, c, t):
        return (direction_lines(self, "u1", "t1", "guide1_angle", 1)
                + direction_lines(self, "u2", "t2", "guide2_angle", 4)
                + meet_lines(self.ix[0], lane(self.k("guide1_offset")), self.ix[3],
                             lane(self.k("guide2_offset")), self.ix[6]))


EMITTERS = (PRPEmitter,)


def warmup(tip):
    """Its groups in the library's warm-up mechanism (``pipeline.compiler.warmup``),
    on points of its own, guide 1 turning with the crank: (fixed points, groups)."""
    return {"PRP_G1": (38.0, 0.0), "PRP_G2": (38.0, 50.0)}, (
        PRP(B="PRP_B", guide1_point="PRP_G1", guide1_angle=0.0, guide2_point="PRP_G2",
            guide2_angle=0.0, guide1_link=("P1", tip)),)
