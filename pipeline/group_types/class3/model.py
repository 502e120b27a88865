"""``class3``: the triad of DOMAIN.md section 5 (lead 2-3 from a known point,
the ternary link 3-4-5, leads 4-6 and 5-7 to fixed pivots), solved by Newton
from a start guess and continued along the revolution.

Study fields: ``input`` (known P2), ``pivot_4``, ``pivot_5`` (known),
``joints`` (the solved vertices 3, 4, 5), ``L23``, ``L34``, ``L45``, ``L35``,
``L46``, ``L57`` (mm; 3-4-5 a triangle), ``start`` ([a, b] deg: the start
guess at ``phi_start``), ``phi_start`` (deg), ``orientation`` (+-1).  With a
``slider`` table in place of ``pivot_5`` and ``L57`` it is a
``ClassIIISlider`` (``pipeline.model.groups.class3_slider``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...base import limits as lim
from ...model.group_base import GroupType, guide_words, host, link_points
from . import G_CLASS3, G_CLASS3_SLIDER


@dataclass(frozen=True)
class ClassIII(GroupType):
    """Triad of DOMAIN.md sections 3 and 5 (lead 2-3, ternary 3-4-5, leads 4-6, 5-7)."""
    input: str
    pivot_4: str
    pivot_5: str
    joints: tuple[str, str, str]   # names of vertices 3, 4, 5
    L23: float
    L34: float
    L45: float
    L35: float
    L46: float
    L57: float
    a0: float                      # start guess at phi_start, rad
    b0: float
    phi_start: float = 0.0
    orientation: int = 1           # sign of U435
    name: str = "triad"

    TYPE = "class3"
    SOLVES_LISTS = ("joints",)

    @classmethod
    def parse(cls, g, f, name):
        inp, p6 = f.point(g, "input"), f.point(g, "pivot_4")
        slider = parse_slider(g, f) if g.has("slider") else None
        if slider is None and not g.has("pivot_5"):
            raise g.error("pivot_5", "required field is missing (or, for a block on a "
                                     "guide in place of lead 5-7, a slider table)")
        p7 = f.point(g, "pivot_5") if slider is None else None
        joints = g.names("joints", n=3)
        for p in joints:
            f.define(g, "joints", p)
        start = g.numbers("start", n=2, within=lim.ANGLE)
        leads = ("L23", "L34", "L45", "L35", "L46") + (("L57",) if slider is None else ())
        L = {k: g.number(k, positive=True, within=lim.LENGTH) for k in leads}
        if not (L["L45"] < L["L34"] + L["L35"] and L["L34"] < L["L45"] + L["L35"]
                and L["L35"] < L["L34"] + L["L45"]):
            raise g.error("L45", "the ternary link 3-4-5 is not a triangle "
                                 f"(L34={L['L34']:g}, L45={L['L45']:g}, L35={L['L35']:g})")
        common = dict(a0=math.radians(start[0]), b0=math.radians(start[1]),
                      phi_start=math.radians(g.number("phi_start", 0.0, within=lim.ANGLE)),
                      orientation=g.integer("orientation", 1, choices=(-1, 1)),
                      name=name or "triad")
        if slider is None:
            return cls(inp, p6, p7, joints, **L, **common)
        point, angle, offset, link = slider
        return ClassIIISlider(inp, p6, point, joints, **L, guide_angle=angle,
                              guide_offset=offset, guide_link=link, **common)

    def reads(self):
        return (self.input, self.pivot_4, self.pivot_5)

    def writes(self):
        return self.joints

    def plan_row(self, pt):
        return (G_CLASS3, [pt(self.input), pt(self.pivot_4), pt(self.pivot_5)]
                + [pt(j) for j in self.joints],
                [("L23", self.L23), ("L34", self.L34), ("L45", self.L45), ("L35", self.L35),
                 ("L46", self.L46), ("L57", self.L57), ("orientation", self.orientation),
                 ("a0", self.a0), ("b0", self.b0), ("phi_start", self.phi_start)])

    def transmission(self):
        """Each lead that joins the ternary link at J to a fixed pivot P (leads 4-6
        and 5-7; "lead", (J, P, A, B, C, D)): the angle at J between the lead J-P
        and the line from J through Q, the point where the lines A-B and C-D of
        the other two leads meet.  With axial forces in those leads, the ternary
        link (three forces in equilibrium meet in one point) passes its force to
        this lead along J-Q: the four-bar's transmission angle (coupler against
        rocker) generalised.  It is 0 when the three leads' lines meet in one
        point, the group's singular position."""
        p3, p4, p5 = self.joints
        label = self.name or "class III"
        return [(f"{label} lead {p4}-{self.pivot_4}", "lead",
                 (p4, self.pivot_4, self.input, p3, p5, self.pivot_5)),
                (f"{label} lead {p5}-{self.pivot_5}", "lead",
                 (p5, self.pivot_5, self.input, p3, p4, self.pivot_4))]

    def segments(self):
        p3, p4, p5 = self.joints
        return [(self.input, p3), (p3, p4), (p4, p5), (p5, p3), (self.pivot_4, p4),
                (self.pivot_5, p5)]


# ``class3`` with ``slider``: the triad with a block at vertex 5 sliding on a
# guide in place of lead 5-7.
# 
# Study fields: as ``class3`` (``pipeline.model.groups.class3``) without ``pivot_5``
# and ``L57``, and ``slider = { point, angle, offset, link }``: the guide runs
# through the known ``point`` at ``angle`` (deg: absolute, or relative to
# ``link = [a, b]``), vertex 5 at ``offset`` (mm) from it on the side of the
# direction turned +90 deg (parameters ``guide_angle``, ``guide_offset``).


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
    direction turned +90 deg (the convention of every guide).  Unknowns,
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
    SOLVES_LISTS = ("joints",)

    def reads(self):
        return (self.input, self.pivot_4, self.guide_point) + (self.guide_link or ())

    def writes(self):
        return self.joints

    def plan_row(self, pt):
        ga, gb = link_points(pt, self.guide_link)
        return (G_CLASS3_SLIDER, [pt(self.input), pt(self.pivot_4), pt(self.guide_point)]
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


# the study types this folder declares (``pipeline.model.groups.GROUP_TYPES``)
STUDY_TYPES = (ClassIII,)
# and the classes their parsers may build in their place
BUILT = (ClassIIISlider,)
