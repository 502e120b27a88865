"""Study files (TOML) -> frozen dataclasses, with errors that name the file,
the field and the reason.

A study is a "scene" (one mechanism: tables, curves, pictures) or a "sweep"
(a Monte-Carlo search over a mechanism's dimensions, see ``pipeline.runs.sweep``).
Both declare the mechanism in ``[mechanism]``; angles are in degrees in the
file and radians in the model.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

from ..base import limits as lim
from ..base.errors import StudyError
from ..model.groups import GROUP_TYPES as _GROUP_CLASSES, SOLVED_KEYS, SOLVED_LISTS
from ..model.groups.law import law_grid_problem
from ..base.limits import (MAX_NAME_LENGTH, MAX_POSITIONS, MAX_STUDY_BYTES, MAX_TITLE_LENGTH,
                           POSITIONS_WHY, STUDY_BYTES_WHY, TITLE_WHY)
from ..model.mechanism import Body, CentreOfMass, Crank, Load, Mechanism, Slide, group_label
from .slide_check import check_slide as _check_slide
# the study file's tables (the reader of every section)
from .section import _MISSING, Section, _key, _quote
from .dynamics_spec import DynamicsSpec, parse_dynamics


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
    motion_law: object = None    # pipeline.model.motion_law.MotionLaw: [output.motion_law]

    def pins(self, joint_names):
        """(length mm, allowable stress MPa) of every joint's pin."""
        over = {j: (length, sigma) for j, length, sigma in self.pin_overrides}
        return [over.get(j, (self.pin_length, self.pin_sigma)) for j in joint_names]


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
    sweep: object = None     # pipeline.study.sweep_spec.SweepSpec for kind = "sweep"
    search: object = None    # pipeline.study.search_spec.SearchSpec: a sweep study's [search]
    tolerance: object = None  # pipeline.study.tolerance_spec.ToleranceSpec: [tolerance]
    cycle: object = None     # pipeline.model.cycle.Cycle: [cycle], the machine's cyclogram
    extra: dict = field(default_factory=dict)
    # the CAD reports its bodies read (cad = { report = ... }): {as written: text},
    # kept in a results file beside the study's text
    cad_reports: dict = field(default_factory=dict)
    # what those reports place on the mechanism (cad_report.CadReports.bodies): where
    # each centre of mass lies is checked where the study is run, on its solved points
    cad_bodies: tuple = ()


KINDS = ("scene", "sweep")
ANALYSES = ("positions", "velocities", "accelerations", "forces")


HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"    # the first bytes of every HDF5 file


