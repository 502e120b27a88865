"""One emitter per structural group type.

An emitter writes the lines of its group for the generated kernels:

* ``params``: the parameters of the candidate row it reads (once per candidate);
* ``derived``: constants it computes from them once per candidate (the
  ternary link's angle, cos/sin of fixed angles, squared lengths);
* ``careful``: the careful path at one crank position (positions, first and
  second analogs to ``order``, status and margin), calling the group's
  formulas in ``pipeline.kernels`` with constant point indices;
* ``lanes`` (where the group has a fast form): the lock-step lane path of the
  sweep's positions stage, written out in full: division and square root
  only, no library call.

Adding a group type means adding one emitter here and its tests.
"""

from __future__ import annotations

from ..kernels import config as kc
from ..kernels import inputs as ik
from .lane_geometry import hoisted_cos_sin, lane_direction, lane_meet
from .names import NO_POINT, lane, text, wrap_line


class Emitter:
    code = None
    fast = False            # has a lane form
    watched = False         # can fail between positions: its margin is watched
    continued = False       # solved by Newton: keeps a row of the continuation state
                            # (``triad_row``: start, predictor, step control, closing)

    def __init__(self, plan, names, g, triad_row=-1):
        self.plan = plan
        self.n = names
        self.g = g
        self.label = plan.group_names[g]
        self.ix = [int(i) for i in plan.gidx[g]]
        self.triad_row = triad_row

    # -- helpers
    def k(self, key):
        return self.n.K(self.g, key)

    def p(self, j):
        """The index constant of the group's point j (gidx column j)."""
        return self.n.I(self.ix[j])

    def xy(self, j):
        """The lane path's locals of the group's point j: stem of p3x, p3y."""
        return self.n.xy(self.ix[j])

    def pname(self, j):
        """The user's name of point j, for a comment (``names.text``)."""
        return text(self.plan.point_names[self.ix[j]])

    def keys(self):
        return list(self.n.group_keys[self.g])

    def params(self):
        return [self.k(key) for key in self.keys()]

    def derived(self):
        return []

    def title(self):
        return f"group {self.g}: {type(self).__name__[:-len('Emitter')]} {text(self.label)}"

    def careful(self):
        raise NotImplementedError

    def lanes(self):
        raise NotImplementedError

    def module_constants(self):
        """Lines of module-level constants the group's kernels read (none by default)."""
        return []

    def transmission_items(self):
        """The group's transmission angles (``pipeline.solve.peaks.transmission_items``)
        as (words, items): each item (kind, arguments) of ``kernels.metrics``'
        ``dyad_transmission`` ("dyad": point indices A, B, C),
        ``lead_transmission`` ("lead": J, P, A, B, C, D) or ``lines_transmission``
        ("lines": a, b, alpha, c, d, beta; a point index -1 for a fixed
        direction, the angles as expressions of the constants); none by default."""
        return "", []

    def transmission(self):
        """Lines that lower ``tr`` to the group's transmission angles at this
        position (rad), given the cos and sin of the smallest angle so far
        (``best_cos``, ``best_sin``: ``kernels.metrics.fold_angle`` skips an
        angle certainly above it)."""
        words, items = self.transmission_items()
        if not items:
            return []
        lines = [f"# {self.title()}: {words}"]
        for kind, args in items:
            a = [self.n.I(x) if isinstance(x, int) and x >= 0 else
                 (NO_POINT if isinstance(x, int) else x) for x in args]
            call = f"tr = min(tr, {kind}_transmission(pos, {', '.join(a)}, best_cos, best_sin))"
            lines.append(wrap_line(call) if kind == "lines" else call)
        return lines


