"""The motion law of an input besides the crank (``rotary_input``,
``slider_input``) and what the two input types share: the law's study table
(README "Inputs besides the crank"), the driven end's fields, the plan's
input row."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...base import limits as lim
from ...group_types import G_INPUT
from ...kernels import inputs as ik
from ...base.limits import MAX_TABLE_POINTS, TABLE_POINTS_WHY
from ..group_base import GroupType

LAW_TYPES = ("harmonic", "cycloidal", "table", "linear")


@dataclass(frozen=True)
class Law:
    """Motion law of an input against the cycle angle phi1
    (``pipeline.kernels.inputs``): ``linear`` (q = phase + ratio phi1, a
    geared second crank), ``harmonic`` or ``cycloidal`` (a rise by ``travel``
    from ``start`` over ``rise`` rad of the cycle from ``phase``, and the
    return), or ``table`` (a periodic cubic spline through ``table``:
    (cycle angle, value) pairs, shifted by ``phase``).  Values are rad for a
    rotary input, mm for a slider input; cycle angles rad."""
    kind: str
    ratio: float = 1.0
    phase: float = 0.0
    start: float = 0.0
    travel: float = 0.0
    rise: float = math.pi
    table: tuple = ()

    # the law's keys in the parameter row -> its fields
    FIELDS = {"ratio": "ratio", "phase_angle": "phase", "start_angle": "start", "start": "start",
              "travel_angle": "travel", "stroke": "travel", "rise_angle": "rise"}

    @property
    def code(self):
        return {v: k for k, v in ik.LAW_NAMES.items()}[self.kind]

    def parameters(self, rotary):
        """(key, value) of the law's entries in the parameter row; angle keys
        end in "angle" (a sweep reads them in degrees)."""
        if self.kind == "linear":
            return [("ratio", self.ratio), ("phase_angle", self.phase)]
        if self.kind == "table":
            return [("phase_angle", self.phase)]
        start, travel = ("start_angle", "travel_angle") if rotary else ("start", "stroke")
        return [(start, self.start), (travel, self.travel), ("phase_angle", self.phase),
                ("rise_angle", self.rise)]

    def spline(self):
        """(knots (n + 1), coefficients (4, n)) of the periodic cubic spline
        through the table, closed after one cycle (2 pi)."""
        from scipy.interpolate import CubicSpline
        t = np.array([p[0] for p in self.table], dtype=np.float64)
        v = np.array([p[1] for p in self.table], dtype=np.float64)
        t = np.append(t, t[0] + 2.0 * math.pi)
        v = np.append(v, v[0])
        s = CubicSpline(t, v, bc_type="periodic")
        return s.x.copy(), np.ascontiguousarray(s.c)

    def pieces(self):
        """(breaks, pieces) of the law against the cycle angle phi1: the cycle
        angles (rad, in [0, 2 pi)) where its derivatives jump, the ends of its
        smooth pieces (a rise's start and end, a table's knots; none for a
        geared crank), and (start, length) of each piece (rad; a geared
        crank's turns, which repeat its motion).  The peaks' refinement
        (``pipeline.solve.peaks``) brackets each piece on its own, at enough
        positions within it."""
        two_pi = 2.0 * math.pi
        if self.kind == "linear":
            turn = two_pi / abs(self.ratio)
            return (), tuple((k * turn, turn) for k in range(int(abs(self.ratio))))
        if self.kind == "table":
            knots = [c for c, _ in self.table]
            gaps = [b - a for a, b in zip(knots, knots[1:] + [knots[0] + two_pi])]
            starts = [(self.phase + c) % two_pi for c in knots]
            return tuple(starts), tuple(zip(starts, gaps))
        rise_end = (self.phase + self.rise) % two_pi
        return ((self.phase % two_pi, rise_end),
                ((self.phase % two_pi, self.rise), (rise_end, two_pi - self.rise)))



def parse_law(s, rotary: bool) -> Law:
    """An input's motion law against the cycle angle phi1 (angles in deg, a
    slider's travel in mm); see ``pipeline.kernels.inputs``."""
    kind = s.string("type", choices=LAW_TYPES)
    unit = "deg" if rotary else "mm"
    to_q = math.radians if rotary else float
    q_range = lim.ANGLE if rotary else lim.OFFSET     # the input's angle (deg) or stroke (mm)
    phase = math.radians(s.number("phase", 0.0, within=lim.ANGLE))
    if kind == "linear":
        if not rotary:
            raise s.error("type", "a slider input cannot follow a linear law: its stroke would "
                                  "grow without end; use harmonic, cycloidal or table")
        ratio = s.number("ratio", nonzero=True, within=lim.RATIO)
        if ratio != round(ratio):
            raise s.error("ratio", f"must be a whole number, got {ratio:g}: the geared crank "
                          "must be back at its start when the main crank has made its one "
                          "revolution of the cycle (for a ratio of 1/n, make the slower crank "
                          "the main crank and give the other the ratio n)")
        law = Law("linear", ratio=ratio, phase=phase)
    elif kind in ("harmonic", "cycloidal"):
        rise = s.number("rise", 180.0)
        if not 0.0 < rise < 360.0:
            raise s.error("rise", f"the rise takes a part of the cycle: more than 0 and less "
                                  f"than 360 deg, got {rise:g}")
        law = Law(kind, phase=phase, start=to_q(s.number("start", 0.0, within=q_range)),
                  travel=to_q(s.number("travel", nonzero=True, within=q_range)),
                  rise=math.radians(rise))
    else:
        for key in ("cycle", "values"):
            v = s.data.get(key)
            if isinstance(v, list) and len(v) > MAX_TABLE_POINTS:
                raise s.error(key, f"a table law has at most {MAX_TABLE_POINTS:,} points "
                                   f"({TABLE_POINTS_WHY}), got {len(v):,}")
        cycle = s.numbers("cycle", within=lim.ANGLE)
        values = s.numbers("values", within=q_range)
        if len(cycle) < 4:
            raise s.error("cycle", f"a table needs at least 4 points for its periodic spline, "
                                   f"got {len(cycle)}")
        if len(values) != len(cycle):
            raise s.error("values", f"one value ({unit}) per cycle angle: {len(cycle)} cycle "
                                    f"angles, {len(values)} values")
        for k in range(1, len(cycle)):
            if not cycle[k] > cycle[k - 1]:
                raise s.error("cycle", f"cycle angles must increase: {cycle[k]:g} deg follows "
                                       f"{cycle[k - 1]:g} deg")
        if cycle[-1] == cycle[0] + 360.0:
            if values[-1] != values[0]:
                raise s.error("values", f"the cycle closes at {cycle[-1]:g} deg with "
                              f"{values[-1]:g} {unit}, but starts with {values[0]:g} {unit}")
            cycle, values = cycle[:-1], values[:-1]
        elif not cycle[-1] < cycle[0] + 360.0:
            raise s.error("cycle", f"the table spans one cycle: the last angle "
                                   f"({cycle[-1]:g} deg) must be less than the first + 360 deg")
        law = Law("table", phase=phase,
                  table=tuple((math.radians(c), to_q(v)) for c, v in zip(cycle, values)))
    s.done()
    return law


def law_grid_problem(law: Law, positions: int):
    """(field, reason) where the law is steeper than ``positions`` crank
    positions per revolution resolve (``limits.LAW_MIN_POSITIONS``), else
    None: a rise or a return over fewer than LAW_MIN_POSITIONS steps, a geared
    crank turning once in fewer, a table whose shortest spline piece spans
    fewer than TABLE_LAW_MIN_POSITIONS steps.  Between positions such a law
    swings unseen: the curves and a sweep's metrics would miss it (a 1 deg
    rise gave a peak acceleration a thousand times too small, with OK).  At
    the limit the scene's refined peaks are exact (``pipeline.solve.peaks``
    divides the positions round the law)."""
    step = 360.0 / positions                                    # deg
    fuzz = 1.0 - 1e-9          # the angles went through radians: 8 steps is 8 steps
    need = lim.LAW_MIN_POSITIONS
    if law.kind in ("harmonic", "cycloidal"):
        rise = math.degrees(law.rise)
        short = min(rise, 360.0 - rise)
        if short >= need * step * fuzz:
            return None
        which = "rise" if rise <= 180.0 else "return"
        return "rise", (f"the {law.kind} law's {which} takes {short:g} deg of the cycle: "
                        f"{short / step:.3g} steps of the {positions:,} positions "
                        f"({step:g} deg each); the law needs at least {need} positions "
                        f"within its rise and its return ({lim.LAW_POSITIONS_WHY}): give a "
                        f"rise of {need * step:g} to {360.0 - need * step:g} deg, or "
                        f"{math.ceil(need * 360.0 / short):,} positions")
    if law.kind == "linear":
        turns = abs(law.ratio)
        if positions >= need * turns:
            return None
        return "ratio", (f"the geared crank turns {turns:g} times per cycle: "
                         f"{positions / turns:.3g} of the {positions:,} positions per turn; it "
                         f"needs at least {need} ({lim.LAW_POSITIONS_WHY}): a ratio of at "
                         f"most {positions // need:,}, or {math.ceil(need * turns):,} positions")
    cycle = [math.degrees(c) for c, _ in law.table]
    gaps = [(b - a, a, b) for a, b in zip(cycle, cycle[1:] + [cycle[0] + 360.0])]
    gap, a, b = min(gaps)
    need = lim.TABLE_LAW_MIN_POSITIONS
    if gap >= need * step * fuzz:
        return None
    return "cycle", (f"the table's shortest spline piece, {a:g} to {b:g} deg, spans "
                     f"{gap / step:.3g} steps of the {positions:,} positions ({step:g} deg "
                     f"each); every piece needs at least {need} ({lim.LAW_POSITIONS_WHY}): "
                     f"space the cycle angles at least {need * step:g} deg apart, or give "
                     f"{math.ceil(need * 360.0 / gap):,} positions")


class Input(GroupType):
    """The hooks shared by the inputs: fields ``law`` and the ends ``ENDS``
    (the fixed one, the one moved by the law); ``ROTARY`` says which kind."""
    ROTARY = True
    ENDS = ("pivot", "tip")

    @classmethod
    def parse_ends(cls, g, f):
        """(fixed end, moved end, law) in the order of the study's fields."""
        first, moved = cls.ENDS
        p0 = f.point(g, first)
        if p0 not in f.fixed:
            raise g.error(first, f"the {cls.TYPE.replace('_', ' ')}'s "
                          f"{first.replace('_', ' ')} {p0!r} must be a fixed point "
                          "(mechanism.fixed): the input is driven from the frame")
        p1 = f.define(g, moved)
        law = parse_law(g.table("law"), cls.ROTARY)
        return p0, p1, law

    def ends(self):
        return tuple(getattr(self, k) for k in self.ENDS)

    def reads(self):
        return (self.ends()[0],)

    def writes(self):
        return (self.ends()[1],)

    def first_parameters(self):
        raise NotImplementedError

    def plan_row(self, pt):
        a, b = self.ends()
        return (G_INPUT, [pt(a), pt(b)],
                self.first_parameters() + self.law.parameters(self.ROTARY))

    def input_row(self, pt):
        a, b = self.ends()
        return (ik.ROTARY if self.ROTARY else ik.SLIDER, self.law.code, [pt(a), pt(b)])
