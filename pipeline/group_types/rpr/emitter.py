"""The RPR dyad's (the coulisse's) lines of the generated module (the hooks of
``pipeline.compiler.emit.Emitter``): the careful path by its library kernel
(no lane form: a mechanism with one takes the careful path), and its instance in
the library's warm-up mechanism."""

from __future__ import annotations

from ...compiler.emit import Emitter
from . import G_RPR
from .model import RPR


class RPREmitter(Emitter):
    watched = True
    code = G_RPR

    def careful(self):
        return [f"# {self.title()}: coulisse about {self.pname(1)} through the block at "
                f"{self.pname(0)}; guide end {self.pname(2)}",
                f"st, m = rpr(pos, d1, d2, {self.p(0)}, {self.p(1)}, {self.p(2)}, "
                f"{self.k('offset')}, {self.k('guide_length')}, {self.k('W')}, order, sing, slack)"]

    def transmission_items(self):
        c, a, e = self.ix[1], self.ix[0], self.ix[2]
        return (f"{self.pname(1)}->{self.pname(0)} against the guide's normal",
                [("lines", (c, a, "0.0", c, e, "0.5 * math.pi"))])


EMITTERS = (RPREmitter,)


def warmup(tip):
    """Its groups in the library's warm-up mechanism (``pipeline.compiler.warmup``),
    on points of its own and the crank's ``tip``: (fixed points, groups)."""
    return {"RPR_C": (38.0, 50.0)}, (
        RPR(block=tip, pivot="RPR_C", guide_end="RPR_E", guide_length=60.0),)