class CrankEmitter(Emitter):
    code = kc.G_CRANK
    fast = True

    def careful(self):
        return [f"# {self.title()}: {self.pname(1)} = {self.pname(0)} + L e(phi1 + phiM0)",
                f"st, m = crank(pos, d1, d2, {self.p(0)}, {self.p(1)}, {self.k('length')}, "
                f"{self.k('phiM0')}, phi, order)"]

    def derived(self):
        return hoisted_cos_sin(self, "phiM0")

    def lanes(self):
        # e(phi1 + phiM0) = e(phi1) rotated by phiM0: the table's cos/sin times
        # the candidate's hoisted cos/sin (no library call)
        o, t = self.xy(0), self.xy(1)
        c, s, L = lane(f"{self.k('phiM0')}_cos"), lane(f"{self.k('phiM0')}_sin"), \
            lane(self.k("length"))
        return [f"# {self.title()}: {t} = {o} + L e(phi1) rotated by phiM0 (table cos/sin)",
                f"ec = cph * {c} - sph * {s}",
                f"es = sph * {c} + cph * {s}",
                f"{t}x = {o}x + {L} * ec",
                f"{t}y = {o}y + {L} * es"]


class RRREmitter(Emitter):
    watched = True
    code = kc.G_RRR
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


class RRPEmitter(Emitter):
    watched = True
    code = kc.G_RRP
    fast = True

    def derived(self):
        # the lane form's guide direction: the hoisted cos/sin of its angle
        return hoisted_cos_sin(self, "guide_angle")

    def lanes(self):
        # kernels.groups.rrp's lines on the guide's unit vector (a guide of fixed
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


class RPREmitter(Emitter):
    watched = True
    code = kc.G_RPR

    def careful(self):
        return [f"# {self.title()}: coulisse about {self.pname(1)} through the block at "
                f"{self.pname(0)}; guide end {self.pname(2)}",
                f"st, m = rpr(pos, d1, d2, {self.p(0)}, {self.p(1)}, {self.p(2)}, "
                f"{self.k('offset')}, {self.k('guide_length')}, {self.k('W')}, order, sing, slack)"]

    def transmission_items(self):
        c, a, e = self.ix[1], self.ix[0], self.ix[2]
        return (f"{self.pname(1)}->{self.pname(0)} against the guide's normal",
                [("lines", (c, a, "0.0", c, e, "0.5 * math.pi"))])


def _guide_link(e, j):
    """Point index constants of a guide link's ends at gidx columns j, j + 1
    (NO_POINT for a guide of fixed direction)."""
    if e.ix[j] < 0:
        return NO_POINT, NO_POINT
    return e.p(j), e.p(j + 1)


def _guide_words(e, j, link_j, angle_key):
    if e.ix[link_j] < 0:
        return f"through {e.pname(j)} at the absolute {angle_key}"
    return (f"through {e.pname(j)} along {e.pname(link_j)}->{e.pname(link_j + 1)} "
            f"+ {angle_key}")


class PRPEmitter(Emitter):
    watched = True
    code = kc.G_PRP
    fast = True

    def derived(self):
        # the lane form turns unit vectors by the guides' angles: their cos/sin, hoisted
        return hoisted_cos_sin(self, "guide1_angle", "guide2_angle")

    def lanes(self):
        return ([f"# {self.title()}: {self.xy(6)} where the two guide lines meet"]
                + lane_direction(self, "u1", "guide1_angle", 1)
                + lane_direction(self, "u2", "guide2_angle", 4)
                + lane_meet(self.xy(0), lane(self.k("guide1_offset")), self.xy(3),
                             lane(self.k("guide2_offset")), self.xy(6)))

    def careful(self):
        a1, b1 = _guide_link(self, 1)
        a2, b2 = _guide_link(self, 4)
        k = self.k
        return [f"# {self.title()}: {self.pname(6)} where the guide lines of two blocks meet",
                "# (linear: B from a 2x2 system);",
                f"# guide 1 {_guide_words(self, 0, 1, 'guide1_angle')},",
                f"# guide 2 {_guide_words(self, 3, 4, 'guide2_angle')}",
                f"st, m = prp(pos, d1, d2, {self.p(0)}, {a1}, {b1}, {self.p(3)}, {a2}, {b2}, "
                f"{self.p(6)}, {k('guide1_angle')}, {k('guide1_offset')}, {k('guide2_angle')}, "
                f"{k('guide2_offset')}, order, sing)"]

    def transmission_items(self):
        return "the angle between the two guides", [
            ("lines", (self.ix[1], self.ix[2], self.k("guide1_angle"), self.ix[4], self.ix[5],
                       self.k("guide2_angle")))]


