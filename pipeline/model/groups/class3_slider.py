"""``class3`` with ``slider``: the triad with a block at vertex 5 sliding on a
guide in place of lead 5-7.

Study fields: as ``class3`` (``pipeline.model.groups.class3``) without ``pivot_5``
and ``L57``, and ``slider = { point, angle, offset, link }``: the guide runs
through the known ``point`` at ``angle`` (deg: absolute, or relative to
``link = [a, b]``), vertex 5 at ``offset`` (mm) from it on the side of the
direction turned +90 deg (parameters ``guide_angle``, ``guide_offset``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...base import limits as lim
from ...kernels import config as kc
from .base import GroupType, guide_words, host, link_points


def parse_slider(g, f):
    """The ``slider`` table of a class III group whose lead 5-7 is a block on a
    guide: (guide point, angle rad, offset mm, guide link or None).  The table
    replaces ``pivot_5`` and ``L57``."""
    for key in ("pivot_5", "L57"):
        if g.has(key):
            raise g.error(key, "a class III group with a slider has no lead 5-7: the slider "
                               "table (point, angle, offset) takes the place of pivot_5 and L57")
    s = g.table("slider")
    point = f.point(s, "point")
    link = f.pair(s, "link", optional=True)
    angle = math.radians(s.number("angle", within=lim.ANGLE))
    offset = s.number("offset", 0.0, within=lim.OFFSET)
    s.done()
    return point, angle, offset, link


@dataclass(frozen=True)
class ClassIIISlider(GroupType):
    """The class III group with a slider in place of lead 5-7: lead 2-3 from
    ``input``, the ternary link 3-4-5, lead 4-6 to ``pivot_4``, and a block
    pinned at vertex 5 that slides on a guide line.

    The guide runs through the known point ``guide_point`` with the absolute
    direction ``guide_angle``, or, with ``guide_link`` = (a, b), the direction
    of the link a->b plus ``guide_angle``; the block carries vertex 5 at the
    perpendicular distance ``guide_offset`` from the guide, on the side of its
    direction turned +90 deg (the convention of RRP, PRP and RPP).  Unknowns,
    start guess and branch as ``ClassIII``."""
    input: str
    pivot_4: str
    guide_point: str
    joints: tuple[str, str, str]   # names of vertices 3, 4, 5
    L23: float
    L34: float
    L45: float
    L35: float
    L46: float
    guide_angle: float             # rad: absolute, or relative to guide_link
    guide_offset: float            # mm
    a0: float                      # start guess at phi_start, rad
    b0: float
    phi_start: float = 0.0
    orientation: int = 1           # sign of U435
    guide_link: tuple[str, str] | None = None
    name: str = "triad"

    TYPE = "class3"      # a class3 table with a slider table: read by ClassIII.parse
    EMITTER = "ClassIIISliderEmitter"
    SOLVES_LISTS = ("joints",)

    def reads(self):
        return (self.input, self.pivot_4, self.guide_point) + (self.guide_link or ())

    def writes(self):
        return self.joints

    def plan_row(self, pt):
        ga, gb = link_points(pt, self.guide_link)
        return (kc.G_CLASS3_SLIDER, [pt(self.input), pt(self.pivot_4), pt(self.guide_point)]
                + [pt(j) for j in self.joints] + [ga, gb],
                [("L23", self.L23), ("L34", self.L34), ("L45", self.L45), ("L35", self.L35),
                 ("L46", self.L46), ("guide_angle", self.guide_angle),
                 ("guide_offset", self.guide_offset), ("orientation", self.orientation),
                 ("a0", self.a0), ("b0", self.b0), ("phi_start", self.phi_start)])

    def segments(self):
        p3, p4, p5 = self.joints
        # (no segment for the block: a line from the guide point would read as a lead)
        return [(self.input, p3), (p3, p4), (p4, p5), (p5, p3), (self.pivot_4, p4)]

    def guides(self, fixed):
        link, angle = self.guide_link, self.guide_angle
        return [(self.joints[2], (link, angle), host(self.guide_point, link, fixed),
                 guide_words(link, angle), ("guide_angle",))]

    def same_directions(self):
        if self.guide_offset == 0.0:
            return [((self.guide_point, self.joints[2]), (self.guide_link, self.guide_angle))]
        return []
