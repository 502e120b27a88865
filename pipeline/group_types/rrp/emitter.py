"""The RRP dyad's lines of the generated module (the hooks of
``pipeline.compiler.emit.Emitter``): the careful path by its library kernel,
the lane form on the guide's unit vector, the force lanes' lines, and its
instances in the library's warm-up mechanism."""

from __future__ import annotations

import math

from ...compiler.emit import TO_ROUNDING, Emitter
from ...compiler.lane_force_groups import direction_analogs, from_position_lanes
from ...compiler.lane_geometry import hoisted_cos_sin, lane_direction
from ...compiler.names import NO_POINT, lane
from . import G_RRP
from .model import RRP


class RRPEmitter(Emitter):
    watched = True
    code = G_RRP
    force_lanes = TO_ROUNDING
    guide_col = 3
    fast = True

    def derived(self):
        # the lane form's guide direction: the hoisted cos/sin of its angle
        return hoisted_cos_sin(self, "guide_angle")

    def lanes(self):
        # kernels.rrp's lines on the guide's unit vector (a guide of fixed
        # direction: its operations, the same bits)
        A, G, B = self.xy(0), self.xy(1), self.xy(2)
        lab, w = lane(self.k("L_AB")), lane(self.k("W"))
        return ([f"# {self.title()}: slider {B} on the guide through {G}, link from {A}"]
                + lane_direction(self, "u1", "guide_angle", 3)
                + ["nx = -u1y", "ny = u1x",
                   f"dx = {A}x - {G}x", f"dy = {A}y - {G}y",
                   "p = u1x * dx + u1y * dy", "h = nx * dx + ny * dy",
                   f"q2 = {lab} * {lab} - h * h",
                   "bad = bad | (q2 < 0.0)",
                   "q = math.sqrt(max(q2, 0.0))",
                   f"s = p + {w} * q",
                   f"{B}x = {G}x + s * u1x", f"{B}y = {G}y + s * u1y",
                   "# margin |cos| of the angle between the link and the guide",
                   f"m = q / {lab}",
                   "low = low | (not (m >= margin_safe))"])

    def careful(self):
        ga = self.p(3) if self.ix[3] >= 0 else NO_POINT
        gb = self.p(4) if self.ix[4] >= 0 else NO_POINT
        return [f"# {self.title()}: slider {self.pname(2)} on the guide through "
                f"{self.pname(1)}, link from {self.pname(0)}",
                f"st, m = rrp(pos, d1, d2, {self.p(0)}, {self.p(1)}, {self.p(2)}, {ga}, {gb}, "
                f"{self.k('L_AB')}, {self.k('guide_angle')}, {self.k('W')}, order, sing, slack)"]

    def transmission_items(self):
        return (f"link {self.pname(0)}-{self.pname(2)} against the guide's normal",
                [("lines", (self.ix[0], self.ix[2], "0.0", self.ix[3], self.ix[4],
                            f"{self.k('guide_angle')} + 0.5 * math.pi"))])

    def force_lines(self, c, t):
        return _force_lines(self)


def _force_lines(e):
    """An RRP dyad by the positions stage's lane form (``kernels.rrp``'s
    lines on the guide's unit vector), its analogs by ``rrp``'s lines."""
    a, g, b = e.ix[:3]
    return from_position_lanes(e.lanes()) + direction_analogs(e, "t1", 3) + [
        "th1 = t11", "th2 = t12",
        f"rx = P{b}_0 - P{a}_0", f"ry = P{b}_1 - P{a}_1",
        "ru = rx * u1x + ry * u1y",
        "# B' = G' + s' u + s th' n ; r.(B' - A') = 0",
        f"tx = V{g}_0 + s * th1 * nx - V{a}_0", f"ty = V{g}_1 + s * th1 * ny - V{a}_1",
        "s1 = -(rx * tx + ry * ty) / ru",
        f"V{b}_0 = V{g}_0 + s1 * u1x + s * th1 * nx",
        f"V{b}_1 = V{g}_1 + s1 * u1y + s * th1 * ny",
        "# B'' = G'' + s'' u + 2 s' th' n + s (th'' n - th'^2 u); r.(B'' - A'') + |B' - A'|^2 = 0",
        f"ex = A{g}_0 + 2.0 * s1 * th1 * nx + s * (th2 * nx - th1 * th1 * u1x) - A{a}_0",
        f"ey = A{g}_1 + 2.0 * s1 * th1 * ny + s * (th2 * ny - th1 * th1 * u1y) - A{a}_1",
        f"wx = V{b}_0 - V{a}_0", f"wy = V{b}_1 - V{a}_1",
        "s2 = -((wx * wx + wy * wy) + rx * ex + ry * ey) / ru",
        f"A{b}_0 = ex + A{a}_0 + s2 * u1x", f"A{b}_1 = ey + A{a}_1 + s2 * u1y",
    ]


EMITTERS = (RRPEmitter,)


def warmup(tip):
    """Its groups in the library's warm-up mechanism (``pipeline.compiler.warmup``),
    on points of its own and the crank's ``tip``, on a fixed guide and on one
    turning with the crank: (fixed points, groups)."""
    return {"RRP_G": (38.0, 0.0)}, (
        RRP(A=tip, B="RRP_B", guide_point="RRP_G", guide_angle=math.radians(90.0), L_AB=44.2,
            W=-1),
        RRP(A=tip, B="RRP_B2", guide_point="RRP_G", guide_angle=math.radians(10.0), L_AB=30.0,
            W=1, guide_link=("P1", tip)))