class RPPEmitter(Emitter):
    watched = True
    code = kc.G_RPP
    fast = True

    def derived(self):
        return hoisted_cos_sin(self, "guide_angle", "slot_angle")

    def lanes(self):
        # kernels.groups.rpp: the guide's line through G at guide_offset, and the
        # slot's line through A (the guide's direction turned by slot_angle) at
        # -slot_offset
        cs, ss = lane(f"{self.k('slot_angle')}_cos"), lane(f"{self.k('slot_angle')}_sin")
        return ([f"# {self.title()}: {self.xy(4)} where the guide and the slot through "
                 f"{self.xy(0)} meet"]
                + lane_direction(self, "u1", "guide_angle", 2)
                + [f"u2x = {cs} * u1x - {ss} * u1y", f"u2y = {ss} * u1x + {cs} * u1y"]
                + lane_meet(self.xy(1), lane(self.k("guide_offset")), self.xy(0),
                             f"-{lane(self.k('slot_offset'))}", self.xy(4)))

    def careful(self):
        ga, gb = _guide_link(self, 2)
        k = self.k
        return [f"# {self.title()}: yoke point {self.pname(4)} on the guide",
                f"# {_guide_words(self, 1, 2, 'guide_angle')}, its slot through the block "
                f"at {self.pname(0)}",
                f"st, m = rpp(pos, d1, d2, {self.p(0)}, {self.p(1)}, {ga}, {gb}, {self.p(4)}, "
                f"{k('guide_angle')}, {k('guide_offset')}, {k('slot_angle')}, "
                f"{k('slot_offset')}, order, sing)"]

    def transmission_items(self):
        ga, gb, g = self.ix[2], self.ix[3], self.k("guide_angle")
        return "the angle between the slot and the guide", [
            ("lines", (ga, gb, g, ga, gb, f"{g} + {self.k('slot_angle')}"))]


