"""Mass properties from a CAD report: a body's mass data read from the file the
CAD program saves instead of typed into the study (``cad = { report = ... }`` in
``[[mechanism.bodies]]``).

Two formats:

* the text report SolidWorks' Mass Properties dialog saves (``Save``)::

      Mass properties of crank
           Configuration: Default
           Coordinate system: -- default --
      Density = 0.01 grams per cubic millimeter          (optional)
      Mass = 910.00 grams
      Volume = ... / Surface area = ...                   (optional)
      Center of mass: ( millimeters )
              X = 26.21
              Y = 0.00
              Z = 0.00
      Principal axes of inertia ... ( ... )               (optional, not read)
      Moments of inertia: ( grams * square millimeters )
      Taken at the center of mass and aligned with the output coordinate system.
              Lxx = ...   Lxy = ...   Lxz = ...
              Lyx = ...   Lyy = ...   Lyz = ...
              Lzx = ...   Lzy = ...   Lzz = 1189631.00
      Moments of inertia: ( ... )  Taken at the output coordinate system.  (not read)

  Whitespace and tabs are free; a decimal comma (as SolidWorks writes numbers
  on a system whose decimal separator is the comma) reads as a point; the
  units are the report's own (grams, kilograms, pounds; millimeters,
  centimeters, meters, inches, feet).

* a neutral CSV for other CAD programs, one row per part: ``name, mass, unit,
  x, y, z, length unit, Lzz, inertia unit`` (optionally ``Lxz, Lyz`` after
  them), an optional header row, ``;`` as the separator where the numbers
  carry decimal commas; units as words or symbols (``g``, ``kg``, ``lb``;
  ``mm``, ``cm``, ``m``, ``in``, ``ft``; ``kg*m^2``, ``g*mm^2``,
  ``grams * square millimeters``).

The part's coordinate system: its origin at a joint of the link, its x axis
along a link vector, z normal to the mechanism's plane.  The centre of mass
(x, y) in that frame is then, in DOMAIN.md section 6's terms, S = origin +
rot(x-axis vector, US, lS) with lS = |(x, y)| and US = atan2(y, x)
(``link_frame``); J_S is Lzz, the moment about z taken at the centre of mass.

Nothing of a report's text becomes code: it is matched line by line against
the patterns below, and a number is a number or an error naming the file and
the line.
"""

from __future__ import annotations

import csv
import io
import math
import re
from dataclasses import dataclass
from pathlib import Path

from ..base import limits as lim
from ..base.errors import StudyError

MAX_REPORT_BYTES = 1_000_000   # a part's report is a few kB; a bigger file is not one

# the products of inertia Lxz, Lyz against Lzz beyond which the part is not
# symmetric about the mechanism's plane (the planar model loses their moment)
PRODUCT_RATIO_WARN = 0.01

# units -> kg, mm: the words SolidWorks writes and the usual symbols
MASS_UNITS = {"grams": 1e-3, "gram": 1e-3, "g": 1e-3,
              "kilograms": 1.0, "kilogram": 1.0, "kg": 1.0,
              "pounds": 0.45359237, "pound": 0.45359237, "lb": 0.45359237,
              "lbs": 0.45359237, "lbm": 0.45359237}
LENGTH_UNITS = {"millimeters": 1.0, "millimetres": 1.0, "millimeter": 1.0,
                "millimetre": 1.0, "mm": 1.0,
                "centimeters": 10.0, "centimetres": 10.0, "cm": 10.0,
                "meters": 1000.0, "metres": 1000.0, "meter": 1000.0, "metre": 1000.0,
                "m": 1000.0,
                "inches": 25.4, "inch": 25.4, "in": 25.4,
                "feet": 304.8, "foot": 304.8, "ft": 304.8}
MASS_WORDS = "grams, kilograms or pounds (g, kg, lb)"
LENGTH_WORDS = "millimeters, centimeters, meters, inches or feet (mm, cm, m, in, ft)"
INERTIA_WORDS = ("a mass unit times a square length unit ('grams * square millimeters', "
                 "'kg*m^2')")
