"""RRR: B joined to known A and C by links A-B and C-B (circle intersection).

Study fields: ``A``, ``C`` (known), ``B`` (solved), ``L_AB``, ``L_CB`` (mm),
``W`` (assembly mode, DOMAIN.md section 2)."""

from __future__ import annotations

from dataclasses import dataclass

from ...base import limits as lim
from ...model.group_base import GroupType
from . import G_RRR


@dataclass(frozen=True)
class RRR(GroupType):
    """B joined to known A by link A-B and to known C by link C-B; mode W."""
    A: str
    C: str
    B: str
    L_AB: float
    L_CB: float
    W: int
    name: str = ""

    TYPE = "RRR"
    SOLVES = ("B",)

    @classmethod
    def parse(cls, g, f, name):
        a, c = f.point(g, "A"), f.point(g, "C")
        b = f.define(g, "B")
        return cls(a, c, b, g.number("L_AB", positive=True, within=lim.LENGTH),
                   g.number("L_CB", positive=True, within=lim.LENGTH), f.mode(g), name)

    def reads(self):
        return (self.A, self.C)

    def writes(self):
        return (self.B,)

    def plan_row(self, pt):
        return (G_RRR, [pt(self.A), pt(self.C), pt(self.B)],
                [("L_AB", self.L_AB), ("L_CB", self.L_CB), ("W", self.W)])

    def transmission(self):
        """The angle at the middle joint B between B->A and B->C ("dyad", (A, B,
        C)): the force along A-B, B moving across C-B."""
        return [(self.name or f"{self.A}-{self.B}-{self.C}", "dyad", (self.A, self.B, self.C))]

    def segments(self):
        return [(self.A, self.B), (self.C, self.B)]


# the study types this folder declares (``pipeline.model.groups.GROUP_TYPES``)
STUDY_TYPES = (RRR,)
