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
  only, no library call;
* ``force_lines`` (where ``force_lanes`` says it has them): its lines of the
  force lanes (``pipeline.compiler.lane_forces``).

Here: the base and the emitters of the mechanism's own elements (the crank, an
attached point, an input); each structural group type's emitters are in its
folder (``pipeline.group_types``), found by ``emitter_classes``.
"""

from __future__ import annotations

from functools import cache

from .. import group_types
from ..group_types import G_ATTACH, G_CRANK, G_INPUT
from ..kernels import inputs as ik
from .lane_force_groups import attach_lines
from .lane_geometry import hoisted_cos_sin
from .names import NO_POINT, lane, text, wrap_line


SAME_BITS = "the same bits"
TO_ROUNDING = "to rounding"


class Emitter:
    code = None
    fast = False            # has a lane form
    watched = False         # can fail between positions: its margin is watched
    takes_law = False       # an input: the lane walk's table holds its law (``law_steps``)
    # its lines of the force lanes (``force_lines``): SAME_BITS, the careful kernel's
    # operations; TO_ROUNDING, its lane form's; None: the force lanes do not know it
    force_lanes = None
    guide_col = None        # gidx column of a guide link: on a guide of fixed direction
                            # (none there) its TO_ROUNDING lines give the same bits

    @property
    def continued(self):
        """Solved by Newton: keeps a row of the continuation state (``triad_row``:
        start, predictor, step control, closing); its folder's ``CONTINUED``
        (``group_types.continued_codes``), the one place that says it."""
        return self.code in group_types.continued_codes()

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

    def setup_lines(self):
        """(A group solved by continuation) its lines of the lane path's
        ``setup_lane``: its row of the lane state at phis[0], from the careful
        solve there."""
        raise NotImplementedError

    def force_lines(self, c, t):
        """Its lines of the force lanes (``pipeline.compiler.lane_forces``): positions,
        velocity and acceleration analogs of its points on the lane's locals
        (P3_0, V3_0, A3_0), a constant by ``c(name)``, a column of the table
        handed over by ``t(col)``."""
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
    code = G_CRANK
    force_lanes = SAME_BITS
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


def guide_link(e, j):
    """Point index constants of a guide link's ends at gidx columns j, j + 1
    (NO_POINT for a guide of fixed direction)."""
    if e.ix[j] < 0:
        return NO_POINT, NO_POINT
    return e.p(j), e.p(j + 1)


def guide_words(e, j, link_j, angle_key):
    if e.ix[link_j] < 0:
        return f"through {e.pname(j)} at the absolute {angle_key}"
    return (f"through {e.pname(j)} along {e.pname(link_j)}->{e.pname(link_j + 1)} "
            f"+ {angle_key}")


class AttachEmitter(Emitter):
    code = G_ATTACH
    force_lanes = SAME_BITS

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

    def force_lines(self, c, t):
        return attach_lines(self, c)

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
    code = G_INPUT
    force_lanes = SAME_BITS
    takes_law = True

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


@cache
def emitter_classes() -> dict:
    """Every plan code -> its emitter class: the mechanism's own elements' and
    each group-type folder's (``emitter.EMITTERS``)."""
    out = {e.code: e for e in (CrankEmitter, AttachEmitter, InputEmitter)}
    for mod in group_types.part("emitter"):
        for e in mod.EMITTERS:
            if e.code not in group_types.folder_codes(mod) or e.code in out:
                raise ValueError(f"{mod.__name__}.{e.__name__}: its code {e.code} is not one "
                                 "of its folder's CODES, or another emitter's")
            out[e.code] = e
    return out


def emitters_for(plan, names):
    """The emitters of a plan's groups, in solve order; each group solved by
    continuation gets the next row of the continuation state."""
    out, row = [], 0
    for g, code in enumerate(plan.codes):
        cls = emitter_classes()[int(code)]
        if int(code) in group_types.continued_codes():
            out.append(cls(plan, names, g, row))
            row += 1
        else:
            out.append(cls(plan, names, g))
    return out


def watched_groups(plan, ems, watch=True):
    """The groups whose margin the walks watch between positions (none without
    ``watch``: the benchmark's baseline of the watch's cost)."""
    return [e.g for e in ems[:plan.n_kinematic] if e.watched and watch]


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
