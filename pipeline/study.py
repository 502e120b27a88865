"""Study files (TOML) -> frozen dataclasses, with errors that name the file,
the field and the reason.

A study is a "scene" (one mechanism: tables, curves, pictures) or a "sweep"
(a Monte-Carlo search over a mechanism's dimensions, see ``pipeline.sweep``).
Both declare the mechanism in ``[mechanism]``; angles are in degrees in the
file and radians in the model.
"""

from __future__ import annotations

import math
import tomllib
import unicodedata
from dataclasses import dataclass, field, replace
from pathlib import Path

from .errors import StudyError
from . import limits as lim
from .limits import (MAX_NAME_LENGTH, MAX_POSITIONS, MAX_STUDY_BYTES, MAX_TABLE_POINTS,
                     MAX_TITLE_LENGTH, NAME_WHY, POSITIONS_WHY, STUDY_BYTES_WHY,
                     TABLE_POINTS_WHY, TITLE_WHY)
from .model import (PRP, RPP, RPR, RRP, RRR, Attach, Body, CentreOfMass, ClassIII,
                    ClassIIISlider, Crank, Law, Load, Mechanism, RotaryInput, Slide, SliderInput,
                    group_label)


_MISSING = object()


class Section:
    """A table of the study being read: tracks its location and the keys used,
    so that unknown keys are reported."""

    def __init__(self, file, where, data):
        self.file = file
        self.where = where
        if not isinstance(data, dict):
            raise StudyError(file, where, f"expected a table, got {type(data).__name__}")
        self.data = data
        self.used = set()

    def path(self, key):
        key = _key(key)
        return f"{self.where}.{key}" if self.where else key

    def error(self, key, reason):
        return StudyError(self.file, self.path(key) if key else self.where, reason)

    def has(self, key):
        return key in self.data

    def raw(self, key, default=_MISSING):
        self.used.add(key)
        if key not in self.data:
            if default is _MISSING:
                raise self.error(key, "required field is missing")
            return default
        return self.data[key]

    def number(self, key, default=_MISSING, positive=False, nonzero=False, within=None):
        """A finite number; ``within``: its ``limits.Range`` (plausible values)."""
        v = self.raw(key, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.error(key, f"expected a number, got {_show(v)}")
        try:
            v = float(v)
        except OverflowError:
            raise self.error(key, "beyond the range of a 64-bit float (about 1.8e308)") from None
        if not math.isfinite(v):
            raise self.error(key, f"must be finite, got {v}")
        if positive and not v > 0:
            raise self.error(key, f"must be positive, got {v:g}")
        if nonzero and v == 0:
            raise self.error(key, "must not be zero")
        if within is not None:
            self.check_range(key, v, within)
        return v

    def check_range(self, key, v, within, what=""):
        """Refuse ``v`` outside ``within`` (a ``limits.Range``), naming the field
        and the range."""
        if not within.holds(v):
            unit = f" {within.unit}" if within.unit else ""
            raise self.error(key, f"{what}{v:g}{unit} is out of range: {within.words()}")

    def integer(self, key, default=_MISSING, minimum=None, choices=None, maximum=None,
                why=""):
        """An integer; ``maximum`` with ``why``: a limit and the reason for it."""
        v = self.raw(key, default)
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.error(key, f"expected an integer, got {_show(v)}")
        if not -2**63 <= v < 2**63:
            raise self.error(key, f"{v} is beyond the range of a 64-bit integer")
        if minimum is not None and v < minimum:
            raise self.error(key, f"must be at least {minimum}, got {v}")
        if maximum is not None and v > maximum:
            raise self.error(key, f"at most {maximum:,} ({why}), got {v:,}")
        if choices is not None and v not in choices:
            raise self.error(key, f"must be one of {', '.join(map(str, choices))}, got {v}")
        return v

    def string(self, key, default=_MISSING, choices=None):
        v = self.raw(key, default)
        if not isinstance(v, str):
            raise self.error(key, f"expected a string, got {_show(v)}")
        if choices is not None and v not in choices:
            raise self.error(key, f"must be one of {', '.join(choices)}, got {_quote(v)}")
        return v

    def name(self, key, default=_MISSING, maximum=MAX_NAME_LENGTH, why=NAME_WHY,
             empty=False):
        """A name (of a point, a group, a body, ...): a string of printable
        characters, at most ``maximum`` long (``name_problem``); the empty
        default of an optional name passes, and ``empty`` lets an empty name
        pass (a label that may be blank: the study's name and title)."""
        v = self.string(key, default)
        if v == "" and (empty or default == ""):
            return v
        problem = name_problem(v, maximum, why)
        if problem:
            raise self.error(key, problem)
        return v

    def names(self, key, n=None, default=_MISSING, maximum=MAX_NAME_LENGTH, why=NAME_WHY):
        """A list of names (``name``), or None where the default is None."""
        v = self.strings(key, n, default)
        for k, x in enumerate(v or ()):
            problem = name_problem(x, maximum, why)
            if problem:
                raise self.error(key, f"name {k + 1}: {problem}")
        return v

    def key_name(self, key, maximum=MAX_NAME_LENGTH, why=NAME_WHY):
        """A key of this table that is a name (a fixed point, a sweep variable)."""
        problem = name_problem(key, maximum, why)
        if problem:     # (an empty key too: its path shows it quoted, '')
            raise StudyError(self.file, self.path(key), problem)
        return key

    def strings(self, key, n=None, default=_MISSING):
        v = self.raw(key, default)
        if v is None:
            return None
        if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
            raise self.error(key, f"expected a list of strings, got {_show(v)}")
        if n is not None and len(v) != n:
            raise self.error(key, f"expected {n} names, got {len(v)}")
        return tuple(v)

    def numbers(self, key, n=None, default=_MISSING, within=None):
        v = self.raw(key, default)
        if not isinstance(v, list) or not all(
                isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):
            raise self.error(key, f"expected a list of numbers, got {_show(v)}")
        if n is not None and len(v) != n:
            raise self.error(key, f"expected {n} numbers, got {len(v)}")
        try:
            out = tuple(float(x) for x in v)
        except OverflowError:
            raise self.error(key, "a number is beyond the range of a 64-bit float "
                                  "(about 1.8e308)") from None
        if not all(math.isfinite(x) for x in out):
            raise self.error(key, "numbers must be finite")
        if within is not None:
            for k, x in enumerate(out):
                self.check_range(key, x, within, f"number {k + 1}: ")
        return out

    def table(self, key, default=_MISSING):
        v = self.raw(key, default)
        if v is None:
            return None
        return Section(self.file, self.path(key), v)

    def tables(self, key, default=_MISSING):
        v = self.raw(key, default)
        if not isinstance(v, list):
            raise self.error(key, f"expected an array of tables ([[{self.path(key)}]]), got {_show(v)}")
        return [Section(self.file, f"{self.path(key)}[{i}]", x) for i, x in enumerate(v)]

    def done(self):
        """Reject keys nobody asked for (typos must not be silently ignored)."""
        extra = sorted(set(self.data) - self.used)
        if extra:
            raise self.error(extra[0], f"unknown key {_quote(extra[0])}"
                             + (f" (known here: {', '.join(sorted(self.used))})" if self.used else ""))


def _show(v):
    s = repr(v)
    return f"{type(v).__name__} {s[:40]}"


def _quote(v, limit=40):
    """A user's text in a message: repr() (one line: every character that is
    not printable escaped), cut after ``limit`` characters."""
    v = str(v)
    return repr(v) if len(v) <= limit else f"{v[:limit]!r}... ({len(v):,} characters)"


def _key(key):
    """A table key in a field's path: bare where it is a plain word, else quoted."""
    k = str(key)
    if k and len(k) <= MAX_NAME_LENGTH and all(c.isascii() and (c.isalnum() or c in "_-")
                                               for c in k):
        return k
    return _quote(k)


_CATEGORIES = {"Cc": "a control character", "Cf": "a format character",
               "Zl": "a line separator", "Zp": "a paragraph separator",
               "Zs": "a space other than U+0020", "Co": "a private-use character",
               "Cn": "an unassigned code point", "Cs": "a surrogate"}


def name_problem(v: str, maximum=MAX_NAME_LENGTH, why=NAME_WHY):
    """Why ``v`` cannot be a name, or None.  A name is data (a label in tables,
    pictures and messages; in generated kernels only inside comments written by
    ascii()), so any printable character is allowed (quotes, backslashes, #,
    slashes, letters of any script); refused: the empty name, more than
    ``maximum`` characters, a character that is not printable (control and
    format characters such as NUL, tab, CR, LF, U+0085, U+200B, line and
    paragraph separators U+2028/U+2029, spaces other than U+0020) and
    surrounding spaces."""
    if not v:
        return "a name must not be empty"
    if len(v) > maximum:
        return f"a name is at most {maximum} characters ({why}), got {len(v):,}"
    for i, c in enumerate(v):
        if not c.isprintable():
            cat = unicodedata.category(c)
            return (f"a name holds printable characters only: character {i + 1} is "
                    f"U+{ord(c):04X}, {_CATEGORIES.get(cat, cat)}")
    if v != v.strip():
        return "a name must not begin or end with a space"
    return None


# ----------------------------------------------------------------- study objects
@dataclass(frozen=True)
class OutputSpec:
    working_point: str
    links: tuple                 # (a, b) point-name pairs
    link_labels: tuple           # "a_b" as written
    table_positions: int = 12
    dense_positions: int = 360
    analysis: str = "accelerations"
    rocker: tuple | None = None  # (pivot, point): output rocker for theta, stroke, dwell
    dwell_deg: float = 150.0
    pin_length: float = 10.0     # mm: pins in bending (DOMAIN.md section 5, the thesis's)
    pin_sigma: float = 200.0     # MPa: allowable bending stress
    pin_overrides: tuple = ()    # (joint, length mm, sigma MPa) per joint that differs
    motion_law: object = None    # pipeline.motion_law.MotionLaw: [output.motion_law]

    def pins(self, joint_names):
        """(length mm, allowable stress MPa) of every joint's pin."""
        over = {j: (length, sigma) for j, length, sigma in self.pin_overrides}
        return [over.get(j, (self.pin_length, self.pin_sigma)) for j in joint_names]


@dataclass(frozen=True)
class DynamicsCase:
    name: str
    phi_start: float        # rad
    omega_start: float      # rad/s
    M1: object              # Expression
    damping: float          # b, N*m*s
    t_end: float
    dt: float
    sample_dt: float


@dataclass(frozen=True)
class DynamicsSpec:
    cases: tuple
    method: str = "rk4"


@dataclass(frozen=True)
class Study:
    path: Path
    text: str
    kind: str
    name: str
    title: str
    mechanism: Mechanism
    output: OutputSpec
    dynamics: DynamicsSpec | None = None
    sweep: object = None     # pipeline.sweep.SweepSpec for kind = "sweep"
    search: object = None    # pipeline.search_spec.SearchSpec: a sweep study's [search]
    extra: dict = field(default_factory=dict)


KINDS = ("scene", "sweep")
ANALYSES = ("positions", "velocities", "accelerations", "forces")


def load_study(path) -> Study:
    """Read and validate a study file."""
    path = Path(path)
    try:
        # at most one character past the limit is read (a huge file, /dev/zero)
        with open(path, encoding="utf-8") as f:
            text = f.read(MAX_STUDY_BYTES + 1)
    except FileNotFoundError:
        raise StudyError(path, "", "file not found") from None
    except (OSError, UnicodeDecodeError) as e:
        raise StudyError(path, "", f"cannot read: {e}") from None
    return parse_study(text, path)


def parse_study(text: str, path="<study>") -> Study:
    if len(text) > MAX_STUDY_BYTES or len(text.encode("utf-8", "surrogatepass")) > MAX_STUDY_BYTES:
        raise StudyError(path, "", f"a study file is at most {MAX_STUDY_BYTES:,} bytes "
                                   f"({STUDY_BYTES_WHY}); this one is larger")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise StudyError(path, "", f"not valid TOML: {e}") from None
    root = Section(path, "", data)
    head = root.table("study")
    kind = head.string("kind", choices=KINDS)
    name = head.name("name", empty=True)
    title = head.name("title", default=name, maximum=MAX_TITLE_LENGTH, why=TITLE_WHY,
                      empty=True)
    head.done()
    mech = parse_mechanism(root.table("mechanism"), name)
    output = parse_output(root.table("output", default={}), mech)
    mech = replace(mech, links=output.links)
    dynamics = None
    if root.has("dynamics"):
        dynamics = parse_dynamics(root.table("dynamics"), mech)
    sweep = None
    if kind == "sweep":
        from .sweep_spec import parse_sweep  # sweep studies have their own section reader
        sweep = parse_sweep(root, mech, output)
    elif root.has("sweep"):
        raise root.error("sweep", "a [sweep] section needs study.kind = \"sweep\"")
    _check_law_grids(path, mech, output, sweep)
    search = None
    if root.has("search"):
        if kind != "sweep":
            raise root.error("search", "a [search] section needs study.kind = \"sweep\" "
                                       "(it searches the [sweep] section's variables)")
        from .search_spec import parse_search
        search = parse_search(root, sweep)
    root.done()
    return Study(path=Path(path), text=text, kind=kind, name=name, title=title,
                 mechanism=mech, output=output, dynamics=dynamics, sweep=sweep, search=search)


# ----------------------------------------------------------------- mechanism
GROUP_TYPES = ("RRR", "RRP", "RPR", "PRP", "RPP", "class3", "attach", "rotary_input",
               "slider_input")
LAW_TYPES = ("harmonic", "cycloidal", "table", "linear")
PARALLEL_SIN = 1e-9     # |sin| of the angle between two guides below this: parallel


def parse_mechanism(sec: Section, name: str) -> Mechanism:
    fixed = {}
    fx = sec.table("fixed")
    for p in list(fx.data):
        fx.key_name(p)
        fixed[p] = fx.numbers(p, n=2, within=lim.OFFSET)
    fx.done()
    known = set(fixed)
    defined = {p: fx.path(p) for p in fixed}

    # points that groups further down define, to tell "solved later" from "unknown"
    later = {}
    for i, g in enumerate(sec.data.get("groups", []) if isinstance(sec.data.get("groups"), list) else []):
        if isinstance(g, dict):
            for key in ("B", "guide_end", "point", "tip", "block"):
                if isinstance(g.get(key), str):
                    later.setdefault(g[key], f"{sec.path('groups')}[{i}].{key}")
            if isinstance(g.get("joints"), list):
                for p in g["joints"]:
                    if isinstance(p, str):
                        later.setdefault(p, f"{sec.path('groups')}[{i}].joints")

    def need(s, key, pname):
        if pname not in known:
            if pname in later:
                raise s.error(key, f"point {pname!r} is solved later ({later[pname]}); "
                                   "groups must come in solve order")
            if pname in defined:
                raise s.error(key, f"point {pname!r} is solved later ({defined[pname]}); "
                                   "groups must come in solve order")
            raise s.error(key, f"unknown point {pname!r}")

    def define(s, key, pname):
        if pname in defined:
            raise s.error(key, f"point {pname!r} is defined twice (first at {defined[pname]})")
        defined[pname] = s.path(key)
        known.add(pname)

    cs = sec.table("crank")
    pivot = cs.name("pivot")
    if pivot not in fixed:
        raise cs.error("pivot", f"the crank pivot {pivot!r} must be a fixed point (mechanism.fixed)")
    tip = cs.name("tip")
    define(cs, "tip", tip)
    crank = Crank(pivot=pivot, tip=tip,
                  length=cs.number("length", positive=True, within=lim.LENGTH),
                  phiM0=math.radians(cs.number("phiM0", 0.0, within=lim.ANGLE)),
                  omega1=cs.number("omega1", nonzero=True, within=lim.OMEGA),
                  eps1=cs.number("eps1", 0.0, within=lim.EPS),
                  rot=cs.integer("rot", -1 if cs.data.get("omega1", 1) < 0 else 1, choices=(-1, 1)),
                  phi0=math.radians(cs.number("phi0", 0.0, within=lim.ANGLE)))
    cs.done()

    groups = []
    names = set()
    for g in sec.tables("groups"):
        t = g.string("type", choices=GROUP_TYPES)
        gname = g.name("name", "")
        if gname:
            if gname in names:
                raise g.error("name", f"group name {gname!r} is used twice")
            names.add(gname)

        def pnt(key):
            p = g.name(key)
            need(g, key, p)
            return p

        def pair(key, optional=False):
            v = g.names(key, n=2, default=None if optional else _MISSING)
            if v is None:
                return None
            for p in v:
                need(g, key, p)
            if v[0] == v[1]:
                raise g.error(key, "a link needs two different points")
            return v

        def mode(key="W"):
            return g.integer(key, choices=(-1, 1))

        if t == "RRR":
            a, c = pnt("A"), pnt("C")
            b = g.name("B")
            define(g, "B", b)
            grp = RRR(a, c, b, g.number("L_AB", positive=True, within=lim.LENGTH),
                      g.number("L_CB", positive=True, within=lim.LENGTH), mode(), gname)
        elif t == "RRP":
            a, gp = pnt("A"), pnt("guide_point")
            link = pair("guide_link", optional=True)
            b = g.name("B")
            define(g, "B", b)
            grp = RRP(a, b, gp, math.radians(g.number("guide_angle", 0.0, within=lim.ANGLE)),
                      g.number("L_AB", positive=True, within=lim.LENGTH), mode(), link, gname)
        elif t == "RPR":
            blk, piv = pnt("block"), pnt("pivot")
            end = g.name("guide_end")
            define(g, "guide_end", end)
            grp = RPR(blk, piv, end, g.number("guide_length", positive=True, within=lim.LENGTH),
                      g.number("offset", 0.0, within=lim.OFFSET), mode(), gname)
        elif t == "PRP":
            guides = []
            for i in (1, 2):
                gp = pnt(f"guide{i}_point")
                link = pair(f"guide{i}_link", optional=True)
                angle = g.number(f"guide{i}_angle", 0.0, within=lim.ANGLE)
                guides.append((gp, link, math.radians(angle),
                               g.number(f"guide{i}_offset", 0.0, within=lim.OFFSET)))
            if guides[0][1] is None and guides[1][1] is None and \
                    abs(math.sin(guides[1][2] - guides[0][2])) < PARALLEL_SIN:
                raise g.error("guide2_angle", "the two guides are parallel (guide1_angle = "
                              f"{math.degrees(guides[0][2]):g} deg, guide2_angle = "
                              f"{math.degrees(guides[1][2]):g} deg): the blocks' lines never "
                              "meet in one point")
            b = g.name("B")
            define(g, "B", b)
            grp = PRP(b, guides[0][0], guides[0][2], guides[1][0], guides[1][2],
                      guides[0][3], guides[1][3], guides[0][1], guides[1][1], gname)
        elif t == "RPP":
            a, gp = pnt("A"), pnt("guide_point")
            link = pair("guide_link", optional=True)
            slot = math.radians(g.number("slot_angle", 90.0, within=lim.ANGLE))
            if abs(math.sin(slot)) < PARALLEL_SIN:
                raise g.error("slot_angle", f"the slot runs along the guide "
                              f"({math.degrees(slot):g} deg from it): the block cannot move "
                              "the yoke")
            b = g.name("B")
            define(g, "B", b)
            grp = RPP(a, b, gp, math.radians(g.number("guide_angle", 0.0, within=lim.ANGLE)), slot,
                      g.number("guide_offset", 0.0, within=lim.OFFSET),
                      g.number("slot_offset", 0.0, within=lim.OFFSET),
                      link, gname)
        elif t == "class3":
            inp, p6 = pnt("input"), pnt("pivot_4")
            slider = _class3_slider(g, need) if g.has("slider") else None
            if slider is None and not g.has("pivot_5"):
                raise g.error("pivot_5", "required field is missing (or, for a block on a "
                                         "guide in place of lead 5-7, a slider table)")
            p7 = pnt("pivot_5") if slider is None else None
            joints = g.names("joints", n=3)
            for p in joints:
                define(g, "joints", p)
            start = g.numbers("start", n=2, within=lim.ANGLE)
            leads = ("L23", "L34", "L45", "L35", "L46") + (("L57",) if slider is None else ())
            L = {k: g.number(k, positive=True, within=lim.LENGTH) for k in leads}
            if not (L["L45"] < L["L34"] + L["L35"] and L["L34"] < L["L45"] + L["L35"]
                    and L["L35"] < L["L34"] + L["L45"]):
                raise g.error("L45", "the ternary link 3-4-5 is not a triangle "
                                     f"(L34={L['L34']:g}, L45={L['L45']:g}, L35={L['L35']:g})")
            common = dict(a0=math.radians(start[0]), b0=math.radians(start[1]),
                          phi_start=math.radians(g.number("phi_start", 0.0, within=lim.ANGLE)),
                          orientation=g.integer("orientation", 1, choices=(-1, 1)),
                          name=gname or "triad")
            if slider is None:
                grp = ClassIII(inp, p6, p7, joints, **L, **common)
            else:
                point, angle, offset, link = slider
                grp = ClassIIISlider(inp, p6, point, joints, **L, guide_angle=angle,
                                     guide_offset=offset, guide_link=link, **common)
        elif t in ("rotary_input", "slider_input"):
            rotary = t == "rotary_input"
            first, moved = ("pivot", "tip") if rotary else ("guide_point", "block")
            p0 = pnt(first)
            if p0 not in fixed:
                raise g.error(first, f"the {t.replace('_', ' ')}'s {first.replace('_', ' ')} "
                              f"{p0!r} must be a fixed point (mechanism.fixed): the input is "
                              "driven from the frame")
            p1 = g.name(moved)
            define(g, moved, p1)
            law = parse_law(g.table("law"), rotary)
            if rotary:
                grp = RotaryInput(p0, p1, g.number("length", positive=True, within=lim.LENGTH),
                                  law, gname)
            else:
                angle = g.number("guide_angle", 0.0, within=lim.ANGLE)
                grp = SliderInput(p0, p1, math.radians(angle), law,
                                  gname)
        else:  # attach
            base = pnt("base")
            along = pair("along", optional=True)
            p = g.name("point")
            define(g, "point", p)
            grp = Attach(p, base, along, math.radians(g.number("angle", 0.0, within=lim.ANGLE)),
                         g.number("length", positive=True, within=lim.LENGTH), gname)
        g.done()
        groups.append(grp)

    bodies, slides, loads = [], [], []
    body_names = {}
    if sec.has("bodies"):
        for b in sec.tables("bodies"):
            bname = b.name("name")
            if bname in body_names:
                raise b.error("name", f"body name {bname!r} is used twice")
            if f"S[{bname}]" in known:
                raise b.error("name", f"the centre of mass of body {bname!r} is the point "
                                      f"'S[{bname}]', and the mechanism has a point of that "
                                      "name already (mechanism.fixed or a group's): rename one")
            joints = b.names("joints")
            for p in joints:
                need(b, "joints", p)
            cm = b.table("com")
            base = cm.name("base")
            need(cm, "base", base)
            along = cm.names("along", n=2, default=None)
            for p in along or ():
                need(cm, "along", p)
            com = CentreOfMass(base, along, cm.number("lS", 0.0, within=lim.OFFSET),
                               math.radians(cm.number("US", 0.0, within=lim.ANGLE)))
            cm.done()
            turns = b.names("turns_with", n=2, default=None)
            for p in turns or ():
                need(b, "turns_with", p)
            body = Body(bname, joints, b.number("mass", positive=True, within=lim.MASS),
                        b.number("J_S", 0.0), com, turns)
            if body.J_S < 0:
                raise b.error("J_S", "must not be negative")
            b.check_range("J_S", body.J_S, lim.INERTIA)
            b.done()
            body_names[bname] = b.path("name")
            bodies.append(body)
        _check_joints(sec, bodies, fixed)
    _check_labels(sec, groups, bodies)
    if sec.has("slides"):
        for s in sec.tables("slides"):
            slider = s.name("slider")
            guide = s.name("guide", "ground")
            for key, v in (("slider", slider), ("guide", guide)):
                if v != "ground" and v not in body_names:
                    raise s.error(key, f"unknown body {v!r}")
            along = s.names("along", n=2, default=None)
            for p in along or ():
                need(s, "along", p)
            slides.append(Slide(slider, None if guide == "ground" else guide,
                                math.radians(s.number("angle", 0.0, within=lim.ANGLE)), along))
            s.done()
            slides[-1] = _check_slide(s, slides[-1], groups, bodies, fixed)
    if sec.has("loads"):
        from .expressions import parse_expression
        for ld in sec.tables("loads"):
            body = ld.name("body")
            if body not in body_names:
                raise ld.error("body", f"unknown body {body!r}")
            point = ld.name("point", "")
            if point:
                need(ld, "point", point)
            comp = {}
            for key in ("fx", "fy", "moment"):
                v = ld.raw(key, 0.0)
                comp[key] = parse_expression(v, f"{ld.file}: {ld.path(key)}")
            if point == "" and not (comp["fx"].is_constant and comp["fx"].evaluate(0.0) == 0
                                    and comp["fy"].is_constant and comp["fy"].evaluate(0.0) == 0):
                raise ld.error("point", "a load with a force needs the point it acts at")
            loads.append(Load(body, point or None, comp["fx"], comp["fy"], comp["moment"],
                              where=f"{ld.file}: {ld.where}"))
            ld.done()
    gravity = sec.number("gravity", 9.81, within=lim.GRAVITY)
    sec.done()
    return Mechanism(name=name, fixed=fixed, crank=crank, groups=tuple(groups),
                     bodies=tuple(bodies), slides=tuple(slides), loads=tuple(loads),
                     gravity=gravity)


def parse_law(s: Section, rotary: bool) -> Law:
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
    swings unseen, and the peaks refined from the positions' samples would be
    wrong (an OK with a peak acceleration a thousand times too small)."""
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


def _check_law_grids(path, mech, output, sweep):
    """Every input law resolved by the positions that sample it: the scene's
    dense revolution (a sweep's candidates are shown as scenes too) and a
    sweep's positions; a swept rise_angle at both ends of its bounds."""
    grids = [(output.dense_positions, "output.dense_positions")]
    if sweep is not None:
        grids.append((sweep.positions, "sweep.positions"))
    positions, where = min(grids)
    for k, g in enumerate(mech.groups):
        law = getattr(g, "law", None)
        if law is None:
            continue
        problem = law_grid_problem(law, positions)
        if problem:
            key, reason = problem
            raise StudyError(path, f"mechanism.groups[{k}].law.{key}",
                             f"{reason} ({where} = {positions:,})")
    if sweep is None:
        return
    labels = mech.compile().group_names
    for v in sweep.variables:
        owner, _, key = v.param.rpartition(".")
        if key != "rise_angle":
            continue
        law = mech.groups[labels.index(owner) - 1].law       # group_names[0]: the crank
        for end, x in (("min", v.low), ("max", v.high)):
            problem = law_grid_problem(replace(law, rise=x * v.factor), positions)
            if problem:
                raise StudyError(path, f"sweep.variables.{_key(v.name)}.{end}",
                                 f"{v.param} = {x:g} {v.units}: {problem[1]} ({where} = "
                                 f"{positions:,})")


def _class3_slider(g: Section, need):
    """The ``slider`` table of a class III group whose lead 5-7 is a block on a
    guide: (guide point, angle rad, offset mm, guide link or None).  The table
    replaces ``pivot_5`` and ``L57``."""
    for key in ("pivot_5", "L57"):
        if g.has(key):
            raise g.error(key, "a class III group with a slider has no lead 5-7: the slider "
                               "table (point, angle, offset) takes the place of pivot_5 and L57")
    s = g.table("slider")
    point = s.name("point")
    need(s, "point", point)
    link = s.names("link", n=2, default=None)
    if link is not None:
        for p in link:
            need(s, "link", p)
        if link[0] == link[1]:
            raise s.error("link", "a link needs two different points")
    angle = math.radians(s.number("angle", within=lim.ANGLE))
    offset = s.number("offset", 0.0, within=lim.OFFSET)
    s.done()
    return point, angle, offset, link


def _check_labels(sec, groups, bodies):
    """A group's name is the label of its parameters (label.key: the sweep's
    variables name them): it must differ from the labels the plan gives the
    crank ('crank'), the unnamed groups ('RRR[2]': type and position) and the
    centres of mass ('S[body]')."""
    taken = {"crank": "the crank"}
    for k, g in enumerate(groups, start=1):
        if not g.name:
            taken[group_label(g, k)] = f"the unnamed group mechanism.groups[{k - 1}]"
    for b in bodies:
        taken[f"S[{b.name}]"] = f"the centre of mass of body {b.name!r}"
    for k, g in enumerate(groups, start=1):
        if g.name in taken:
            raise StudyError(sec.file, f"{sec.path('groups')}[{k - 1}].name",
                             f"the group name {g.name!r} is the label of {taken[g.name]} "
                             "(parameters are named label.key): choose another name")


def _check_joints(sec, bodies, fixed):
    """Every point shared by bodies is a revolute joint of exactly two of them
    (or of one body and the ground)."""
    owners = {}
    for b in bodies:
        for p in b.joints:
            owners.setdefault(p, []).append(b.name)
    for p, who in owners.items():
        n = len(who) + (1 if p in fixed else 0)
        if n > 2:
            raise sec.error("bodies", f"point {p!r} joins {n} links ({', '.join(who)}"
                            + (", ground" if p in fixed else "") + "); only binary joints are "
                            "supported: split it into two points")


# ----------------------------------------------------------------- slides against the guides
SLIDE_ANGLE_TOL = math.radians(1e-3)   # rad: two lines closer than 0.001 deg are one


def _deg(angle):
    return f"{math.degrees(angle):g} deg"


def _along_words(link, angle):
    return f"along {link[0]}->{link[1]} + {_deg(angle)}" if link else f"at {_deg(angle)}"


def _guides(groups, fixed):
    """The sliding pairs the groups define: (who, point, (link, angle), host,
    words, params).  The slider carries ``point``; the guide's direction is
    the link a->b turned by angle, or the absolute angle (link None); host:
    the points the guide's body carries (None: the ground); params: the
    group's parameters (plan names) whose sum is that angle."""
    out = []
    for k, g in enumerate(groups):
        kind = type(g).__name__
        who = (f"the {kind} group {g.name!r}" if g.name
               else f"the {kind} group mechanism.groups[{k}]")
        label = group_label(g, k + 1)
        n = len(out)

        def host(point, link):
            return link if link else (None if point in fixed else (point,))

        def words(link, angle):
            return _along_words(link, angle) + ("" if link else " (absolute)")

        if isinstance(g, RRP):
            out.append((who, g.B, (g.guide_link, g.guide_angle),
                        host(g.guide_point, g.guide_link), words(g.guide_link, g.guide_angle)))
        elif isinstance(g, RPR):
            out.append((who, g.block, ((g.pivot, g.guide_end), 0.0), (g.pivot,),
                        f"along {g.pivot}->{g.guide_end} (its guide, turning about {g.pivot})"))
        elif isinstance(g, PRP):
            for i, (gp, link, angle) in enumerate(
                    ((g.guide1_point, g.guide1_link, g.guide1_angle),
                     (g.guide2_point, g.guide2_link, g.guide2_angle)), start=1):
                out.append((who, g.B, (link, angle), host(gp, link),
                            f"on guide {i} {words(link, angle)}"))
        elif isinstance(g, RPP):
            out.append((who, g.B, (g.guide_link, g.guide_angle), host(g.guide_point, g.guide_link),
                        words(g.guide_link, g.guide_angle)))
            out.append((who, g.A, (g.guide_link, g.guide_angle + g.slot_angle), (g.B,),
                        f"along its slot, {_deg(g.slot_angle)} from its guide "
                        f"{words(g.guide_link, g.guide_angle)}"))
        elif isinstance(g, SliderInput):
            out.append((who, g.block, (None, g.guide_angle), None,
                        words(None, g.guide_angle)))
        elif isinstance(g, ClassIIISlider):
            out.append((who, g.joints[2], (g.guide_link, g.guide_angle),
                        host(g.guide_point, g.guide_link), words(g.guide_link, g.guide_angle)))
        keys = {RRP: [("guide_angle",)], PRP: [("guide1_angle",), ("guide2_angle",)],
                RPP: [("guide_angle",), ("guide_angle", "slot_angle")],
                SliderInput: [("guide_angle",)],
                ClassIIISlider: [("guide_angle",)]}.get(type(g), [()] * (len(out) - n))
        out[n:] = [o + (tuple(f"{label}.{key}" for key in ks),) for o, ks in zip(out[n:], keys)]
    return out


def _same_directions(groups):
    """{(a, b): (link, angle)}: the direction a->b is that of ``link`` turned
    by ``angle`` (the absolute angle where link is None), modulo 180 deg, by
    the groups' own geometry: an attached point, a coulisse without offset
    (pivot->block along its guide), a guide's point and the point sliding on
    it without offset (RRP, PRP, RPP), the yoke's point and the block in its
    slot without offset."""
    same = {}
    for g in groups:
        if isinstance(g, Attach):
            same.setdefault((g.base, g.point), (g.along, g.angle))
        elif isinstance(g, RPR) and g.offset == 0.0:
            same.setdefault((g.pivot, g.block), ((g.pivot, g.guide_end), 0.0))
        elif isinstance(g, RRP):
            same.setdefault((g.guide_point, g.B), (g.guide_link, g.guide_angle))
        elif isinstance(g, PRP):
            for gp, link, angle, off in ((g.guide1_point, g.guide1_link, g.guide1_angle,
                                          g.guide1_offset),
                                         (g.guide2_point, g.guide2_link, g.guide2_angle,
                                          g.guide2_offset)):
                if off == 0.0:
                    same.setdefault((gp, g.B), (link, angle))
        elif isinstance(g, RPP):
            if g.guide_offset == 0.0:
                same.setdefault((g.guide_point, g.B), (g.guide_link, g.guide_angle))
            if g.slot_offset == 0.0:
                same.setdefault((g.B, g.A), (g.guide_link, g.guide_angle + g.slot_angle))
        elif isinstance(g, SliderInput):
            same.setdefault((g.guide_point, g.block), (None, g.guide_angle))
        elif isinstance(g, ClassIIISlider) and g.guide_offset == 0.0:
            same.setdefault((g.guide_point, g.joints[2]), (g.guide_link, g.guide_angle))
    return same


def _reduce(direction, same, fixed):
    """A direction (link, angle) rewritten through ``same`` and the fixed
    points until its link is none (absolute) or one nothing rewrites; the
    link's ends in name order (the angle turned by 180 deg if swapped)."""
    link, angle = direction
    for _ in range(64):
        if link is None:
            return None, angle
        a, b = link
        if a in fixed and b in fixed:
            dx, dy = fixed[b][0] - fixed[a][0], fixed[b][1] - fixed[a][1]
            if dx or dy:
                return None, angle + math.atan2(dy, dx)
        if (a, b) in same:
            link, turn = same[(a, b)]
        elif (b, a) in same:
            link, turn = same[(b, a)]
            turn += math.pi
        else:
            break
        angle += turn
    return (tuple(link), angle) if link[0] <= link[1] else ((link[1], link[0]), angle + math.pi)


def _carries(body, groups):
    """The points a body is declared to carry: its joints, its centre of mass's
    base and along link, what it turns with, and the points attached to those
    (attach groups, a coulisse's guide end)."""
    pts = set(body.joints) | {body.com.base}
    pts |= set(body.com.along or ()) | set(body.turns_with or ())
    for g in groups:
        if isinstance(g, Attach) and g.base in pts and set(g.along or ()) <= pts:
            pts.add(g.point)
        elif isinstance(g, RPR) and g.pivot in pts:
            pts.add(g.guide_end)
    return pts


def _check_slide(s: Section, slide: Slide, groups, bodies, fixed):
    """Refuse a slide whose direction contradicts the guide of the group whose
    sliding pair it is (its forces would be silently wrong).

    The pair: the slider body has the group's sliding point among its joints
    (or as its centre of mass's base), and the slide's guide is the ground for
    a guide of fixed direction through a fixed point, else a body that carries
    the guide's link (or its point).  Only one pair may match (or all matches
    agree); an ambiguous slide is not checked.  Both directions are reduced
    through the groups' geometry (``_same_directions``) and the fixed points;
    it is an error when

    * they come down to the same link (or both to absolute angles) and differ
      by more than 0.001 deg modulo 180 deg (``.angle``);
    * the slide follows a link that neither the slider nor its guide carries
      (``.along``);
    * the guide turns with a link, the slide's guide body turns (it declares
      turns_with or a centre of mass along a link), and the slide gives a fixed
      angle (``.along``).

    Anything else (e.g. another link of the guide's own body) is not flagged:
    its angle to the guide's link is not known before the kinematics.

    Returns the slide, following the guide's angle parameters (``follows``)
    where it is written along the guide's own link (or both are absolute):
    a sweep that turns the guide turns the slide with it."""
    by_name = {b.name: b for b in bodies}
    slider = by_name[slide.slider]
    guide = by_name[slide.guide] if slide.guide else None
    guide_pts = _carries(guide, groups) if guide else None
    same = _same_directions(groups)
    matches = []
    for who, point, direction, host, words, params in _guides(groups, fixed):
        if point not in slider.joints and point != slider.com.base:
            continue
        if (host is None) != (guide is None) or (host and not set(host) <= guide_pts):
            continue
        matches.append((who, point, _reduce(direction, same, fixed), words, direction, params))
    if not matches:
        return slide
    (who, point, (glink, gangle), words, direction, params) = matches[0]
    for m in matches[1:]:
        if m[2][0] != glink or abs(math.sin(m[2][1] - gangle)) > math.sin(SLIDE_ANGLE_TOL):
            return slide    # ambiguous: the slider carries the sliding point of two pairs
    slink, sangle = _reduce((slide.along, slide.angle), same, fixed)
    says = _along_words(slide.along, slide.angle) if slide.along else _deg(slide.angle)
    guide_words = f"{who} guides {point} {words}"
    if slink == glink:
        if abs(math.sin(sangle - gangle)) > math.sin(SLIDE_ANGLE_TOL):
            raise s.error("angle", f"{guide_words}; this slide says {says} (lines "
                                   f"{_fold_deg(sangle - gangle):.4g} deg apart: the slide's "
                                   "normal force would be taken across the wrong line)")
        if params and slide.along == direction[0]:
            # written along the guide's own link (or both absolute): the slide turns with
            # the guide's parameters when a sweep varies them
            return replace(slide, follows=params, follows_declared=direction[1])
        return slide
    if slide.along and not (set(slide.along) <= fixed.keys()):
        pts = _carries(slider, groups) | (guide_pts or set(fixed))
        if not set(slide.along) <= pts:
            a, b = slide.along
            raise s.error("along", f"this slide follows {a}->{b}, a link of neither the slider "
                                   f"{slide.slider!r} nor its guide "
                                   f"{slide.guide or 'ground'!r}; {guide_words}")
    if slink is None and glink is not None and guide is not None and \
            (guide.turns_with or guide.com.along):
        raise s.error("along", f"{guide_words}, turning with its body {guide.name!r}; this "
                               f"slide gives the fixed direction {_deg(slide.angle)} (give "
                               "along = [a, b], a link of the guide's body, and the angle "
                               "from it)")
    return slide


def _fold_deg(angle):
    """The angle between two lines that differ by ``angle``, in [0, 90] deg."""
    return math.degrees(math.atan2(abs(math.sin(angle)), abs(math.cos(angle))))


def parse_link(s: Section, key, label, known):
    try:
        a, b = label.split("_")
    except ValueError:
        raise s.error(key, f"link {label!r} must be written a_b (from point Pa to point Pb)") from None
    pa = a if a in known else f"P{a}"
    pb = b if b in known else f"P{b}"
    for p in (pa, pb):
        if p not in known:
            raise s.error(key, f"link {label!r}: unknown point {p!r}")
    return pa, pb


def _parse_pins(sec: Section, mech: Mechanism) -> dict:
    """[output.pins]: length (mm) and allowable bending stress sigma (MPa) of the
    pins, and per joint (R1 = { length = 14.0 }) where one differs."""
    if not sec.has("pins"):
        return {}
    p = sec.table("pins")
    length = p.number("length", 10.0, positive=True, within=lim.LENGTH)
    sigma = p.number("sigma", 200.0, positive=True, within=lim.STRESS)
    joints = set(mech.compile().joint_names)
    over = []
    for key in [k for k in p.data if k not in ("length", "sigma")]:
        if key not in joints:
            raise p.error(key, f"unknown joint {_quote(key)}; joints: "
                               f"{', '.join(sorted(joints))}")
        j = p.table(key)
        over.append((key, j.number("length", length, positive=True, within=lim.LENGTH),
                     j.number("sigma", sigma, positive=True, within=lim.STRESS)))
        j.done()
    p.done()
    return {"pin_length": length, "pin_sigma": sigma, "pin_overrides": tuple(over)}


def parse_output(sec: Section, mech: Mechanism) -> OutputSpec:
    known = set(mech.fixed) | {mech.crank.tip}
    for g in mech.groups:
        known.update(g.writes())
    # a link's label is a_b (two point names, or their numbers n of Pn)
    labels = sec.names("links", default=[], maximum=2 * MAX_NAME_LENGTH + 1) or ()
    links = tuple(parse_link(sec, "links", lab, known) for lab in labels)
    wp = sec.name("working_point", mech.groups[-1].writes()[-1] if mech.groups else mech.crank.tip)
    if wp not in known:
        raise sec.error("working_point", f"unknown point {wp!r}")
    rocker = None
    if sec.has("rocker"):
        rocker = sec.names("rocker", n=2)
        for p in rocker:
            if p not in known:
                raise sec.error("rocker", f"unknown point {p!r}")
    law = None
    if sec.has("motion_law"):
        from .motion_law import parse_motion_law
        if rocker is None:
            raise sec.error("motion_law", "a motion law is the output rocker's: give "
                                          "output.rocker = [pivot, point]")
        law = parse_motion_law(sec.table("motion_law"))
    default = "forces" if mech.bodies else "accelerations"
    analysis = sec.string("analysis", default, choices=ANALYSES)
    if analysis == "forces" and not mech.bodies:
        raise sec.error("analysis", "force analysis needs mass data: declare [[mechanism.bodies]]")
    out = OutputSpec(working_point=wp, links=links, link_labels=tuple(labels),
                     table_positions=sec.integer("table_positions", 12, minimum=2,
                                                 maximum=MAX_POSITIONS, why=POSITIONS_WHY),
                     dense_positions=sec.integer("dense_positions", 360, minimum=4,
                                                 maximum=MAX_POSITIONS, why=POSITIONS_WHY),
                     analysis=analysis, rocker=rocker, motion_law=law,
                     dwell_deg=sec.number("dwell", 150.0, positive=True),
                     **_parse_pins(sec, mech))
    if not out.dwell_deg < 360:
        raise sec.error("dwell", "must be less than 360 deg")
    sec.done()
    return out


def parse_dynamics(sec: Section, mech: Mechanism) -> DynamicsSpec:
    from .expressions import parse_expression
    if not mech.bodies:
        raise sec.error("", "crank dynamics needs mass data: declare [[mechanism.bodies]]")
    method = sec.string("method", "rk4", choices=("rk4", "dop853"))
    cases = []
    names = set()
    for c in sec.tables("cases"):
        name = c.name("name")
        if name in names or not name.replace("_", "").isalnum():
            raise c.error("name", f"case name {name!r} must be unique and made of letters, "
                                  "digits and _")
        names.add(name)
        t_end = c.number("t_end", 10.0, positive=True, within=lim.DURATION)
        # RK4 step: 1e-4 s keeps phi1 within 1e-7 rad of DOP853 over 10 s at ~125 rad/s
        dt = c.number("dt", 1e-4, positive=True, within=lim.DURATION)
        sample = c.number("sample_dt", 0.01, positive=True, within=lim.DURATION)
        if dt > sample:
            raise c.error("dt", f"the integration step {dt:g} s exceeds the sampling step {sample:g} s")
        if abs(sample / dt - round(sample / dt)) > 1e-9 * (sample / dt):
            raise c.error("dt", f"the sampling step {sample:g} s must be a whole number of "
                                f"integration steps (dt = {dt:g} s)")
        if abs(t_end / sample - round(t_end / sample)) > 1e-9 * (t_end / sample):
            raise c.error("t_end", f"t_end = {t_end:g} s must be a whole number of sampling "
                                   f"steps (sample_dt = {sample:g} s)")
        if t_end / dt > lim.MAX_DYNAMICS_STEPS:
            raise c.error("t_end", f"t_end / dt = {t_end / dt:,.0f} integration steps; at most "
                                   f"{lim.MAX_DYNAMICS_STEPS:,} ({lim.DYNAMICS_STEPS_WHY})")
        if t_end / sample > lim.MAX_DYNAMICS_SAMPLES:
            raise c.error("t_end", f"t_end / sample_dt = {t_end / sample:,.0f} samples; at most "
                                   f"{lim.MAX_DYNAMICS_SAMPLES:,} ({lim.DYNAMICS_SAMPLES_WHY})")
        cases.append(DynamicsCase(
            name=name, phi_start=math.radians(c.number("phi_start", within=lim.ANGLE)),
            omega_start=c.number("omega_start", 0.0, within=lim.OMEGA),
            M1=parse_expression(c.raw("M1", 0.0), f"{c.file}: {c.path('M1')}"),
            damping=c.number("damping", 0.0), t_end=t_end, dt=dt, sample_dt=sample))
        if cases[-1].damping < 0:
            raise c.error("damping", "must not be negative")
        c.check_range("damping", cases[-1].damping, lim.DAMPING)
        c.done()
        # M1 and the loads must be constant, 2*pi-periodic in phi, or functions of t alone
        from .dynamics import check_drive
        check_drive(mech, cases[-1], c.file)
    sec.done()
    return DynamicsSpec(cases=tuple(cases), method=method)


def stored_study(attrs, results_path=None):
    """The study rebuilt from the TOML stored verbatim in a results file's root
    attributes; None if the file has none.  Its errors name the results file
    (the stored copy is what is wrong, not the study file it came from)."""
    from .storage import attr_text
    text = attrs.get("study_toml")
    if not text:
        return None
    origin = str(attr_text(attrs.get("study_file", "?")))
    # the file's own word for where it came from is data too: shown quoted where it
    # is not one printable line (a message stays one line)
    shown = origin if origin.isprintable() and len(origin) <= 4096 else _quote(origin, 200)
    label = f"{results_path} (the study stored from {shown})" if results_path else shown
    study = parse_study(str(attr_text(text)), label)
    return replace(study, path=Path(origin))
