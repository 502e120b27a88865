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
from ...kernels import config as kc
from .base import GroupType
from .class3_slider import ClassIIISlider, parse_slider


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
    EMITTER = "ClassIIIEmitter"
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
        return (kc.G_CLASS3, [pt(self.input), pt(self.pivot_4), pt(self.pivot_5)]
                + [pt(j) for j in self.joints],
                [("L23", self.L23), ("L34", self.L34), ("L45", self.L45), ("L35", self.L35),
                 ("L46", self.L46), ("L57", self.L57), ("orientation", self.orientation),
                 ("a0", self.a0), ("b0", self.b0), ("phi_start", self.phi_start)])

    def transmission(self):
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