class AttachEmitter(Emitter):
    code = kc.G_ATTACH

    @property
    def fast(self):
        return self.ix[1] >= 0

    def careful(self):
        if self.ix[1] < 0:
            return [f"# {self.title()}: {self.pname(3)} = {self.pname(0)} + length e(angle)",
                    f"st, m = attach(pos, d1, d2, {self.p(0)}, {NO_POINT}, {NO_POINT}, {self.p(3)}, "
                    f"{self.k('angle')}, {self.k('length')}, order)"]
        base, a, b, out = (self.p(j) for j in (0, 1, 2, 3))
        c, s_, L = f"{self.k('angle')}_cos", f"{self.k('angle')}_sin", self.k("length")
        return [
            f"# {self.title()}: {self.pname(3)} = {self.pname(0)} + rot({self.pname(1)}->"
            f"{self.pname(2)}, angle, length):",
            "# the link vector v turned by the hoisted cos/sin of the angle and scaled to the",
            "# length (no library call); analogs from th' = (v x v') / |v|^2 and",
            "# th'' = (v x v'') / |v|^2 - 2 (v . v') (v x v') / |v|^4",
            f"vx = pos[{b}, 0] - pos[{a}, 0]",
            f"vy = pos[{b}, 1] - pos[{a}, 1]",
            "r2 = vx * vx + vy * vy",
            "if not (r2 > 0.0):   # the link has no length: no direction",
            "    for q in range(2):",
            f"        pos[{out}, q] = math.nan",
            f"        d1[{out}, q] = math.nan",
            f"        d2[{out}, q] = math.nan",
            "    st, m = SINGULAR, 0.0",
            "else:",
            f"    f = {L} / math.sqrt(r2)",
            f"    ex = f * ({c} * vx - {s_} * vy)",
            f"    ey = f * ({s_} * vx + {c} * vy)",
            f"    pos[{out}, 0] = pos[{base}, 0] + ex",
            f"    pos[{out}, 1] = pos[{base}, 1] + ey",
            "    if order >= 1:",
            f"        v1x = d1[{b}, 0] - d1[{a}, 0]",
            f"        v1y = d1[{b}, 1] - d1[{a}, 1]",
            "        cr1 = vx * v1y - vy * v1x",
            "        th1 = cr1 / r2",
            f"        d1[{out}, 0] = d1[{base}, 0] - th1 * ey",
            f"        d1[{out}, 1] = d1[{base}, 1] + th1 * ex",
            "        if order >= 2:",
            f"            v2x = d2[{b}, 0] - d2[{a}, 0]",
            f"            v2y = d2[{b}, 1] - d2[{a}, 1]",
            "            th2 = (vx * v2y - vy * v2x) / r2 - 2.0 * (vx * v1x + vy * v1y) * cr1 / (r2 * r2)",
            f"            d2[{out}, 0] = d2[{base}, 0] - th2 * ey - th1 * th1 * ex",
            f"            d2[{out}, 1] = d2[{base}, 1] + th2 * ex - th1 * th1 * ey",
            "    st, m = OK, 1.0",
        ]

    def derived(self):
        return hoisted_cos_sin(self, "angle")

    def lanes(self):
        base, a, b, out = (self.xy(j) for j in (0, 1, 2, 3))
        c, s, L = lane(f"{self.k('angle')}_cos"), lane(f"{self.k('angle')}_sin"), \
            lane(self.k("length"))
        return [f"# {self.title()}: {out} = {base} + rot({a}->{b}, angle, length), "
                "hoisted cos/sin",
                f"vx = {b}x - {a}x",
                f"vy = {b}y - {a}y",
                f"f = {L} / math.sqrt(vx * vx + vy * vy)",
                f"{out}x = {base}x + f * ({c} * vx - {s} * vy)",
                f"{out}y = {base}y + f * ({s} * vx + {c} * vy)"]


