"""PRP: two blocks joined by the revolute B, each sliding on a known guide (a
slot in a rocker and the frame's guide: a slotted-lever drive; the double
slider).

Study fields: ``B`` (solved); per guide i = 1, 2: ``guide{i}_point`` (a known
point of its line), ``guide{i}_angle`` (deg: absolute, or relative to
``guide{i}_link = [a, b]``), ``guide{i}_offset`` (mm: the pin's distance from
the guide's line, on the side of the direction turned +90 deg).  Two absolute
guides may not be parallel."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...base import limits as lim
from ...model.group_base import PARALLEL_SIN, GroupType, guide_words, host, link_points
from . import G_PRP


@dataclass(frozen=True)
class PRP(GroupType):
    """Two blocks joined by the revolute B, each sliding on a known guide.

    Guide i runs through the known point ``guide{i}_point`` with the absolute
    direction ``guide{i}_angle``, or, with ``guide{i}_link`` = (a, b), with the
    direction of the link a->b plus ``guide{i}_angle`` (a slot in that link);
    block i carries B at the perpendicular distance ``guide{i}_offset`` from
    its guide, on the side of the guide's direction turned +90 deg.  B is
    where the two lines meet; the group cannot be assembled where the guides
    are parallel."""
    B: str
    guide1_point: str
    guide1_angle: float          # rad: absolute, or relative to guide1_link
    guide2_point: str
    guide2_angle: float
    guide1_offset: float = 0.0   # mm
    guide2_offset: float = 0.0
    guide1_link: tuple[str, str] | None = None
    guide2_link: tuple[str, str] | None = None
    name: str = ""

    TYPE = "PRP"
    SOLVES = ("B",)

    @classmethod
    def parse(cls, g, f, name):
        guides = []
        for i in (1, 2):
            gp = f.point(g, f"guide{i}_point")
            link = f.pair(g, f"guide{i}_link", optional=True)
            angle = g.number(f"guide{i}_angle", 0.0, within=lim.ANGLE)
            guides.append((gp, link, math.radians(angle),
                           g.number(f"guide{i}_offset", 0.0, within=lim.OFFSET)))
        if guides[0][1] is None and guides[1][1] is None and \
                abs(math.sin(guides[1][2] - guides[0][2])) < PARALLEL_SIN:
            raise g.error("guide2_angle", "the two guides are parallel (guide1_angle = "
                          f"{math.degrees(guides[0][2]):g} deg, guide2_angle = "
                          f"{math.degrees(guides[1][2]):g} deg): the blocks' lines never "
                          "meet in one point")
        b = f.define(g, "B")
        return cls(b, guides[0][0], guides[0][2], guides[1][0], guides[1][2],
                   guides[0][3], guides[1][3], guides[0][1], guides[1][1], name)

    def reads(self):
        return ((self.guide1_point,) + (self.guide1_link or ()) + (self.guide2_point,)
                + (self.guide2_link or ()))

    def writes(self):
        return (self.B,)

    def _lines(self):
        return ((self.guide1_point, self.guide1_link, self.guide1_angle, self.guide1_offset),
                (self.guide2_point, self.guide2_link, self.guide2_angle, self.guide2_offset))

    def plan_row(self, pt):
        links = []
        for link in (self.guide1_link, self.guide2_link):
            links += link_points(pt, link)
        return (G_PRP, [pt(self.guide1_point), links[0], links[1], pt(self.guide2_point),
                           links[2], links[3], pt(self.B)],
                [("guide1_angle", self.guide1_angle), ("guide1_offset", self.guide1_offset),
                 ("guide2_angle", self.guide2_angle), ("guide2_offset", self.guide2_offset)])

    def transmission(self):
        """Block 1 passes the force to the pin along the normal of guide 1, and
        block 2 moves along guide 2 (either way round), so mu = the angle between
        the two guides (0 where they are parallel; sin mu is the group's margin)."""
        a1, b1 = self.guide1_link or (None, None)
        a2, b2 = self.guide2_link or (None, None)
        return [(self.name or f"PRP {self.B}", "lines",
                 ((a1, b1, self.guide1_angle), (a2, b2, self.guide2_angle)))]

    def segments(self):
        return [(p, self.B) for p in (self.guide1_point, self.guide2_point) if p != self.B]

    def guides(self, fixed):
        return [(self.B, (link, angle), host(gp, link, fixed),
                 f"on guide {i} {guide_words(link, angle)}", (f"guide{i}_angle",))
                for i, (gp, link, angle, _off) in enumerate(self._lines(), start=1)]

    def same_directions(self):
        return [((gp, self.B), (link, angle)) for gp, link, angle, off in self._lines()
                if off == 0.0]


# the study types this folder declares (``pipeline.model.groups.GROUP_TYPES``)
STUDY_TYPES = (PRP,)
