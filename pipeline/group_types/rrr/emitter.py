"""The RRR dyad's lines of the generated module (the hooks of
``pipeline.compiler.emit.Emitter``): the careful path by its library kernel,
the lane form (the cosine law without acos), the force lanes' lines, and its
instance in the library's warm-up mechanism."""

from __future__ import annotations

from ...compiler.emit import TO_ROUNDING, Emitter
from ...compiler.lane_force_groups import from_position_lanes
from ...compiler.names import lane
from . import G_RRR
from .model import RRR


class RRREmitter(Emitter):
    watched = True
    code = G_RRR
    force_lanes = TO_ROUNDING
    fast = True

    def careful(self):
        return [f"# {self.title()}: {self.pname(2)} at L_AB from {self.pname(0)} and L_CB "
                f"from {self.pname(1)}, assembly mode W (circle intersection)",
                f"st, m = rrr(pos, d1, d2, {self.p(0)}, {self.p(1)}, {self.p(2)}, "
                f"{self.k('L_AB')}, {self.k('L_CB')}, {self.k('W')}, order, sing, slack)"]

    def derived(self):
        # the lane form divides by nothing that is fixed per candidate
        lab, lcb = self.k("L_AB"), self.k("L_CB")
        return [(self.k("inv_cb"), f"1.0 / {lcb}"),
                (self.k("inv_ab_cb"), f"1.0 / ({lab} * {lcb})"),
                (self.k("k"), f"{lcb} * {lcb} - {lab} * {lab}")]

    def lanes(self):
        A, C, B = (self.xy(j) for j in range(3))
        lab, lcb, w = (lane(self.k(x)) for x in ("L_AB", "L_CB", "W"))
        inv_cb, inv_ab_cb, kk = (lane(self.k(x)) for x in ("inv_cb", "inv_ab_cb", "k"))
        return [
            f"# {self.title()}: {B} from {A} and {C}, cosine law without acos:",
            "# C->B = L_CB (cos U r/|r| - W sin U n(r)/|r|), r = A - C, cos U = arg",
            f"rx = {A}x - {C}x",
            f"ry = {A}y - {C}y",
            "r2 = rx * rx + ry * ry",
            "ir = 1.0 / math.sqrt(r2)",
            f"cu = (r2 + {kk}) * (0.5 * ir * {inv_cb})",
            "q = 1.0 - cu * cu",
            "bad = bad | (q < 0.0) | (r2 <= 0.0)",
            "su = math.sqrt(max(q, 0.0))",
            f"{B}x = {C}x + {lcb} * ir * (cu * rx + {w} * su * ry)",
            f"{B}y = {C}y + {lcb} * ir * (cu * ry - {w} * su * rx)",
            f"# margin |sin| of the angle at {B}",
            f"m = abs(({B}x - {A}x) * ({B}y - {C}y) - ({B}y - {A}y) * ({B}x - {C}x)) "
            f"* {inv_ab_cb}",
            "low = low | (not (m >= margin_safe))",
        ]

    def transmission_items(self):
        a, c, b = self.ix[:3]
        return f"the angle at {self.pname(2)} between the links", [("dyad", (a, b, c))]

    def force_lines(self, c, t):
        return _force_lines(self)


def _force_lines(e):
    """An RRR dyad by the positions stage's lane form (the cosine law without
    acos), its analogs by ``kernels.rrr``'s 2 x 2 solves."""
    a, cc, b = e.ix[:3]
    return from_position_lanes(e.lanes()) + [
        f"pax = P{b}_0 - P{a}_0", f"pay = P{b}_1 - P{a}_1",
        f"pcx = P{b}_0 - P{cc}_0", f"pcy = P{b}_1 - P{cc}_1",
        "dj = pax * pcy - pay * pcx",
        "# first analogs: (B - A).(B' - A') = 0, (B - C).(B' - C') = 0",
        f"h1 = pax * V{a}_0 + pay * V{a}_1", f"h2 = pcx * V{cc}_0 + pcy * V{cc}_1",
        f"V{b}_0 = (h1 * pcy - pay * h2) / dj", f"V{b}_1 = (pax * h2 - h1 * pcx) / dj",
        "# second analogs",
        f"ux = V{b}_0 - V{a}_0", f"uy = V{b}_1 - V{a}_1",
        f"wx = V{b}_0 - V{cc}_0", f"wy = V{b}_1 - V{cc}_1",
        f"h1 = pax * A{a}_0 + pay * A{a}_1 - (ux * ux + uy * uy)",
        f"h2 = pcx * A{cc}_0 + pcy * A{cc}_1 - (wx * wx + wy * wy)",
        f"A{b}_0 = (h1 * pcy - pay * h2) / dj", f"A{b}_1 = (pax * h2 - h1 * pcx) / dj",
    ]


EMITTERS = (RRREmitter,)


def warmup(tip):
    """Its groups in the library's warm-up mechanism (``pipeline.compiler.warmup``),
    on points of its own and the crank's ``tip``: (fixed points, groups)."""
    return {"RRR_C": (38.0, 0.0)}, (RRR(A=tip, C="RRR_C", B="RRR_B", L_AB=41.0, L_CB=40.0, W=1),)
