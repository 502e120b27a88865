"""RPR (coulisse): a block pinned at a known point slides on a guide turning
about a known pivot.

Study fields: ``block``, ``pivot`` (known), ``guide_end`` (solved: pivot +
``guide_length`` along the guide, mm), ``offset`` (mm: the guide line's
distance from the pivot), ``W``."""

from __future__ import annotations

from dataclasses import dataclass

from ...base import limits as lim
from ...model.group_base import HALF, GroupType
from . import G_RPR


@dataclass(frozen=True)
class RPR(GroupType):
    """Coulisse: a block pinned at known point ``block`` slides on a guide turning
    about ``pivot``; ``guide_end`` = pivot + guide_length along the guide."""
    block: str
    pivot: str
    guide_end: str
    guide_length: float
    offset: float = 0.0
    W: int = 1
    name: str = ""

    TYPE = "RPR"
    SOLVES = ("guide_end",)

    @classmethod
    def parse(cls, g, f, name):
        blk, piv = f.point(g, "block"), f.point(g, "pivot")
        end = f.define(g, "guide_end")
        return cls(blk, piv, end, g.number("guide_length", positive=True, within=lim.LENGTH),
                   g.number("offset", 0.0, within=lim.OFFSET), f.mode(g), name)

    def reads(self):
        return (self.block, self.pivot)

    def writes(self):
        return (self.guide_end,)

    def plan_row(self, pt):
        return (G_RPR, [pt(self.block), pt(self.pivot), pt(self.guide_end)],
                [("offset", self.offset), ("guide_length", self.guide_length), ("W", self.W)])

    def transmission(self):
        """The block at A pushes the guide along its normal n, and the guide's
        point under the block moves across C->A, so mu = angle(C->A, n) = 90 deg -
        angle(C->A, C->E); 90 deg with no offset, 0 where the block passes the
        foot of the perpendicular from C (the group's toggle)."""
        return [(self.name or f"RPR {self.pivot}-{self.block}", "lines",
                 ((self.pivot, self.block, 0.0), (self.pivot, self.guide_end, HALF)))]

    def segments(self):
        return [(self.pivot, self.guide_end)]

    def guides(self, fixed):
        return [(self.block, ((self.pivot, self.guide_end), 0.0), (self.pivot,),
                 f"along {self.pivot}->{self.guide_end} (its guide, turning about "
                 f"{self.pivot})", ())]

    def same_directions(self):
        if self.offset == 0.0:
            return [((self.pivot, self.block), ((self.pivot, self.guide_end), 0.0))]
        return []

    def carried(self, pts):
        return (self.guide_end,) if self.pivot in pts else ()


# the study types this folder declares (``pipeline.model.groups.GROUP_TYPES``)
STUDY_TYPES = (RPR,)