class InputEmitter(Emitter):
    """A rotary or slider input moved by its law of the crank angle phi
    (``pipeline.kernels.inputs``); a table law's spline is a constant of the
    module."""
    code = kc.G_INPUT

    def __init__(self, plan, names, g, triad_row=-1):
        super().__init__(plan, names, g, triad_row)
        self.i = [int(x) for x in plan.input_group].index(g)
        self.kind = int(plan.input_kind[self.i])
        self.law = int(plan.input_law[self.i])
        self.table = f"LAW_{names.K(g, 'spline')}"

    def module_constants(self):
        if self.law != ik.LAW_TABLE:
            return []
        knots, coef = self.plan.input_tables[self.i]
        return [f"# the periodic spline of {text(self.label)}'s table: knots (rad) and coefficients",
                wrap_line(f"{self.table}_KNOTS = np.array({[float(x) for x in knots]!r})"),
                wrap_line(f"{self.table}_COEF = np.array({coef.tolist()!r})")]

    def derived(self):
        if self.kind != ik.SLIDER:
            return []
        return hoisted_cos_sin(self, "guide_angle")

    fast = True
    theta_col = -1          # its columns of the lane path's table (lanes.lane_kernel)

    def law_call(self):
        """(words, expression) of the input's law at ``phi``: (q, q', q'')."""
        k = self.k
        rotary = self.kind == ik.ROTARY
        if self.law == ik.LAW_LINEAR:
            words = "q = phase + ratio phi (a geared crank)"
            law = f"linear_law(phi, {k('ratio')}, {k('phase_angle')})"
        elif self.law == ik.LAW_TABLE:
            words = "q from the periodic spline of its table"
            law = f"table_law(phi, {k('phase_angle')}, {self.table}_KNOTS, {self.table}_COEF)"
        else:
            cyc = self.law == ik.LAW_CYCLOIDAL
            words = f"{'cycloidal' if cyc else 'harmonic'} rise and return"
            start, travel = ("start_angle", "travel_angle") if rotary else ("start", "stroke")
            law = (f"rise_return(phi, {k(start)}, {k(travel)}, {k('phase_angle')}, "
                   f"{k('rise_angle')}, {cyc})")
        return words, law

    def careful(self):
        k = self.k
        rotary = self.kind == ik.ROTARY
        words, law = self.law_call()
        lines = [f"# {self.title()}: {words}", f"q, q1, q2 = {law}"]
        if rotary:
            lines += [f"# {self.pname(1)} = {self.pname(0)} + length e(q)",
                      f"st, m = rotary_input(pos, d1, d2, {self.p(0)}, {self.p(1)}, "
                      f"{k('length')}, q, q1, q2, order)"]
        else:
            a = k("guide_angle")
            lines += [f"# {self.pname(1)} = {self.pname(0)} + q e(guide_angle)",
                      f"st, m = slider_input(pos, d1, d2, {self.p(0)}, {self.p(1)}, {a}_cos, "
                      f"{a}_sin, q, q1, q2, order)"]
        return lines

    def law_steps(self):
        """Lines of ``setup_lane`` that fill the input's columns of the lane path's
        table (theta[k, col * LANES + l]) at every step k of the walk: e(q) (a
        rotary input) or q (a slider input), then q' and q'', by the careful
        path's own law and library calls (the same bits); the lanes read them
        instead of calling the library."""
        c = self.theta_col
        words, law = self.law_call()
        rotary = self.kind == ik.ROTARY
        return [f"# {self.title()}: {words}, at every step of the walk",
                "for k in range(phis.shape[0] + 3):",
                "    phi = walk_angle(phis, k, close)",
                f"    q, q1, q2 = {law}",
                f"    theta[k, {c} * LANES + l] = {'math.cos(q)' if rotary else 'q'}",
                f"    theta[k, {c + 1} * LANES + l] = {'math.sin(q)' if rotary else '0.0'}",
                f"    theta[k, {c + 2} * LANES + l] = q1",
                f"    theta[k, {c + 3} * LANES + l] = q2"]

    def lanes(self):
        c = self.theta_col
        piv, tip = self.xy(0), self.xy(1)
        if self.kind == ik.ROTARY:
            L = lane(self.k("length"))
            return [f"# {self.title()}: {tip} = {piv} + length e(q), e(q) from the lane's table",
                    f"{tip}x = {piv}x + {L} * theta[k, {c} * LANES + l]",
                    f"{tip}y = {piv}y + {L} * theta[k, {c + 1} * LANES + l]"]
        a = self.k("guide_angle")
        return [f"# {self.title()}: {tip} = {piv} + q e(guide_angle), q from the lane's table",
                f"{tip}x = {piv}x + theta[k, {c} * LANES + l] * {lane(a + '_cos')}",
                f"{tip}y = {piv}y + theta[k, {c} * LANES + l] * {lane(a + '_sin')}"]


class ClassIIIEmitter(Emitter):
    watched = True
    continued = True
    code = kc.G_CLASS3
    fast = True

    def derived(self):
        u = self.k("U435")
        return [(u, f"ternary_angle({self.k('L34')}, {self.k('L45')}, {self.k('L35')}, "
                    f"{self.k('orientation')})"),
                (f"{u}_cos", f"math.cos({u})"), (f"{u}_sin", f"math.sin({u})")]

    def careful(self):
        i2, i6, i7, i3, i4, i5 = (self.p(j) for j in range(6))
        k = self.k
        return [f"# {self.title()}: ternary link {self.pname(3)}-{self.pname(4)}-"
                f"{self.pname(5)} on leads from {self.pname(0)}, {self.pname(1)}, "
                f"{self.pname(2)}; Newton on the closure from the continuation state row "
                f"{self.triad_row}",
                f"st, m = class3(pos, d1, d2, {i2}, {i6}, {i7}, {i3}, {i4}, {i5}, {k('L23')}, "
                f"{k('L34')}, {k('U435')}, {k('L35')}, {k('L46')}, {k('L57')}, state, "
                f"{_row(self)}, order, tols, {k('U435')}_cos, {k('U435')}_sin)"]

    def transmission_items(self):
        i2, i6, i7, i3, i4, i5 = self.ix[:6]
        n = self.pname
        return (f"leads {n(4)}-{n(1)} and {n(5)}-{n(2)}, each against the line to the meet of "
                "the other two leads",
                [("lead", (i4, i6, i2, i3, i5, i7)), ("lead", (i5, i7, i2, i3, i4, i6))])


