"""The mechanism model: declared once (frozen dataclasses), compiled once into
the flat arrays the kernels read (``Plan``).

Units follow DOMAIN.md: lengths in mm, angles in radians here (the study
parser converts from degrees), masses kg, moments of inertia kg*m^2.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from .kernels import config as kc
from .kernels import inputs as ik


# ----------------------------------------------------------------- groups
@dataclass(frozen=True)
class Crank:
    """Driver: crank pivot-tip, tip at pivot + L e(phi1 + phiM0)."""
    pivot: str
    tip: str
    length: float
    phiM0: float = 0.0       # mounting phase, rad
    omega1: float = 1.0      # rad/s, sign = direction of rotation
    eps1: float = 0.0        # rad/s^2
    rot: int = 1             # direction of the revolution: phi1 from phi0 to phi0 + rot*2pi
    phi0: float = 0.0        # start of the revolution, rad
    name: str = "crank"

    def reads(self):
        return (self.pivot,)

    def writes(self):
        return (self.tip,)


@dataclass(frozen=True)
class RRR:
    """B joined to known A by link A-B and to known C by link C-B; mode W."""
    A: str
    C: str
    B: str
    L_AB: float
    L_CB: float
    W: int
    name: str = ""

    def reads(self):
        return (self.A, self.C)

    def writes(self):
        return (self.B,)


@dataclass(frozen=True)
class RRP:
    """Slider B on a guide line through G (fixed direction, or turning with the
    link guide_link), joined to known A by link A-B; mode W = side along the guide."""
    A: str
    B: str
    guide_point: str
    guide_angle: float       # rad: absolute, or relative to guide_link
    L_AB: float
    W: int
    guide_link: tuple[str, str] | None = None
    name: str = ""

    def reads(self):
        return (self.A, self.guide_point) + (self.guide_link or ())

    def writes(self):
        return (self.B,)


@dataclass(frozen=True)
class RPR:
    """Coulisse: a block pinned at known point ``block`` slides on a guide turning
    about ``pivot``; ``guide_end`` = pivot + guide_length along the guide."""
    block: str
    pivot: str
    guide_end: str
    guide_length: float
    offset: float = 0.0
    W: int = 1
    name: str = ""

    def reads(self):
        return (self.block, self.pivot)

    def writes(self):
        return (self.guide_end,)


@dataclass(frozen=True)
class PRP:
    """Two blocks joined by the revolute B, each sliding on a known guide.

    Guide i runs through the known point ``guide{i}_point`` with the absolute
    direction ``guide{i}_angle``, or, with ``guide{i}_link`` = (a, b), with the
    direction of the link a->b plus ``guide{i}_angle`` (a slot in that link);
    block i carries B at the perpendicular distance ``guide{i}_offset`` from
    its guide, on the side of the guide's direction turned +90 deg.  B is
    where the two lines meet; the group cannot be assembled where the guides
    are parallel."""
    B: str
    guide1_point: str
    guide1_angle: float          # rad: absolute, or relative to guide1_link
    guide2_point: str
    guide2_angle: float
    guide1_offset: float = 0.0   # mm
    guide2_offset: float = 0.0
    guide1_link: tuple[str, str] | None = None
    guide2_link: tuple[str, str] | None = None
    name: str = ""

    def reads(self):
        return ((self.guide1_point,) + (self.guide1_link or ()) + (self.guide2_point,)
                + (self.guide2_link or ()))

    def writes(self):
        return (self.B,)


@dataclass(frozen=True)
class RPP:
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

    def reads(self):
        return (self.A, self.guide_point) + (self.guide_link or ())

    def writes(self):
        return (self.B,)


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
        from .kernels import inputs
        return {v: k for k, v in inputs.LAW_NAMES.items()}[self.kind]

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


@dataclass(frozen=True)
class RotaryInput:
    """A link turned about the fixed ``pivot`` to the absolute angle given by
    ``law`` of the cycle angle: ``tip`` = pivot + length e(q(phi1)).  An
    oscillating rocker driven by a cam, or a second crank geared to the
    first (linear law)."""
    pivot: str
    tip: str
    length: float
    law: Law
    name: str = ""

    def reads(self):
        return (self.pivot,)

    def writes(self):
        return (self.tip,)


@dataclass(frozen=True)
class SliderInput:
    """A block moved along a fixed guide by ``law`` of the cycle angle: the
    guide runs through the fixed ``guide_point`` at the absolute direction
    ``guide_angle``; ``block`` = guide_point + q(phi1) e(guide_angle).  A
    linear actuator with a stroke law."""
    guide_point: str
    block: str
    guide_angle: float
    law: Law
    name: str = ""

    def reads(self):
        return (self.guide_point,)

    def writes(self):
        return (self.block,)


@dataclass(frozen=True)
class ClassIII:
    """Triad of DOMAIN.md sections 3 and 5 (lead 2-3, ternary 3-4-5, leads 4-6, 5-7)."""
    input: str
    pivot_4: str
    pivot_5: str
    joints: tuple[str, str, str]   # names of vertices 3, 4, 5
    L23: float
    L34: float
    L45: float
    L35: float
    L46: float
    L57: float
    a0: float                      # start guess at phi_start, rad
    b0: float
    phi_start: float = 0.0
    orientation: int = 1           # sign of U435
    name: str = "triad"

    def reads(self):
        return (self.input, self.pivot_4, self.pivot_5)

    def writes(self):
        return self.joints


@dataclass(frozen=True)
class ClassIIISlider:
    """The class III group with a slider in place of lead 5-7: lead 2-3 from
    ``input``, the ternary link 3-4-5, lead 4-6 to ``pivot_4``, and a block
    pinned at vertex 5 that slides on a guide line.

    The guide runs through the known point ``guide_point`` with the absolute
    direction ``guide_angle``, or, with ``guide_link`` = (a, b), the direction
    of the link a->b plus ``guide_angle``; the block carries vertex 5 at the
    perpendicular distance ``guide_offset`` from the guide, on the side of its
    direction turned +90 deg (the convention of RRP, PRP and RPP).  Unknowns,
    start guess and branch as ``ClassIII``."""
    input: str
    pivot_4: str
    guide_point: str
    joints: tuple[str, str, str]   # names of vertices 3, 4, 5
    L23: float
    L34: float
    L45: float
    L35: float
    L46: float
    guide_angle: float             # rad: absolute, or relative to guide_link
    guide_offset: float            # mm
    a0: float                      # start guess at phi_start, rad
    b0: float
    phi_start: float = 0.0
    orientation: int = 1           # sign of U435
    guide_link: tuple[str, str] | None = None
    name: str = "triad"

    def reads(self):
        return (self.input, self.pivot_4, self.guide_point) + (self.guide_link or ())

    def writes(self):
        return self.joints


@dataclass(frozen=True)
class Attach:
    """Point rigidly attached to a link: base + rot(along vector, angle, length);
    with along=None the direction is the absolute ``angle`` (translating body)."""
    point: str
    base: str
    along: tuple[str, str] | None
    angle: float
    length: float
    name: str = ""

    def reads(self):
        return (self.base,) + (self.along or ())

    def writes(self):
        return (self.point,)


Group = (Crank | RRR | RRP | RPR | PRP | RPP | ClassIII | ClassIIISlider | Attach | RotaryInput
         | SliderInput)


# ----------------------------------------------------------------- bodies and loads
@dataclass(frozen=True)
class CentreOfMass:
    """S = base + rot(along vector, US, lS), or base + lS e(US) if along is None."""
    base: str
    along: tuple[str, str] | None
    lS: float
    US: float


@dataclass(frozen=True)
class Body:
    """A moving link for force analysis: the points at which it is jointed,
    its mass data, and what it turns with (its ``along`` vector by default)."""
    name: str
    joints: tuple[str, ...]
    mass: float
    J_S: float
    com: CentreOfMass
    turns_with: tuple[str, str] | None = None   # None: the com's along vector


@dataclass(frozen=True)
class Slide:
    """A prismatic pair: ``slider`` body slides on ``guide`` body (None = ground)
    along a direction: fixed angle, or the angle of ``along`` plus ``angle``."""
    slider: str
    guide: str | None
    angle: float
    along: tuple[str, str] | None = None
    # the parameters (plan names) of the group's guide this slide runs along:
    # the direction is angle - (their declared sum) + their values in the
    # candidate's row, so a sweep that turns the guide turns the slide with it
    follows: tuple = ()
    follows_declared: float = 0.0


@dataclass(frozen=True)
class Load:
    """External force (fx, fy at ``point``) and moment on a body; each component
    is an ``Expression`` of phi and t (see pipeline.expressions)."""
    body: str
    point: str | None
    fx: object
    fy: object
    moment: object
    where: str = ""           # study location, for error messages


@dataclass(frozen=True)
class Mechanism:
    name: str
    fixed: dict            # point name -> (x, y) mm
    crank: Crank
    groups: tuple          # groups after the crank, in solve order
    links: tuple = ()      # (a, b) pairs whose angles are reported
    bodies: tuple = ()
    slides: tuple = ()
    loads: tuple = ()
    gravity: float = 9.81

    def compile(self) -> "Plan":
        return compile_mechanism(self)


# ----------------------------------------------------------------- compiled plan
GIDX_WIDTH = 8                         # point indices per group row (class3_slider uses 8)

@dataclass(frozen=True)
class Plan:
    """Flat arrays read by the kernels; ``par`` is the base parameter row."""
    codes: np.ndarray
    gidx: np.ndarray
    goff: np.ndarray
    par: np.ndarray
    fixed_idx: np.ndarray
    fixed_off: np.ndarray
    point_names: tuple
    par_names: tuple
    group_names: tuple
    n_visible: int                     # points before the hidden centres of mass
    n_kinematic: int                   # groups before the hidden centres of mass
    link_a: np.ndarray
    link_b: np.ndarray
    # force analysis (empty when no bodies)
    body_names: tuple = ()
    body_com: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    body_turn: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    body_mass_off: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    joint_point: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    joint_bodies: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    joint_names: tuple = ()
    slide_bodies: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    slide_dir: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    slide_angle: np.ndarray = field(default_factory=lambda: np.zeros(0))
    # per slide: up to two parameters (indices into par, -1: none) added to
    # slide_angle - slide_declared (the guide parameters a slide follows)
    slide_follow: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    slide_declared: np.ndarray = field(default_factory=lambda: np.zeros(0))
    slide_names: tuple = ()
    crank_body: int = -1
    load_body: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    load_point: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    gravity: float = 9.81
    # inputs besides the crank (pipeline.kernels.inputs), in solve order: their
    # group, kind (ROTARY/SLIDER), law code, points (pivot, tip) or (guide
    # point, block), the body the drive acts on (-1: none) and, for a table
    # law, its spline (knots, coefficients), else None
    input_group: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    input_kind: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    input_law: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    input_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    input_body: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    input_tables: tuple = ()
    input_names: tuple = ()

    @property
    def n_points(self):
        return len(self.point_names)

    @property
    def n_groups(self):
        return len(self.codes)

    @property
    def n_inputs(self):
        return len(self.input_group)

    def point(self, name):
        return self.point_names.index(name)

    def param(self, name):
        try:
            return self.par_names.index(name)
        except ValueError:
            raise KeyError(f"no parameter {name!r}; known: {', '.join(self.par_names)}") from None


def group_label(g, k):
    """A readable name for group ``g`` at position ``k`` of the solve order."""
    if getattr(g, "name", ""):
        return g.name
    return f"{type(g).__name__}[{k}]"


def compile_mechanism(m: Mechanism) -> Plan:
    """Compile a declared mechanism into the flat plan.  Declaration errors are
    caught by the study parser; this assumes a consistent mechanism."""
    names = list(m.fixed)
    index = {n: i for i, n in enumerate(names)}

    def pt(n):
        if n not in index:
            index[n] = len(names)
            names.append(n)
        return index[n]

    par: list[float] = []
    par_names: list[str] = []

    def add(label, value):
        par_names.append(label)
        par.append(float(value))
        return len(par) - 1

    fixed_idx, fixed_off = [], []
    for n, (x, y) in m.fixed.items():
        fixed_idx.append(index[n])
        fixed_off.append(add(f"{n}.x", x))
        add(f"{n}.y", y)

    codes, gidx, goff, gnames = [], [], [], []
    inputs = []

    def emit(code, idx, label, values):
        codes.append(code)
        row = list(idx) + [-1] * (GIDX_WIDTH - len(idx))
        gidx.append(row)
        gnames.append(label)
        goff.append(len(par))
        for key, v in values:
            add(f"{label}.{key}", v)

    c = m.crank
    emit(kc.G_CRANK, [pt(c.pivot), pt(c.tip)], c.name,
         [("length", c.length), ("phiM0", c.phiM0)])
    for k, g in enumerate(m.groups, start=1):
        label = group_label(g, k)
        if isinstance(g, RRR):
            emit(kc.G_RRR, [pt(g.A), pt(g.C), pt(g.B)], label,
                 [("L_AB", g.L_AB), ("L_CB", g.L_CB), ("W", g.W)])
        elif isinstance(g, RRP):
            ga, gb = (pt(g.guide_link[0]), pt(g.guide_link[1])) if g.guide_link else (-1, -1)
            emit(kc.G_RRP, [pt(g.A), pt(g.guide_point), pt(g.B), ga, gb], label,
                 [("L_AB", g.L_AB), ("guide_angle", g.guide_angle), ("W", g.W)])
        elif isinstance(g, RPR):
            emit(kc.G_RPR, [pt(g.block), pt(g.pivot), pt(g.guide_end)], label,
                 [("offset", g.offset), ("guide_length", g.guide_length), ("W", g.W)])
        elif isinstance(g, PRP):
            links = []
            for link in (g.guide1_link, g.guide2_link):
                links += [pt(link[0]), pt(link[1])] if link else [-1, -1]
            emit(kc.G_PRP, [pt(g.guide1_point), links[0], links[1], pt(g.guide2_point),
                            links[2], links[3], pt(g.B)], label,
                 [("guide1_angle", g.guide1_angle), ("guide1_offset", g.guide1_offset),
                  ("guide2_angle", g.guide2_angle), ("guide2_offset", g.guide2_offset)])
        elif isinstance(g, RPP):
            ga, gb = (pt(g.guide_link[0]), pt(g.guide_link[1])) if g.guide_link else (-1, -1)
            emit(kc.G_RPP, [pt(g.A), pt(g.guide_point), ga, gb, pt(g.B)], label,
                 [("guide_angle", g.guide_angle), ("guide_offset", g.guide_offset),
                  ("slot_angle", g.slot_angle), ("slot_offset", g.slot_offset)])
        elif isinstance(g, ClassIII):
            emit(kc.G_CLASS3, [pt(g.input), pt(g.pivot_4), pt(g.pivot_5)]
                 + [pt(j) for j in g.joints], label,
                 [("L23", g.L23), ("L34", g.L34), ("L45", g.L45), ("L35", g.L35),
                  ("L46", g.L46), ("L57", g.L57), ("orientation", g.orientation),
                  ("a0", g.a0), ("b0", g.b0), ("phi_start", g.phi_start)])
        elif isinstance(g, ClassIIISlider):
            ga, gb = (pt(g.guide_link[0]), pt(g.guide_link[1])) if g.guide_link else (-1, -1)
            emit(kc.G_CLASS3_SLIDER, [pt(g.input), pt(g.pivot_4), pt(g.guide_point)]
                 + [pt(j) for j in g.joints] + [ga, gb], label,
                 [("L23", g.L23), ("L34", g.L34), ("L45", g.L45), ("L35", g.L35),
                  ("L46", g.L46), ("guide_angle", g.guide_angle),
                  ("guide_offset", g.guide_offset), ("orientation", g.orientation),
                  ("a0", g.a0), ("b0", g.b0), ("phi_start", g.phi_start)])
        elif isinstance(g, Attach):
            ia, ib = (pt(g.along[0]), pt(g.along[1])) if g.along else (-1, -1)
            emit(kc.G_ATTACH, [pt(g.base), ia, ib, pt(g.point)], label,
                 [("angle", g.angle), ("length", g.length)])
        elif isinstance(g, (RotaryInput, SliderInput)):
            rotary = isinstance(g, RotaryInput)
            ends = (g.pivot, g.tip) if rotary else (g.guide_point, g.block)
            first = [("length", g.length)] if rotary else [("guide_angle", g.guide_angle)]
            inputs.append((len(codes), ik.ROTARY if rotary else ik.SLIDER, g.law.code,
                           [pt(ends[0]), pt(ends[1])], g, label))
            emit(kc.G_INPUT, [pt(ends[0]), pt(ends[1])], label,
                 first + g.law.parameters(rotary))
        else:  # pragma: no cover - the parser only builds the types above
            raise TypeError(f"unknown group {g!r}")
    n_visible = len(names)
    n_kinematic = len(codes)

    # bodies: each centre of mass is a hidden attached point "S[body]"
    body_com, body_turn, body_mass_off = [], [], []
    for b in m.bodies:
        s = f"S[{b.name}]"
        com = b.com
        ia, ib = (index[com.along[0]], index[com.along[1]]) if com.along else (-1, -1)
        emit(kc.G_ATTACH, [index[com.base], ia, ib, pt(s)], s,
             [("angle", com.US), ("length", com.lS)])
        body_com.append(index[s])
        turn = b.turns_with if b.turns_with is not None else com.along
        body_turn.append([index[turn[0]], index[turn[1]]] if turn else [-1, -1])
        body_mass_off.append(add(f"{b.name}.mass", b.mass))
        add(f"{b.name}.J_S", b.J_S)

    joints, jb, jnames = [], [], []
    bodies_of = {}
    for i, b in enumerate(m.bodies):
        for p in b.joints:
            bodies_of.setdefault(p, []).append(i)
    for p in names[:n_visible]:
        owners = bodies_of.get(p, [])
        if p in m.fixed and len(owners) == 1:
            joints.append(index[p]); jb.append([-1, owners[0]])
        elif len(owners) == 2:
            joints.append(index[p]); jb.append(owners)
        else:
            continue
        jnames.append("R" + p[1:] if p.startswith("P") and p[1:].isdigit() else f"R[{p}]")
    order = sorted(range(len(joints)), key=lambda k: natural_key(jnames[k]))
    joints, jb, jnames = [joints[k] for k in order], [jb[k] for k in order], [jnames[k] for k in order]
    body_index = {b.name: i for i, b in enumerate(m.bodies)}
    sb, sd, sa, sn, sf, sdecl = [], [], [], [], [], []
    for s in m.slides:
        sf.append([par_names.index(f) for f in s.follows] + [-1] * (2 - len(s.follows)))
        sdecl.append(s.follows_declared)
        sb.append([body_index[s.guide] if s.guide else -1, body_index[s.slider]])
        sd.append([index[s.along[0]], index[s.along[1]]] if s.along else [-1, -1])
        sa.append(s.angle)
        sn.append(f"slide[{s.slider}]")
    crank_body = -1
    for i, b in enumerate(m.bodies):
        if c.pivot in b.joints and c.tip in b.joints:
            crank_body = i
    input_body = [_driven_body(m, g) for (*_, g, _l) in inputs]
    lb = [body_index[ld.body] for ld in m.loads]
    lp = [index[ld.point] if ld.point else -1 for ld in m.loads]

    i64 = lambda x, shape=None: np.asarray(x, dtype=np.int64).reshape(shape if shape else (-1,))
    return Plan(
        codes=i64(codes), gidx=i64(gidx, (-1, GIDX_WIDTH)), goff=i64(goff),
        par=np.asarray(par, dtype=np.float64),
        fixed_idx=i64(fixed_idx), fixed_off=i64(fixed_off),
        point_names=tuple(names), par_names=tuple(par_names), group_names=tuple(gnames),
        n_visible=n_visible, n_kinematic=n_kinematic,
        link_a=i64([index[a] for a, _ in m.links]), link_b=i64([index[b] for _, b in m.links]),
        body_names=tuple(b.name for b in m.bodies),
        body_com=i64(body_com), body_turn=i64(body_turn, (-1, 2)),
        body_mass_off=i64(body_mass_off),
        joint_point=i64(joints), joint_bodies=i64(jb, (-1, 2)), joint_names=tuple(jnames),
        slide_bodies=i64(sb, (-1, 2)), slide_dir=i64(sd, (-1, 2)),
        slide_angle=np.asarray(sa, dtype=np.float64), slide_names=tuple(sn),
        slide_follow=i64(sf, (-1, 2)), slide_declared=np.asarray(sdecl, dtype=np.float64),
        crank_body=crank_body, load_body=i64(lb), load_point=i64(lp), gravity=m.gravity,
        input_group=i64([i[0] for i in inputs]), input_kind=i64([i[1] for i in inputs]),
        input_law=i64([i[2] for i in inputs]), input_points=i64([i[3] for i in inputs], (-1, 2)),
        input_body=i64(input_body),
        input_tables=tuple(i[4].law.spline() if i[4].law.kind == "table" else None
                           for i in inputs),
        input_names=tuple(i[5] for i in inputs),
    )


def _driven_body(m: Mechanism, g) -> int:
    """The body an input's drive acts on: the one jointed at the pivot and the
    tip of a rotary input, the one sliding on the ground at a slider input's
    block; -1 if no body is declared for it."""
    for i, b in enumerate(m.bodies):
        if isinstance(g, RotaryInput):
            if g.pivot in b.joints and g.tip in b.joints:
                return i
        elif g.block in b.joints and any(s.slider == b.name and s.guide is None
                                         for s in m.slides):
            return i
    return -1


def natural_key(name):
    """Sort R2 before R10."""
    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", name)]
