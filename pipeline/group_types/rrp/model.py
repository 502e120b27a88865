"""RRP: slider B on a guide line, joined to known A by link A-B.

Study fields: ``A`` (known), ``B`` (solved), ``guide_point`` (known),
``guide_angle`` (deg: absolute, or relative to ``guide_link = [a, b]``, a
guide turning with that link), ``L_AB`` (mm), ``W`` (side along the guide)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...base import limits as lim
from ...model.group_base import HALF, GroupType, guide_words, host, link_points
from . import G_RRP


@dataclass(frozen=True)
class RRP(GroupType):
    """Slider B on a guide line through G (fixed direction, or turning with the
    link guide_link), joined to known A by link A-B; mode W = side along the guide."""
    A: str
    B: str
    guide_point: str
    guide_angle: float       # rad: absolute, or relative to guide_link
    L_AB: float
    W: int
    guide_link: tuple[str, str] | None = None
    name: str = ""

    TYPE = "RRP"
    SOLVES = ("B",)

    @classmethod
    def parse(cls, g, f, name):
        a, gp = f.point(g, "A"), f.point(g, "guide_point")
        link = f.pair(g, "guide_link", optional=True)
        b = f.define(g, "B")
        return cls(a, b, gp, math.radians(g.number("guide_angle", 0.0, within=lim.ANGLE)),
                   g.number("L_AB", positive=True, within=lim.LENGTH), f.mode(g), link, name)

    def reads(self):
        return (self.A, self.guide_point) + (self.guide_link or ())

    def writes(self):
        return (self.B,)

    def plan_row(self, pt):
        ga, gb = link_points(pt, self.guide_link)
        return (G_RRP, [pt(self.A), pt(self.guide_point), pt(self.B), ga, gb],
                [("L_AB", self.L_AB), ("guide_angle", self.guide_angle), ("W", self.W)])

    def transmission(self):
        """The force along A-B drives the slider along the guide, so mu = 90 deg -
        angle(A-B, guide) = the angle between A-B and the guide's normal (the
        slider-crank's: coupler against the normal to the slider's path); 0 where
        A-B lies across the guide, the group's toggle (its margin is sin mu)."""
        ga, gb = self.guide_link or (None, None)
        return [(self.name or f"RRP {self.A}-{self.B}", "lines",
                 ((self.A, self.B, 0.0), (ga, gb, self.guide_angle + HALF)))]

    def segments(self):
        return [(self.A, self.B)]

    def guides(self, fixed):
        return [(self.B, (self.guide_link, self.guide_angle),
                 host(self.guide_point, self.guide_link, fixed),
                 guide_words(self.guide_link, self.guide_angle), ("guide_angle",))]

    def same_directions(self):
        return [((self.guide_point, self.B), (self.guide_link, self.guide_angle))]


# the study types this folder declares (``pipeline.model.groups.GROUP_TYPES``)
STUDY_TYPES = (RRP,)
