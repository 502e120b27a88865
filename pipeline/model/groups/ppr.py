"""PPR: a slider on a sliding guide.  A sliding guide (a carriage) moves along
a guide; a slider runs in a slot of the sliding guide and is pinned at a known
point.  Read from the frame: prismatic (the sliding guide on its guide),
prismatic (the slider in its slot), revolute (the slider's pin).

Study fields (``type = "PPR"``):

* ``pin``: the known point the slider is pinned at;
* ``guide_point`` (known), ``guide_angle`` (deg: absolute, or relative to
  ``guide_link = [a, b]``, a guide turning with that link): the sliding
  guide's guide;
* ``B`` (solved): the sliding guide's point on its guide, where the slot's
  centre line crosses it; ``guide_offset`` (mm): B's distance from the
  guide's line, on the side of its direction turned +90 deg;
* ``slot_angle`` (deg, default 90): the slider's slot in the sliding guide,
  from the guide (not along it); ``slot_offset`` (mm): the pin's distance from
  the slot's line through B, on its +90 deg side.

It is the RPP chain read from its other end, and is solved as one: the same
plan row (code ``G_RPP``, points pin, guide point, guide link, B; parameters
``guide_angle``, ``guide_offset``, ``slot_angle``, ``slot_offset``, the names
a sweep varies), the same emitter and the same transmission angle (the slot
against the guide), so a PPR gives exactly the numbers of the RPP declared
with ``A`` = pin."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...base import limits as lim
from .rpp import Yoke, parse_yoke


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