CSV_FIELDS = ("name", "mass", "unit", "x", "y", "z", "length unit", "Lzz", "inertia unit")


@dataclass(frozen=True)
class MassProperties:
    """One part's mass properties, in the study's units: kg, mm in the part's
    frame, kg*m^2; where each came from (lines of the report) and the units
    as the report stated them."""
    file: str
    part: str                  # the report's name for the part ('' where it gives none)
    mass: float                # kg
    x: float                   # mm: the centre of mass in the part's frame
    y: float
    z: float
    J_S: float                 # kg*m^2: Lzz, about z at the centre of mass
    Lxz: float = 0.0           # kg*m^2: the products of inertia (0 where not given)
    Lyz: float = 0.0
    units: str = ""            # the report's units, as it states them
    mass_line: int = 0
    com_line: int = 0
    inertia_line: int = 0

    def link_frame(self):
        """(lS mm, US rad): the centre of mass as DOMAIN.md section 6 places it,
        S = origin + rot(x-axis vector, US, lS)."""
        return math.hypot(self.x, self.y), math.atan2(self.y, self.x)

    def product_ratio(self):
        """The products of inertia about the plane against Lzz:
        sqrt(Lxz^2 + Lyz^2) / Lzz (0 for a part symmetric about the plane)."""
        p = math.hypot(self.Lxz, self.Lyz)
        return p / self.J_S if self.J_S > 0 else (math.inf if p > 0 else 0.0)

    def describe(self) -> dict:
        """What was read, in the study's units, for people (``pipeline bodies``)."""
        lS, US = self.link_frame()
        out = {"report": self.file, "part": self.part or "(unnamed)",
               "units read": self.units,
               "m": f"{self.mass:.10g} kg",
               "centre of mass": f"x = {self.x:.10g} mm, y = {self.y:.10g} mm "
                                 f"(z = {self.z:.10g} mm) in the part's frame",
               "lS, US": f"{lS:.10g} mm, {math.degrees(US):.10g} deg (from the part's origin, "
                         "turned from its x axis)",
               "J_S": f"{self.J_S:.10g} kg*m^2 (Lzz, about z at the centre of mass)",
               "Lxz, Lyz / Lzz": f"{self.product_ratio():.3g}"}
        warning = self.warning()
        if warning:
            out["warning"] = warning
        return out

    def warning(self):
        """One line where the part is not symmetric about the mechanism's plane
        (its products of inertia Lxz, Lyz not small against Lzz), else None."""
        r = self.product_ratio()
        if r <= PRODUCT_RATIO_WARN:
            return None
        name = f"part {self.part!r}" if self.part else "the part"
        return (f"{self.file}: line {self.inertia_line}: {name}: the products of inertia "
                f"Lxz, Lyz are {100 * r:.3g}% of Lzz (more than "
                f"{100 * PRODUCT_RATIO_WARN:g}%): the part is not symmetric about the "
                "mechanism's plane and the planar model leaves out the moment they make")


def _error(file, line, reason):
    return StudyError(file, f"line {line}" if line else "", reason)


