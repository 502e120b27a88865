"""A sweep's design written as a scene study of its own (`pipeline export
RESULTS --candidate ID --study OUT.toml`).

The scene study is the sweep's study as its results file stores it (verbatim)
with: ``study.kind = "scene"``; every swept parameter at the design's value;
the sweep's mass model applied (each scaled body's mass, J_S and lS written
out); the dense revolution at the sweep's positions and the force analysis
where the mechanism has mass data (what ``analysis.candidate.candidate_scene``
solves, and `pipeline show --candidate`); the [sweep] and [search] sections
gone.  Every other section, the loads among them, is kept as written.

Values are written as the study file states them (angles in degrees), floats
with ``repr`` so that reading the file back gives the same bits; the text is
read back before it is returned and must give the design's mechanism exactly.
Nothing of the study's text is ever run: it is data, written as TOML strings.
"""

from __future__ import annotations

import math
import re
import tomllib
from .reader import parse_study
from .sweep_spec import apply_design

BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


# ----------------------------------------------------------------- TOML out
def _string(s: str) -> str:
    """A TOML basic string: quote, backslash and control characters escaped."""
    out = []
    for c in s:
        if c in '"\\':
            out.append("\\" + c)
        elif c == "\n":
            out.append("\\n")
        elif c == "\t":
            out.append("\\t")
        elif ord(c) < 0x20 or ord(c) == 0x7F:
            out.append(f"\\u{ord(c):04x}")
        else:
            out.append(c)
    return '"' + "".join(out) + '"'


def _key(k: str) -> str:
    return k if BARE_KEY.fullmatch(k) else _string(k)


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        return repr(v) if math.isfinite(v) else ("inf" if v > 0 else "-inf")
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + " }" \
            if v else "{}"
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    raise TypeError(f"no TOML value for {type(v).__name__}")    # dates: not in a study


def _is_tables(v) -> bool:
    return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)


def _table(lines, path, data):
    """Lines of the table ``path`` (a list of keys): its plain values, then
    its sub-tables and arrays of tables (their elements' tables inline)."""
    for k, v in data.items():
        if not isinstance(v, dict) and not _is_tables(v):
            lines.append(f"{_key(k)} = {_value(v)}")
    for k, v in data.items():
        name = ".".join(_key(p) for p in path + [k])
        if isinstance(v, dict):
            if not v or any(not isinstance(x, dict) and not _is_tables(x) for x in v.values()):
                lines.append("")
                lines.append(f"[{name}]")      # (a table of tables alone needs no header)
            _table(lines, path + [k], v)
        elif _is_tables(v):
            for item in v:
                lines.append("")
                lines.append(f"[[{name}]]")
                for kk, vv in item.items():
                    lines.append(f"{_key(kk)} = {_value(vv)}")


def toml_text(data: dict, comment_lines=()) -> str:
    """``data`` (what tomllib reads) as TOML text, ``comment_lines`` on top."""
    lines = [f"# {c}" for c in comment_lines]
    top = {k: v for k, v in data.items() if not isinstance(v, dict) and not _is_tables(v)}
    _table(lines, [], top)
    _table(lines, [], {k: v for k, v in data.items() if k not in top})
    return "\n".join(lines).lstrip("\n") + "\n"


# ----------------------------------------------------------------- the design's study
def degrees_exact(rad: float) -> float:
    """An angle in degrees that the study reader (``math.radians``) turns back
    into ``rad`` exactly, where one is within a few ulps of ``math.degrees``
    (every angle a study gave in degrees has one; an angle from elsewhere, a
    CAD report's, may have none: then the nearest, and ``_check_reproduces``
    says so)."""
    d = math.degrees(rad)
    up = down = d
    for _ in range(8):
        for c in (up, down):
            if math.radians(c) == rad:
                return c
        up, down = math.nextafter(up, math.inf), math.nextafter(down, -math.inf)
    return d


def _set_parameter(data, mech, param, value):
    """Put a swept parameter's value (in the study file's units) where the
    study file declares it."""
    owner, key = param.rsplit(".", 1)
    m = data["mechanism"]
    if owner in mech.fixed and key in ("x", "y"):
        m["fixed"][owner]["xy".index(key)] = value
    elif owner == mech.crank.name:
        m["crank"][key] = value
    else:
        k = mech.compile().group_names.index(owner) - 1      # group_names[0] is the crank
        group = m["groups"][k]
        law = getattr(mech.groups[k], "law", None)
        if law is not None and key in law.FIELDS:
            group["law"][law.FIELDS[key]] = value
        else:
            group[key] = value


def design_study_text(study, x, *, label: str, origin: str, name: str) -> str:
    """The TOML text of the scene study of the sweep ``study``'s design with
    design-variable row ``x`` (``label``: the design's, 'candidate #12';
    ``origin``: a line saying where it came from; ``name``: the new study's
    name)."""
    spec = study.sweep
    mech = apply_design(study.mechanism, spec, x)
    data = tomllib.loads(study.text)
    data["study"]["kind"] = "scene"
    data["study"]["name"] = name
    data["study"]["title"] = f"{study.title} ({label})"
    for v, xi in zip(spec.variables, x):
        _set_parameter(data, study.mechanism, v.param, float(xi))
    scaled = {ms.body for ms in spec.mass_model}
    for b, table in zip(mech.bodies, data["mechanism"].get("bodies", [])):
        if "cad" in table:           # a CAD report's figures: written out, the report stays
            del table["cad"]
            table["com"] = {"base": b.com.base, "lS": float(b.com.lS),
                            "US": degrees_exact(b.com.US)}
            if b.com.along:
                table["com"]["along"] = list(b.com.along)
        if b.name in scaled or "mass" not in table:
            table["mass"], table["J_S"] = float(b.mass), float(b.J_S)
            table["com"]["lS"] = float(b.com.lS)
    output = data.setdefault("output", {})
    output["dense_positions"] = int(spec.positions)
    output["analysis"] = "forces" if mech.bodies else "accelerations"
    for section in ("sweep", "search"):
        data.pop(section, None)
    text = toml_text(data, [
        f"{name}: a scene study of one design of a sweep, written by `pipeline export`.",
        f"From: {origin}.",
        "Every swept parameter at the design's value, the sweep's mass model applied (the",
        "bodies' mass, J_S and lS written out), the sweep's positions per revolution and",
        "operating speed: `pipeline run` of this file gives `pipeline show --candidate`'s",
        "numbers."])
    _check_reproduces(text, study, mech, spec)
    return text


def _check_reproduces(text, study, mech, spec):
    """The written study read back gives the design's mechanism bit for bit
    (a parameter written where the reader does not take it would be lost)."""
    back = parse_study(text, "<the exported study>")
    want, got = mech.compile(), back.mechanism.compile()
    bad = [n for n, a, b in zip(want.par_names, want.par, got.par)
           if not (a == b or (math.isnan(a) and math.isnan(b)))]
    if want.par_names != got.par_names or bad or back.mechanism.bodies != mech.bodies \
            or back.output.dense_positions != spec.positions:
        what = bad[0] if bad else "its parameters, bodies or positions"
        raise RuntimeError(f"the exported study does not reproduce the design ({what}); "
                           "please report this")