def _row(e):
    """A class III group's row of the continuation state as its kernel's
    argument: np.int64, not a literal (numba would compile the kernel once per
    row: once for each class III group of a mechanism, and again for a
    mechanism whose group has another row than the one the library warm-up
    compiled, pipeline.compiler.warmup)."""
    return f"np.int64({e.triad_row})"


class ClassIIISliderEmitter(Emitter):
    """The class III group with a block on a guide in place of lead 5-7: the
    continuation state, the watch and the lane form (``lanes._triad_lines``)
    like ``ClassIIIEmitter``'s."""
    watched = True
    continued = True
    code = kc.G_CLASS3_SLIDER
    fast = True

    def derived(self):
        u = self.k("U435")
        return [(u, f"ternary_angle({self.k('L34')}, {self.k('L45')}, {self.k('L35')}, "
                    f"{self.k('orientation')})"),
                (f"{u}_cos", f"math.cos({u})"), (f"{u}_sin", f"math.sin({u})")] \
            + hoisted_cos_sin(self, "guide_angle")    # (the lane form's guide direction)

    def careful(self):
        i2, i6, i7, i3, i4, i5 = (self.p(j) for j in range(6))
        ga, gb = _guide_link(self, 6)
        k = self.k
        return [f"# {self.title()}: ternary link {self.pname(3)}-{self.pname(4)}-"
                f"{self.pname(5)}",
                f"# on leads from {self.pname(0)}, {self.pname(1)} and a block at {self.pname(5)} "
                f"on the guide {_guide_words(self, 2, 6, 'guide_angle')}",
                "# (P5 at guide_offset from it); Newton on |P4 - P6| = L46, n.(P5 - G) = offset",
                f"# from the continuation state row {self.triad_row}",
                wrap_line(f"st, m = class3_slider(pos, d1, d2, {i2}, {i6}, {i7}, {i3}, {i4}, "
                           f"{i5}, {ga}, {gb}, {k('L23')}, {k('L34')}, {k('U435')}, "
                           f"{k('L35')}, {k('L46')}, {k('guide_angle')}, {k('guide_offset')}, "
                           f"state, {_row(self)}, order, tols, {k('U435')}_cos, "
                           f"{k('U435')}_sin)")]


EMITTERS = {e.code: e for e in (CrankEmitter, RRREmitter, RRPEmitter, RPREmitter,
                                PRPEmitter, RPPEmitter, AttachEmitter, ClassIIIEmitter,
                                InputEmitter, ClassIIISliderEmitter)}


def emitters_for(plan, names):
    """The emitters of a plan's groups, in solve order; each group solved by
    continuation gets the next row of the continuation state."""
    out, row = [], 0
    for g, code in enumerate(plan.codes):
        cls = EMITTERS[int(code)]
        if cls.continued:
            out.append(cls(plan, names, g, row))
            row += 1
        else:
            out.append(cls(plan, names, g))
    return out


def constants_of(plan, n, ems):
    """(local name, expression) of every per-candidate constant: the fixed
    pivots, each group's parameters and what its emitter derives from them."""
    consts = []
    for off in plan.fixed_off:
        for j in (int(off), int(off) + 1):          # x, y
            consts.append((n.par(j), f"par[PAR_{n.par(j)}]"))
    for e in ems:
        for k in e.params():
            consts.append((k, f"par[PAR_{k}]"))
        consts.extend(e.derived())
    return consts


def constant_names(plan, n, ems):
    return [c[0] for c in constants_of(plan, n, ems)]
