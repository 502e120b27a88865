"""RPP (Scotch yoke): a block pinned at a known point A slides in a slot of a
yoke that slides on a guide.

Study fields: ``A`` (known), ``B`` (solved: the yoke's point on its guide
where the slot's centre line crosses it), ``guide_point`` (known),
``guide_angle`` (deg: absolute, or relative to ``guide_link = [a, b]``),
``guide_offset`` (mm: B's distance from the guide's line), ``slot_angle``
(deg: the slot in the yoke, from the guide; default 90), ``slot_offset`` (mm:
A's distance from the slot's line through B).  The slot may not run along the
guide.  A PPR (``pipeline.model.groups.ppr``) is this chain read from its other end."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...base import limits as lim
from ...kernels import config as kc
from .base import PARALLEL_SIN, GroupType, deg, guide_words, host, link_points


def parse_yoke(g, f, pin_key, moves="the block cannot move the yoke"):
    """(pin, guide point, guide link, slot angle rad, B) of an RPP or a PPR,
    read in the order (and with the errors) of the RPP's fields; ``pin_key``:
    the field of the known pin, ``moves``: what a slot along the guide means."""
    a, gp = f.point(g, pin_key), f.point(g, "guide_point")
    link = f.pair(g, "guide_link", optional=True)
    slot = math.radians(g.number("slot_angle", 90.0, within=lim.ANGLE))
    if abs(math.sin(slot)) < PARALLEL_SIN:
        raise g.error("slot_angle", f"the slot runs along the guide "
                      f"({math.degrees(slot):g} deg from it): {moves}")
    b = f.define(g, "B")
    return a, gp, link, slot, b


class Yoke(GroupType):
    """The hooks of a block whose pin ``pin`` runs in a slot of a yoke sliding
    on a guide (RPP, and PPR read from its other end): the fields ``pin``,
    ``B``, ``guide_point``, ``guide_angle``, ``guide_link``, ``guide_offset``,
    ``slot_angle``, ``slot_offset`` of ``RPP``."""
    EMITTER = "RPPEmitter"
    SOLVES = ("B",)

    def reads(self):
        return (self.pin, self.guide_point) + (self.guide_link or ())

    def writes(self):
        return (self.B,)

    def plan_row(self, pt):
        ga, gb = link_points(pt, self.guide_link)
        return (kc.G_RPP, [pt(self.pin), pt(self.guide_point), ga, gb, pt(self.B)],
                [("guide_angle", self.guide_angle), ("guide_offset", self.guide_offset),
                 ("slot_angle", self.slot_angle), ("slot_offset", self.slot_offset)])

    def transmission(self):
        ga, gb = self.guide_link or (None, None)
        return [(self.name or f"{self.TYPE} {self.pin}-{self.B}", "lines",
                 ((ga, gb, self.guide_angle), (ga, gb, self.guide_angle + self.slot_angle)))]

    def segments(self):
        return [(self.pin, self.B)]

    def guides(self, fixed):
        link, angle = self.guide_link, self.guide_angle
        return [(self.B, (link, angle), host(self.guide_point, link, fixed),
                 guide_words(link, angle), ("guide_angle",)),
                (self.pin, (link, angle + self.slot_angle), (self.B,),
                 f"along its slot, {deg(self.slot_angle)} from its guide "
                 f"{guide_words(link, angle)}", ("guide_angle", "slot_angle"))]

    def same_directions(self):
        out = []
        if self.guide_offset == 0.0:
            out.append(((self.guide_point, self.B), (self.guide_link, self.guide_angle)))
        if self.slot_offset == 0.0:
            out.append(((self.B, self.pin), (self.guide_link, self.guide_angle + self.slot_angle)))
        return out


@dataclass(frozen=True)
class RPP(Yoke):
    """Scotch yoke: a block pinned at the known point A slides in a slot of a
    yoke, and the yoke slides on a guide.

    The guide runs through the known point ``guide_point`` with the absolute
    direction ``guide_angle``, or, with ``guide_link`` = (a, b), the direction
    of the link a->b plus ``guide_angle``; the yoke's reference point B travels
    on the line at the perpendicular distance ``guide_offset`` from the guide
    (on the side of its direction turned +90 deg).  The slot is fixed in the
    yoke at ``slot_angle`` from the guide, through B; the block's pin A runs at
    ``slot_offset`` from the slot's line (on its +90 deg side).  The yoke turns
    with the guide; the group cannot be assembled with the slot along the
    guide (slot_angle = 0 or 180 deg)."""
    A: str
    B: str
    guide_point: str
    guide_angle: float           # rad: absolute, or relative to guide_link
    slot_angle: float            # rad, relative to the guide
    guide_offset: float = 0.0    # mm
    slot_offset: float = 0.0     # mm
    guide_link: tuple[str, str] | None = None
    name: str = ""

    TYPE = "RPP"

    @classmethod
    def parse(cls, g, f, name):
        a, gp, link, slot, b = parse_yoke(g, f, "A")
        return cls(a, b, gp, math.radians(g.number("guide_angle", 0.0, within=lim.ANGLE)), slot,
                   g.number("guide_offset", 0.0, within=lim.OFFSET),
                   g.number("slot_offset", 0.0, within=lim.OFFSET), link, name)

    @property
    def pin(self):
        return self.A
