"""The mechanism model: declared once (frozen dataclasses), compiled once into
the flat arrays the kernels read (``Plan``).

Units follow DOMAIN.md: lengths in mm, angles in radians here (the study
parser converts from degrees), masses kg, moments of inertia kg·m².
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from ..group_types import G_ATTACH, G_CRANK, continued_codes
from .group_base import GroupType
from ..kernels import config as kc


# ----------------------------------------------------------------- groups
@dataclass(frozen=True)
class Crank:
    """Driver: crank pivot-tip, tip at pivot + L e(phi1 + phiM0)."""
    pivot: str
    tip: str
    length: float
    phiM0: float = 0.0       # mounting phase, rad
    omega1: float = 1.0      # rad/s, sign = direction of rotation
    eps1: float = 0.0        # rad/s²
    rot: int = 1             # direction of the revolution: phi1 from phi0 to phi0 + rot*2pi
    phi0: float = 0.0        # start of the revolution, rad
    name: str = "crank"

    def reads(self):
        return (self.pivot,)

    def writes(self):
        return (self.tip,)


# the group types after the crank: one module each in pipeline.model.groups (their
# fields, study parsing, plan row, emitter, transmission angles, drawing, guides)
Group = Crank | GroupType


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
    is an ``Expression`` of phi and t (see pipeline.base.expressions)."""
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
    friction: object = None   # model.friction.Friction: [mechanism.friction]; None: frictionless

    def compile(self) -> "Plan":
        return compile_mechanism(self)


# ----------------------------------------------------------------- compiled plan
GIDX_WIDTH = 8                         # point indices per group row (the widest type's)

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

    @property
    def has_continued(self) -> bool:
        """Whether a group solved by continuation is in the plan
        (``group_types.continued_codes``): its singularity margin is then a
        metric and a constraint."""
        return bool(np.isin(self.codes, continued_codes()).any())

    @property
    def crank_pivot(self):
        """Point index of the crank's pivot (the crank is the plan's first group)."""
        return int(self.gidx[0, 0])

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


def transmission_items(mech):
    """The mechanism's transmission angles, in order: (label, kind, what).

    A transmission angle is 90 deg minus the pressure angle, the angle between
    the line of the force a group passes to the member it drives (frictionless
    joints, links without their own loads) and that member's velocity; 90 deg
    is best, 0 a dead position.  Every angle is folded into [0, 90] deg
    (min(mu, 180 - mu)).

    Each group type gives its own items (its ``transmission`` hook, whose
    docstring says which angle it is: ``pipeline.group_types``): a two-link
    dyad's angle at its middle joint ("dyad", (A, B, C): between B->A and
    B->C); a lead of a group of higher class against the line from its joint
    to the meet of the other leads ("lead", (J, P, A, B, C, D)); a group with
    a sliding pair gives two lines ("lines", ((a, b, alpha), (c, d, beta))):
    the link a->b turned by alpha (the absolute direction alpha where a is
    None) against c->d turned by beta (``kernels.metrics.lines_transmission``)."""
    out = []
    for g in mech.groups:
        out += g.transmission()     # the group type's items (pipeline.model.groups)
    return out


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
    emit(G_CRANK, [pt(c.pivot), pt(c.tip)], c.name,
         [("length", c.length), ("phiM0", c.phiM0)])
    for k, g in enumerate(m.groups, start=1):
        label = group_label(g, k)
        entry = g.input_row(pt)
        if entry is not None:
            inputs.append((len(codes), *entry, g, label))
        code, idx, values = g.plan_row(pt)
        emit(code, idx, label, values)
    n_visible = len(names)
    n_kinematic = len(codes)

    # bodies: each centre of mass is a hidden attached point "S[body]"
    body_com, body_turn, body_mass_off = [], [], []
    for b in m.bodies:
        s = f"S[{b.name}]"
        com = b.com
        ia, ib = (index[com.along[0]], index[com.along[1]]) if com.along else (-1, -1)
        emit(G_ATTACH, [index[com.base], ia, ib, pt(s)], s,
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
    input_body = [g.driven_body(m) for (*_, g, _l) in inputs]
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


def natural_key(name):
    """Sort R2 before R10."""
    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", name)]