def read_text(path) -> str:
    """A report's text: UTF-8 (with or without a byte-order mark), UTF-16 with
    its mark (Windows' 'Unicode'), else Windows-1252; at most
    ``MAX_REPORT_BYTES``."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            raw = f.read(MAX_REPORT_BYTES + 1)
    except FileNotFoundError:
        raise StudyError(path, "", "report file not found") from None
    except OSError as e:
        raise StudyError(path, "", f"cannot read: {e.strerror or e}") from None
    if len(raw) > MAX_REPORT_BYTES:
        raise StudyError(path, "", f"a mass properties report is at most "
                                   f"{MAX_REPORT_BYTES:,} bytes (one part's is a few kB); "
                                   "this file is larger")
    if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
        return raw.decode("utf-16")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        return raw.decode("cp1252", errors="replace")


def read_parts(path, text=None) -> list[MassProperties]:
    """Every part of a report (a SolidWorks text report holds one; a CSV one
    per row).  ``text``: the report's content where it is not read from
    ``path`` (a copy kept in a results file)."""
    text = read_text(path) if text is None else text
    if Path(str(path)).suffix.lower() == ".csv":
        return _parse_csv(text, str(path))
    return [_parse_solidworks(text, str(path))]


def read_part(path, part=None, text=None) -> MassProperties:
    """The one part of a report (``part``: its name, to pick a row of a CSV
    that holds several)."""
    parts = read_parts(path, text)
    if part is None:
        if len(parts) > 1:
            names = ", ".join(repr(p.part) for p in parts[:5])
            raise _error(path, parts[1].mass_line,
                         f"a second part ({len(parts)} parts: {names}"
                         f"{', ...' if len(parts) > 5 else ''}): expected one part per "
                         "report, or name the part to read (cad.part)")
        return parts[0]
    for p in parts:
        if p.part == part:
            return p
    names = ", ".join(repr(p.part) for p in parts[:5])
    raise StudyError(path, "", f"no part named {part!r} (the report has {names})")


# ----------------------------------------------------------------- numbers and units
_NUMBER = re.compile(r"[-+]?(?:\d+(?:[.,]\d*)?|[.,]\d+)(?:[eE][-+]?\d+)?")


def _number(token, file, line, what):
    """A number as CAD writes it: a decimal point or a decimal comma."""
    t = token.strip()
    if not _NUMBER.fullmatch(t):
        raise _error(file, line, f"expected a number for {what}, got {t[:40]!r}")
    v = float(t.replace(",", "."))
    if not math.isfinite(v):
        raise _error(file, line, f"expected a finite number for {what}, got {t[:40]!r}")
    return v


def _unit(word, table, words, file, line, what):
    w = word.strip().lower()
    if w not in table:
        raise _error(file, line, f"{what} unit {word.strip()[:40]!r} is not one this reader "
                                 f"knows: expected {words}")
    return table[w]


_INERTIA = re.compile(r"(?P<mass>[a-z]+)\s*(?:\*|x|·|\.|-)?\s*"
                      r"(?:square\s+(?P<sq>[a-z]+)|(?P<len>[a-z]+)\s*(?:\^\s*2|²|2))",
                      re.IGNORECASE)


def _inertia_unit(text, file, line):
    """kg*m^2 per unit of ``text``: '<mass unit> * square <length unit>' or
    '<mass unit>*<length unit>^2'."""
    m = _INERTIA.fullmatch(text.strip())
    if not m:
        raise _error(file, line, f"inertia unit {text.strip()[:40]!r} is not one this reader "
                                 f"knows: expected {INERTIA_WORDS}")
    mass = _unit(m["mass"], MASS_UNITS, MASS_WORDS, file, line, "the inertia's mass")
    length = _unit(m["sq"] or m["len"], LENGTH_UNITS, LENGTH_WORDS, file, line,
                   "the inertia's length")
    return mass * (length / 1000.0) ** 2


def _check(file, line, what, v, within):
    if not within.holds(v):
        raise _error(file, line, f"{what} {v:g} {within.unit} is out of range: "
                                 f"{within.words()}")


def _finish(file, part, mass, com, lzz, lxz, lyz, units, lines):
    """A ``MassProperties`` in the study's units, its values checked against
    the study's plausible ranges."""
    _check(file, lines[0], "the mass", mass, lim.MASS)
    for axis, v in zip("xy", com[:2]):
        _check(file, lines[1], f"the centre of mass's {axis}", v, lim.OFFSET)
    if lzz < 0:
        raise _error(file, lines[2], f"Lzz must not be negative, got {lzz:g} kg*m^2")
    _check(file, lines[2], "Lzz", lzz, lim.INERTIA)
    return MassProperties(file, part, mass, *com, lzz, lxz, lyz, units, *lines)


# ----------------------------------------------------------------- SolidWorks' text
_PART = re.compile(r"\s*mass properties of\b\s*(.*?)\s*$", re.IGNORECASE)
_MASS = re.compile(r"\s*mass\s*(?:\([^)]*\))?\s*[=:]\s*(\S+)\s*(\S*)", re.IGNORECASE)
_COM = re.compile(r"\s*cent(?:er|re) of (?:mass|gravity)\b[^:]*:\s*\(\s*([^)]*?)\s*\)",
                  re.IGNORECASE)