def load_study(path) -> Study:
    """Read and validate a study file."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            if f.read(8) == HDF5_SIGNATURE:
                raise StudyError(path, "", "is an HDF5 file (a results file?), not a study: "
                                           "`pipeline run` takes a study's TOML file; browse, "
                                           "show, report, export and tolerance read results "
                                           "files")
        # at most one character past the limit is read (a huge file, /dev/zero)
        with open(path, encoding="utf-8") as f:
            text = f.read(MAX_STUDY_BYTES + 1)
    except FileNotFoundError:
        raise StudyError(path, "", "file not found") from None
    except (OSError, UnicodeDecodeError) as e:
        raise StudyError(path, "", f"cannot read: {e}") from None
    return parse_study(text, path)


def parse_study(text: str, path="<study>", cad_reports=None) -> Study:
    """A study from its text; ``cad_reports``: the CAD reports its bodies read
    ({as written: text}, a results file's copies), else they are read from the
    study file's folder."""
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
    from .cad_report import CadReports
    cad = CadReports(Path(str(path)).parent, cad_reports, origin=path)
    mech = parse_mechanism(root.table("mechanism"), name, cad)
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
    cycle = None
    if root.has("cycle"):
        from .cycle_spec import parse_cycle
        cycle = parse_cycle(root.table("cycle"), output)
    tolerance = None
    if root.has("tolerance"):
        from .tolerance_spec import parse_tolerance
        tolerance = parse_tolerance(root, mech, output, sweep)
    root.done()
    return Study(path=Path(path), text=text, kind=kind, name=name, title=title,
                 mechanism=mech, output=output, dynamics=dynamics, sweep=sweep, search=search,
                 tolerance=tolerance, cycle=cycle, cad_reports=cad.texts,
                 cad_bodies=tuple(cad.bodies))


# ----------------------------------------------------------------- mechanism
GROUP_TYPES = tuple(_GROUP_CLASSES)      # the study's group `type`s (pipeline.model.groups)


class Fields:
    """What a group type's parser (``GroupType.parse``) reads its points with:
    a known point, a link of two, a point it solves, the assembly mode; and
    the fixed points."""

    def __init__(self, fixed, need, define):
        self.fixed = fixed
        self.need = need            # need(section, key, point): refuse an unknown point
        self._define = define

    def point(self, s, key):
        """A known point (solved by the crank or a group before)."""
        p = s.name(key)
        self.need(s, key, p)
        return p

    def pair(self, s, key, optional=False):
        """A link (a, b) of two known points, or None where optional and absent."""
        v = s.names(key, n=2, default=None if optional else _MISSING)
        if v is None:
            return None
        for p in v:
            self.need(s, key, p)
        if v[0] == v[1]:
            raise s.error(key, "a link needs two different points")
        return v

    def define(self, s, key, p=None):
        """A point the group solves (its name read from ``key`` unless given)."""
        if p is None:
            p = s.name(key)
        self._define(s, key, p)
        return p

    def mode(self, s, key="W"):
        return s.integer(key, choices=(-1, 1))


def parse_mechanism(sec: Section, name: str, cad=None) -> Mechanism:
    """``cad``: where bodies with cad = { report = ... } read their reports
    (``cad_report.CadReports``; default: the study file's folder)."""
    if cad is None:
        from .cad_report import CadReports
        cad = CadReports(Path(str(sec.file)).parent)
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
            for key in SOLVED_KEYS:
                if isinstance(g.get(key), str):
                    later.setdefault(g[key], f"{sec.path('groups')}[{i}].{key}")
            for key in SOLVED_LISTS:
                if isinstance(g.get(key), list):
                    for p in g[key]:
                        if isinstance(p, str):
                            later.setdefault(p, f"{sec.path('groups')}[{i}].{key}")

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
    fields = Fields(fixed, need, define)
    for g in sec.tables("groups"):
        t = g.string("type", choices=GROUP_TYPES)
        gname = g.name("name", "")
        if gname:
            if gname in names:
                raise g.error("name", f"group name {gname!r} is used twice")
            names.add(gname)
        grp = _GROUP_CLASSES[t].parse(g, fields, gname)
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
            cad_sec = b.table("cad", default=None)
            if cad_sec is not None:         # mass data from a CAD report
                mass, J_S, com = cad.body_data(b, cad_sec, need, sec.file)
            else:
                cm = b.table("com")
                base = cm.name("base")
                need(cm, "base", base)
                along = cm.names("along", n=2, default=None)
                for p in along or ():
                    need(cm, "along", p)
                com = CentreOfMass(base, along, cm.number("lS", 0.0, within=lim.OFFSET),
                                   math.radians(cm.number("US", 0.0, within=lim.ANGLE)))
                cm.done()
                mass = b.number("mass", positive=True, within=lim.MASS)
                J_S = b.number("J_S", 0.0)
            turns = b.names("turns_with", n=2, default=None)
            for p in turns or ():
                need(b, "turns_with", p)
            body = Body(bname, joints, mass, J_S, com, turns)
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
        from ..base.expressions import parse_expression
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
    friction = sec.table("friction", default=None)
    sec.done()
    mech = Mechanism(name=name, fixed=fixed, crank=crank, groups=tuple(groups),
                     bodies=tuple(bodies), slides=tuple(slides), loads=tuple(loads),
                     gravity=gravity)
    if friction is not None:        # [mechanism.friction]: absent, the frictionless forces
        from .friction_spec import parse_friction
        mech = replace(mech, friction=parse_friction(friction, mech))
    return mech


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


def _check_labels(sec, groups, bodies):
    """A group's name is the label of its parameters (label.key: the sweep's
    variables name them): it must differ from the labels the plan gives the
    crank ('crank'), the unnamed groups (their type and position: 'TYPE[2]') and the
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
        from ..model.motion_law import parse_motion_law
        if rocker is None:
            raise sec.error("motion_law", "a motion law is the output rocker's: give "
                                          "output.rocker = [pivot, point]")
        law = parse_motion_law(sec.table("motion_law"))
    default = "forces" if mech.bodies else "accelerations"
    analysis = sec.string("analysis", default, choices=ANALYSES)
    if analysis == "forces" and not mech.bodies:
        raise sec.error("analysis", "force analysis needs mass data: declare [[mechanism.bodies]]")
    if mech.friction is not None and analysis != "forces":
        raise sec.error("analysis", "[mechanism.friction] acts on the forces: "
                                    f"analysis = \"forces\", got {_quote(analysis)}")
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


def stored_study(attrs, results_path=None):
    """The study rebuilt from the TOML stored verbatim in a results file's root
    attributes; None if the file has none.  Its errors name the results file
    (the stored copy is what is wrong, not the study file it came from)."""
    def attr_text(v):        # an HDF5 string attribute (h5py may hand back bytes)
        return v.decode() if isinstance(v, bytes) else v
    text = attrs.get("study_toml")
    if not text:
        return None
    origin = str(attr_text(attrs.get("study_file", "?")))
    # the file's own word for where it came from is data too: shown quoted where it
    # is not one printable line (a message stays one line)
    shown = origin if origin.isprintable() and len(origin) <= 4096 else _quote(origin, 200)
    label = f"{results_path} (the study stored from {shown})" if results_path else shown
    # the CAD reports its bodies read, kept beside it (none kept: none read now either)
    reports = attrs.get("cad_reports")
    import json
    reports = json.loads(attr_text(reports)) if reports is not None else {}
    study = parse_study(str(attr_text(text)), label, cad_reports=reports)
    return replace(study, path=Path(origin))
