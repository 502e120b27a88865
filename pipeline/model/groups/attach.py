"""``attach``: a point fixed to a link.

Study fields: ``point`` (solved), ``base`` (known), ``along = [a, b]`` (the
link's vector; omit for a translating body: ``angle`` is then absolute),
``angle`` (deg), ``length`` (mm): point = base + rot(along, angle, length)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...base import limits as lim
from ...group_types import G_ATTACH
from ..group_base import GroupType, link_points


@dataclass(frozen=True)
class Attach(GroupType):
    """Point rigidly attached to a link: base + rot(along vector, angle, length);
    with along=None the direction is the absolute ``angle`` (translating body)."""
    point: str
    base: str
    along: tuple[str, str] | None
    angle: float
    length: float
    name: str = ""

    TYPE = "attach"
    SOLVES = ("point",)

    @classmethod
    def parse(cls, g, f, name):
        base = f.point(g, "base")
        along = f.pair(g, "along", optional=True)
        p = f.define(g, "point")
        return cls(p, base, along, math.radians(g.number("angle", 0.0, within=lim.ANGLE)),
                   g.number("length", positive=True, within=lim.LENGTH), name)

    def reads(self):
        return (self.base,) + (self.along or ())

    def writes(self):
        return (self.point,)

    def plan_row(self, pt):
        ia, ib = link_points(pt, self.along)
        return (G_ATTACH, [pt(self.base), ia, ib, pt(self.point)],
                [("angle", self.angle), ("length", self.length)])

    def segments(self):
        if not self.along:
            return []
        return [(self.base, self.point)] + ([(self.along[0], self.point)]
                                            if self.base not in self.along else [])

    def same_directions(self):
        return [((self.base, self.point), (self.along, self.angle))]

    def carried(self, pts):
        if self.base in pts and set(self.along or ()) <= pts:
            return (self.point,)
        return ()
