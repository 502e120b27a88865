"""RPP (Scotch yoke): a block pinned at a known point A slides in a slot of a
yoke that slides on a guide.

Study fields: ``A`` (known), ``B`` (solved: the yoke's point on its guide
where the slot's centre line crosses it), ``guide_point`` (known),
``guide_angle`` (deg: absolute, or relative to ``guide_link = [a, b]``),
``guide_offset`` (mm: B's distance from the guide's line), ``slot_angle``
(deg: the slot in the yoke, from the guide; default 90), ``slot_offset`` (mm:
A's distance from the slot's line through B).  The slot may not run along the
guide.  A PPR (``PPR`` below) is this chain read from its other end."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...base import limits as lim
from ...model.group_base import PARALLEL_SIN, GroupType, deg, guide_words, host, link_points
from . import G_RPP


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
    SOLVES = ("B",)

    def reads(self):
        return (self.pin, self.guide_point) + (self.guide_link or ())

    def writes(self):
        return (self.B,)

    def plan_row(self, pt):
        ga, gb = link_points(pt, self.guide_link)
        return (G_RPP, [pt(self.pin), pt(self.guide_point), ga, gb, pt(self.B)],
                [("guide_angle", self.guide_angle), ("guide_offset", self.guide_offset),
                 ("slot_angle", self.slot_angle), ("slot_offset", self.slot_offset)])

    def transmission(self):
        """The block pushes the yoke along the slot's normal, and the yoke moves
        along its guide, so mu = the angle between the slot and the guide,
        |slot_angle| folded: constant over the revolution, a design quantity (90
        deg for the classic yoke).  (PPR, the same chain, inherits it.)"""
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


# PPR: a slider on a sliding guide.  A sliding guide (a carriage) moves along
# a guide; a slider runs in a slot of the sliding guide and is pinned at a known
# point.  Read from the frame: prismatic (the sliding guide on its guide),
# prismatic (the slider in its slot), revolute (the slider's pin).
# 
# Study fields (``type = "PPR"``):
# 
# * ``pin``: the known point the slider is pinned at;
# * ``guide_point`` (known), ``guide_angle`` (deg: absolute, or relative to
#   ``guide_link = [a, b]``, a guide turning with that link): the sliding
#   guide's guide;
# * ``B`` (solved): the sliding guide's point on its guide, where the slot's
#   centre line crosses it; ``guide_offset`` (mm): B's distance from the
#   guide's line, on the side of its direction turned +90 deg;
# * ``slot_angle`` (deg, default 90): the slider's slot in the sliding guide,
#   from the guide (not along it); ``slot_offset`` (mm): the pin's distance from
#   the slot's line through B, on its +90 deg side.
# 
# It is the RPP chain read from its other end, and is solved as one: the same
# plan row (code ``G_RPP``, points pin, guide point, guide link, B; parameters
# ``guide_angle``, ``guide_offset``, ``slot_angle``, ``slot_offset``, the names
# a sweep varies), the same emitter and the same transmission angle (the slot
# against the guide), so a PPR gives exactly the numbers of the RPP declared
# with ``A`` = pin.
@dataclass(frozen=True)
class PPR(Yoke):
    """A slider pinned at the known ``pin`` runs in a slot (``slot_angle`` from
    the guide, ``slot_offset`` from the pin) of a sliding guide whose point B
    moves along the guide (``guide_point``, ``guide_angle``, ``guide_link``,
    ``guide_offset``); conventions of ``RPP``."""
    pin: str
    B: str
    guide_point: str
    guide_angle: float           # rad: absolute, or relative to guide_link
    slot_angle: float            # rad, relative to the guide
    guide_offset: float = 0.0    # mm
    slot_offset: float = 0.0     # mm
    guide_link: tuple[str, str] | None = None
    name: str = ""

    TYPE = "PPR"

    @classmethod
    def parse(cls, g, f, name):
        pin, gp, link, slot, b = parse_yoke(
            g, f, "pin", "the slider cannot move the sliding guide")
        return cls(pin, b, gp, math.radians(g.number("guide_angle", 0.0, within=lim.ANGLE)),
                   slot, g.number("guide_offset", 0.0, within=lim.OFFSET),
                   g.number("slot_offset", 0.0, within=lim.OFFSET), link, name)


# the study types this folder declares (``pipeline.model.groups.GROUP_TYPES``)
STUDY_TYPES = (RPP, PPR,)