_MOMENTS = re.compile(r"\s*moments of inertia\b[^:]*:\s*\(\s*([^)]*?)\s*\)(.*)$",
                      re.IGNORECASE)
_AT_COM = re.compile(r"taken at the cent(?:er|re) of mass and aligned", re.IGNORECASE)
_AT_OUTPUT = re.compile(r"taken at the output coordinate system", re.IGNORECASE)
_SECTION = re.compile(r"\s*(principal axes|density|volume|surface area|coordinate system|"
                      r"configuration|output coordinate)", re.IGNORECASE)
_XYZ = re.compile(r"\b([XYZ])\s*=\s*(\S+)")
_LIJ = re.compile(r"\b(L[xyz][xyz])\s*=\s*(\S+)", re.IGNORECASE)
_TAKEN_WORDS = ("a 'Moments of inertia: ( <unit> )' block 'Taken at the center of mass and "
                "aligned with the output coordinate system.' with an Lzz")


def _parse_solidworks(text, file):
    part, part_line = "", 0
    mass = mass_line = None
    com_unit = com_line = None
    com = {}
    inertia_unit = inertia_line = None
    moments = {}
    state, pending = None, None        # pending: a moments block's unit, before 'Taken at'
    lines = text.splitlines()
    for n, line in enumerate(lines, start=1):
        if not line.strip():
            if state == "com" and len(com) >= 2:
                state = None
            continue
        m = _PART.match(line)
        if m:
            if part_line:
                raise _error(file, n, f"a second part ('Mass properties of {m[1][:40]}'; "
                                      f"the first, {part!r}, at line {part_line}): expected "
                                      "one part per report (save each part's own)")
            part, part_line, state = m[1], n, None
            continue
        m = _MASS.match(line)
        if m:
            if mass_line:
                raise _error(file, n, f"a second mass line (the first at line {mass_line}): "
                                      "expected one part per report (save each part's own)")
            value = _number(m[1], file, n, "the mass")
            factor = _unit(m[2] or "(none)", MASS_UNITS, MASS_WORDS, file, n, "mass")
            mass, mass_line, mass_word, state = value * factor, n, m[2], None
            continue
        m = _COM.match(line)
        if m:
            if com_line:
                raise _error(file, n, f"a second centre of mass (the first at line "
                                      f"{com_line}): expected one part per report")
            com_unit = _unit(m[1], LENGTH_UNITS, LENGTH_WORDS, file, n, "length")
            com_word, com_line, state = m[1], n, "com"
            line = line[m.end():]
        m = _MOMENTS.match(line)
        if m:
            pending, pending_word, pending_line = m[1], m[1], n
            state = "moments"
            line = m[2]
        if state == "moments" and _AT_COM.search(line):
            if inertia_line:
                raise _error(file, n, f"a second moment of inertia at the centre of mass "
                                      f"(the first at line {inertia_line}): expected one "
                                      "part per report")
            inertia_unit = _inertia_unit(pending, file, pending_line)
            inertia_word, inertia_line, state = pending_word, n, "L"
            continue
        if state == "moments" and _AT_OUTPUT.search(line):
            state = "skip"
            continue
        if _SECTION.match(line):
            state = None
            continue
        if state == "com":
            for axis, token in _XYZ.findall(line):
                com[axis] = (_number(token, file, n, f"the centre of mass's {axis}"), n)
        elif state == "L":
            for name, token in _LIJ.findall(line):
                key = name[0].upper() + name[1:].lower()
                moments[key] = (_number(token, file, n, key), n)
    if not mass_line:
        raise StudyError(file, "", "no mass line: expected 'Mass = <number> grams', "
                                   "'kilograms' or 'pounds' (a SolidWorks mass properties "
                                   "report, or a .csv file)")
    if not com_line:
        raise StudyError(file, "", "no centre of mass: expected 'Center of mass: ( <unit> )' "
                                   "and its lines 'X = <number>', 'Y = <number>'")
    for axis in "XY":
        if axis not in com:
            raise _error(file, com_line, f"the centre of mass has no {axis}: expected a line "
                                         f"'{axis} = <number>' below it")
    if not inertia_line:
        raise StudyError(file, "", f"no moment of inertia at the centre of mass: expected "
                                   f"{_TAKEN_WORDS}")
    if "Lzz" not in moments:
        raise _error(file, inertia_line, "no Lzz in the block below: expected "
                                         "'Lzx = <number>  Lzy = <number>  Lzz = <number>'")
    xyz = tuple(com[a][0] * com_unit if a in com else 0.0 for a in "XYZ")
    prod = [moments.get(k, moments.get(k[0] + k[2] + k[1], (0.0, 0)))[0] * inertia_unit
            for k in ("Lxz", "Lyz")]
    units = ", ".join(" ".join(w.split()) for w in (mass_word, com_word, inertia_word))
    return _finish(file, part, mass, xyz, moments["Lzz"][0] * inertia_unit, *prod, units,
                   (mass_line, com["X"][1], moments["Lzz"][1]))


# ----------------------------------------------------------------- neutral CSV
def _parse_csv(text, file):
    rows = [(n, line) for n, line in enumerate(text.splitlines(), start=1)
            if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise StudyError(file, "", f"no part: expected rows of {', '.join(CSV_FIELDS)}")
    delimiter = ";" if ";" in rows[0][1] else ","
    parts, seen = [], {}
    for k, (n, line) in enumerate(rows):
        fields = [f.strip() for f in next(csv.reader(io.StringIO(line), delimiter=delimiter))]
        if k == 0 and len(fields) > 1 and not _NUMBER.fullmatch(fields[1]):
            if fields[1].lower() == "mass":
                continue                    # the header row
        if len(fields) not in (9, 11):
            raise _error(file, n, f"expected 9 fields ({', '.join(CSV_FIELDS)}), or 11 with "
                                  f"Lxz, Lyz after them; got {len(fields)}"
                                  + (" (a decimal comma needs ';' between the fields)"
                                     if delimiter == "," and len(fields) > 11 else ""))
        name = fields[0]
        if name in seen:
            raise _error(file, n, f"part {name[:40]!r} again (first at line {seen[name]}): "
                                  "expected one row per part")
        seen[name] = n
        mass = _number(fields[1], file, n, "the mass") * _unit(
            fields[2], MASS_UNITS, MASS_WORDS, file, n, "mass")
        length = _unit(fields[6], LENGTH_UNITS, LENGTH_WORDS, file, n, "length")
        xyz = tuple(_number(fields[i], file, n, f"the centre of mass's {a}") * length
                    for i, a in zip((3, 4, 5), "xyz"))
        inertia = _inertia_unit(fields[8], file, n)
        lzz = _number(fields[7], file, n, "Lzz") * inertia
        prod = [_number(fields[i], file, n, w) * inertia
                for i, w in ((9, "Lxz"), (10, "Lyz"))] if len(fields) == 11 else [0.0, 0.0]
        parts.append(_finish(file, name, mass, xyz, lzz, *prod,
                             f"{fields[2]}, {fields[6]}, {fields[8]}", (n, n, n)))
    if not parts:
        raise StudyError(file, "", f"no part: expected rows of {', '.join(CSV_FIELDS)}")
    return parts


# ----------------------------------------------------------------- the link it belongs to
def far_outside(props, joints, origin, x_axis):
    """Why the centre of mass is far outside its link, else None.

    ``joints``: the link's points at an assembled position {name: (x, y) mm},
    its joints and the part frame's origin and x-axis points among them.  The
    centre of mass is placed in that frame (``link_frame``); it is far
    outside when it lies farther from every one of those points than the
    link's span (the largest distance between two of them): the report's
    unit, or the part's origin or x axis, is not what the study says."""
    ox, oy = joints[origin]
    ax, ay = joints[x_axis[0]]
    bx, by = joints[x_axis[1]]
    L = math.hypot(bx - ax, by - ay)
    if L == 0:
        return None
    ex, ey = (bx - ax) / L, (by - ay) / L
    sx = ox + props.x * ex - props.y * ey
    sy = oy + props.x * ey + props.y * ex
    pts = list(joints.items())
    span = max(math.hypot(p[0] - q[0], p[1] - q[1]) for _, p in pts for _, q in pts)
    near, d = min(((n, math.hypot(sx - p[0], sy - p[1])) for n, p in pts), key=lambda t: t[1])
    if span == 0 or d <= span:
        return None
    return (f"the centre of mass (x, y) = ({props.x:.6g}, {props.y:.6g}) mm in the part's "
            f"frame is {d:.6g} mm from the link's nearest point ({near}), farther than the "
            f"link is long ({span:.6g} mm): expected it on the link (check the report's "
            f"units ({props.units}) and the part's origin {origin} and x axis "
            f"{x_axis[0]}->{x_axis[1]})")


# ----------------------------------------------------------------- a study's bodies
class CadReports:
    """The reports a study's bodies read (``cad = { report = ... }``): from the
    study file's folder, or from the copies a results file keeps (``stored``:
    {report as the study writes it: its text}); ``texts`` collects what was
    read, for the results file, and ``bodies`` what they place on the
    mechanism, for the run to check where they lie (``check_placed``)."""

    def __init__(self, folder, stored=None, origin=""):
        self.folder = Path(folder)
        self.stored = stored
        self.origin = origin          # the results file the stored copies come from
        self.texts = {}
        self.bodies = []              # (body name, props, origin, x_axis, joints, where)

    def body_data(self, b, cad, need, study_file):
        """(mass kg, J_S kg*m^2, CentreOfMass) of body section ``b`` from its
        ``cad`` table: report, origin, x_axis (and part, for a CSV of several)."""
        from ..model.mechanism import CentreOfMass
        for key in ("mass", "J_S", "com"):
            if b.has(key):
                raise b.error(key, "a body takes its mass data from cad = { report = ... } "
                                   "or from mass, J_S and com, not both")
        report = cad.string("report")
        if not report.strip() or "\x00" in report:
            raise cad.error("report", "expected the report file's path (relative to the "
                                      "study file's folder)")
        origin = cad.name("origin")
        need(cad, "origin", origin)
        x_axis = cad.names("x_axis", n=2)
        for p in x_axis:
            need(cad, "x_axis", p)
        if x_axis[0] == x_axis[1]:
            raise cad.error("x_axis", "the x axis needs two different points")
        part = cad.name("part", "")
        cad.done()
        where = f"the report of {study_file}: {cad.path('report')}"
        try:
            if self.stored is not None:
                if report not in self.stored:
                    raise StudyError(self.origin, "", f"keeps no copy of the report "
                                                      f"{report!r} ({cad.path('report')})")
                path, text = report, self.stored[report]
            else:
                path = self.folder / report
                text = read_text(path)
            props = read_part(path, part or None, text)
        except StudyError as e:
            raise StudyError(e.file, e.field, f"{e.reason} ({where})") from None
        self.texts[report] = text
        warning = props.warning()
        if warning:
            import logging
            logging.getLogger(__name__).warning("%s (%s)", warning, where)
        lS, US = props.link_frame()
        self.bodies.append((b.data.get("name"), props, origin, x_axis, where))
        return props.mass, props.J_S, CentreOfMass(origin, x_axis, lS, US)


def check_placed(bodies, mech, point_at):
    """Refuse a centre of mass far outside its link (``far_outside``).

    ``bodies``: what a study's CAD reports placed on its mechanism
    (``Study.cad_bodies``: ``CadReports.bodies``); ``point_at(name)``: the
    point's (x, y) mm at the crank's first position (phi0) of ``mech`` as
    declared, which the run solves (``solve.scene.check_centres_of_mass``)."""
    by_name = {b.name: b for b in mech.bodies}
    for name, props, origin, x_axis, where in bodies:
        names = dict.fromkeys((*by_name[name].joints, origin, *x_axis))
        points = {p: point_at(p) for p in names}
        problem = far_outside(props, points, origin, x_axis)
        if problem:
            raise _error(props.file, props.com_line, f"{problem} ({where})")
