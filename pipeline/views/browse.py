"""Browsing a sweep results file: its tree, counts by status, the best designs
and one candidate in detail (`pipeline browse`); one candidate re-run as a
scene and drawn (`pipeline show`) is show.py's.

Works on a sweep file whether or not ``pipeline analyze`` has been run: without
a stored ``/analysis`` the fronts are ranked on the fly (and not stored).
"""

from __future__ import annotations

import io
import json
import math

import h5py
import numpy as np
import pandas as pd

from ..analysis.fronts import read_analysis, sweep_objectives, variable_units
from ..base.units import unit_text
from ..kernels import config as kc
from ..results.storage import attr_text, candidate_ids, open_results, read_units, variables
from ..study.reader import stored_study
from ..results.sweep_file import status_counts
# the fronts, one design and its picture have modules of their own (ranking,
# candidate, show); rerun_candidate and candidate_figure are importable from here
# too (docs/guide/api.md)
from ..analysis.candidate import (STATUS_HELP, rerun_candidate,  # noqa: F401 (the API's)
                                  resolve_candidate)
from ..analysis.ranking import best_designs, ranking
from .show import candidate_figure  # noqa: F401 (the API's)

FORMATS = ("table", "json", "csv")


def _clean(v):
    """JSON-safe scalar: NaN and inf become None, numpy scalars Python ones."""
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, (np.floating, float)):
        v = float(v)
        return v if math.isfinite(v) else None
    if isinstance(v, np.bool_):
        return bool(v)
    if isinstance(v, np.ndarray):
        return [_clean(x) for x in v.tolist()]
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_clean(x) for x in v]
    return v


def _g(v, digits=4):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-" if v is None or math.isnan(v) else str(v)
    if isinstance(v, (int, np.integer)):
        return str(v)
    return f"{v:.{digits}g}"


# ----------------------------------------------------------------- the file
def tree(f) -> list[dict]:
    """Groups and datasets of an open file with shapes, types and units."""
    rows = []

    def visit(name, obj):
        a = obj.attrs
        if isinstance(obj, h5py.Dataset):
            rows.append({"path": "/" + name, "kind": "dataset",
                         "shape": "x".join(map(str, obj.shape)) or "scalar",
                         "dtype": str(obj.dtype),
                         "units": _short_units(read_units(obj, obj.shape[-1]
                                                          if obj.ndim > 1 else 1)),
                         "long_name": str(attr_text(a.get("long_name", "")))})
        else:
            rows.append({"path": "/" + name, "kind": "group", "shape": "", "dtype": "",
                         "units": "", "long_name": str(attr_text(a.get("long_name", "")))})
    f.visititems(visit)
    return rows


def overview(path, top=10) -> dict:
    """Everything `pipeline browse FILE` shows."""
    if top < 1:
        raise ValueError(f"--top must be at least 1, got {top}")
    with open_results(path, "sweep") as f:
        a = f.attrs
        rk = ranking(f)
        info = {k: _clean(attr_text(a[k])) for k in ("study_name", "study_title", "study_file",
                                              "software_version", "created", "seed", "sampler",
                                              "n_candidates", "positions_per_revolution",
                                              "complete") if k in a}
        info["objectives"] = list(sweep_objectives(f))
        ana = {"stored": rk.stored, "fronts": int(rk.rank.max(initial=0)),
               "front 1": int((rk.rank == 1).sum()), "knee": rk.knee}
        if not rk.stored:
            ana["note"] = (f"not analyzed: fronts ranked on the fly (not stored); run "
                           f"`pipeline analyze {path}` to store them with the parameter "
                           "importances and representative designs")
        else:
            A = read_analysis(f)
            ana["reference rank"] = int(A.reference["rank"]) if \
                bool(A.reference.get("feasible", True)) else \
                f"infeasible, on no front ({A.reference.get('note', '')})"
            ana["reference dominated by"] = int(A.reference["dominated_by_count"])
            for o, m in A.models.items():
                ana[f"R2 {o}"] = float(m["r2_test"]) if m.get("fitted") else \
                    f"skipped: {attr_text(m.get('reason', ''))}"
        info["objective_units"] = {o: str(attr_text(f[f"metrics/{o}"].attrs.get("units", "1")))
                                   for o in info["objectives"]}
        ref = {}
        if "reference" in f:
            for o in info["objectives"]:
                if o in f["reference"]:
                    ref[o] = float(f["reference"][o][0])
        ana["reference design"] = ref
        return {"file": str(path), "info": info, "tree": tree(f), "status": status_counts(f),
                "analysis": ana, "designs": best_designs(f, top, rk)}


# ----------------------------------------------------------------- one candidate
def _reason(status, fail_phi, constraints, names, feasible, group=None):
    if status != kc.OK:
        where = f" at phi1 = {fail_phi:.9g} deg" if math.isfinite(fail_phi) else ""
        where += f" in group {group!r}" if group else ""
        return f"{kc.STATUS_NAMES.get(status, status)}{where}: {STATUS_HELP.get(status, '')}"
    if feasible:
        return "feasible"
    bad = [f"{n} violated by {g:.4g}" for n, g in zip(names, constraints) if g > 0]
    return "constraints: " + ("; ".join(bad) if bad else "objectives not finite")


def candidate_details(path, cid) -> dict:
    """Design variables (names, units), metrics, status and reason of one candidate."""
    with open_results(path, "sweep") as f:
        i = resolve_candidate(f, cid)
        p = f["candidates/params"]
        names = [str(attr_text(x)) for x in p.attrs["names"]]
        units = variable_units(p)
        joints = [str(attr_text(j)) for j in f["metrics"].attrs.get("joint_names", [])]
        metrics = []
        if i == "reference":
            g = f["reference"]
            x = g["params"][()]
            status = int(g["status"][0])
            for m in variables(f["metrics"]):
                if m in g:
                    metrics.append((m, float(g[m][0]), f["metrics"][m].attrs))
            out = {"candidate": "reference", "status": kc.STATUS_NAMES.get(status, status),
                   "reason": "the study's reference design"}
        else:
            x = p[i]
            status = int(f["candidates/status"][i])
            feas = bool(f["candidates/feasible"][i])
            fail = float(f["candidates/fail_phi"][i])
            cn = [str(attr_text(n)) for n in f["candidates/constraints"].attrs.get("names", [])]
            G = f["candidates/constraints"][i]
            cu = read_units(f["candidates/constraints"], len(cn))
            for m in variables(f["metrics"]):
                metrics.append((m, float(f["metrics"][m][i]), f["metrics"][m].attrs))
            rk = ranking(f)
            group = None
            if "fail_group" in f["candidates"]:      # format 1.2
                fg = f["candidates/fail_group"]
                g = int(fg[i])
                groups = [str(attr_text(x)) for x in fg.attrs.get("groups", [])]
                group = groups[g] if 0 <= g < len(groups) else None
            reason = _reason(status, fail, G, cn, feas, group)
            if status == kc.BAD_GEOMETRY:
                reason = "; ".join(_geometry_problems(f, x)) or reason
            out = {"candidate": int(candidate_ids(f)[i]),
                   "status": kc.STATUS_NAMES.get(status, status),
                   "feasible": feas, "reason": reason,
                   "fail_phi_deg": fail, "cv": float(f["candidates/cv"][i]),
                   "constraints": {n: float(g) for n, g in zip(cn, G)},
                   "constraint_units": dict(zip(cn, cu)),
                   "front": int(rk.rank[i]), "crowding": float(rk.crowding[i]),
                   "ranking": "stored analysis" if rk.stored else "ranked on the fly"}
        out["params"] = [{"name": n, "value": float(v), "units": u}
                         for n, v, u in zip(names, x, units)]
        rows = []
        for m, v, a in metrics:
            row = {"name": m, "value": v, "units": unit_text(attr_text(a.get("units", ""))),
                   "long_name": str(attr_text(a.get("long_name", "")))}
            if m == "peak_joint" and math.isfinite(v) and 0 <= int(v) < len(joints):
                row["joint"] = joints[int(v)]
            rows.append(row)
        out["metrics"] = rows
        return out


def _geometry_problems(f, x) -> list:
    """Which length or triangle inequality a BAD_GEOMETRY candidate breaks."""
    from ..study.sweep_spec import geometry_problems, parameter_rows
    study = stored_study(f.attrs, f.filename)
    if study is None:
        return []
    plan = study.mechanism.compile()
    return geometry_problems(plan, parameter_rows(plan, study.sweep, np.asarray(x)[None, :])[0])


# ----------------------------------------------------------------- formatting
def _table(df: pd.DataFrame, width=None) -> str:
    """``df`` as text; with ``width``, the columns wrap into blocks that fit."""
    if df.empty:
        return "  (none)"
    return df.to_string(index=False, float_format=lambda v: _g(v), line_width=width)


def _leading(df: pd.DataFrame, width: int) -> pd.DataFrame:
    """The first columns of ``df`` that fit ``width`` characters side by side
    (at least the first two): the compact table; the rest is --wide's."""
    keep = list(df.columns[:2])
    for c in df.columns[2:]:
        text = _table(df[keep + [c]])
        if max(map(len, text.splitlines())) > width:
            break
        keep.append(c)
    return df[keep]


def _with_unit(value, unit, digits=4) -> str:
    """'1074 N', '0.07209' (a unit of 1 left out: a pure number)."""
    text = _g(value, digits)
    return text if unit in ("", "1") or text == "-" else f"{text} {unit}"


def _short_units(units: list) -> str:
    """Units per column as "mm (all 9)" or "mm, deg, ..."."""
    if len(units) > 1 and len(set(units)) == 1:
        return f"{units[0]} (all {len(units)})"
    return ", ".join(units)


def _tree_lines(rows) -> list[str]:
    cols = [("path", 36), ("shape", 10), ("dtype", 8), ("units", 12), ("long_name", 64)]
    out = ["  ".join(c.ljust(w) for c, w in cols).rstrip()]
    for r in rows:
        r = dict(r)
        if r["kind"] == "group":
            r["shape"] = "(group)"
        out.append("  ".join(str(r[c])[:w].ljust(w) for c, w in cols).rstrip())
    return out


WIDTH = 80      # columns of the text output unless --wide (a terminal's)


def _fit(lines):
    """Lines longer than WIDTH wrapped, continued under their text."""
    import textwrap
    out = []
    for ln in lines:
        if len(ln) <= WIDTH:
            out.append(ln)
            continue
        body = ln.lstrip()
        m = len(ln) - len(body) + (body.find(": ") + 2 if ": " in body[:40] else 2)
        out += textwrap.wrap(ln, WIDTH, subsequent_indent=" " * min(m, 40),
                             break_on_hyphens=False)
    return out


def format_overview(ov: dict, fmt="table", wide=False) -> str:
    if fmt == "json":
        d = dict(ov)
        d["designs"] = [_clean(r) for r in ov["designs"].to_dict(orient="records")]
        return json.dumps(_clean(d), indent=2)
    if fmt == "csv":
        buf = io.StringIO()
        ov["designs"].to_csv(buf, index=False)
        return buf.getvalue().rstrip("\n")
    info, ana = ov["info"], ov["analysis"]
    lines = [f"{ov['file']}: sweep of study {info.get('study_name', '?')!r} "
             f"({info.get('n_candidates', '?')} candidates, seed {info.get('seed', '?')}, "
             f"sampler {info.get('sampler', '?')}"
             + ("" if info.get("complete", True) else ", UNFINISHED") + ")"]
    if wide:
        lines += ["", "Contents:"] + ["  " + s for s in _tree_lines(ov["tree"])]
    else:
        lines += ["  (the file's datasets, units and descriptions: --wide)"]
    lines += ["", "Candidates by status:"]
    for k, v in ov["status"].items():
        lines.append(f"  {k:>26}: {v['count']:>9}  ({v['percent']:.1f}%)")
    lines += ["", "Pareto fronts (objectives " + ", ".join(info["objectives"]) +
              ", all minimised):"]
    ounits = info.get("objective_units", {})
    for k, v in ana.items():
        if k == "reference design":
            v = ", ".join(f"{o} {_with_unit(x, ounits.get(o, ''))}"
                          for o, x in v.items()) or "none"
        elif isinstance(v, float):
            v = _g(v, 3)
        lines.append(f"  {k:>26}: {v}")
    lines += ["", "Best designs:"]
    if not wide:
        lines += ["  (more columns: --wide; every value of one design: --candidate ID)"]
    for sel, df in ov["designs"].groupby("selection", sort=False):
        # crowding distance: a pure number (unit 1, as the other columns say theirs)
        df = df.drop(columns="selection").rename(columns={"crowding": "crowding [1]"})
        lines += ["", f"  {sel}:"]
        lines += ["  " + s for s in _table(df if wide else _leading(df, WIDTH - 2)).splitlines()]
    return "\n".join(lines if wide else _fit(lines))


def format_candidate(d: dict, fmt="table", wide=False) -> str:
    if fmt == "json":
        return json.dumps(_clean(d), indent=2)
    rows = [{"section": "design variable", "name": p["name"], "value": p["value"],
             "units": p["units"]} for p in d["params"]]
    rows += [{"section": "metric", "name": m["name"], "value": m["value"], "units": m["units"]}
             for m in d["metrics"]]
    if fmt == "csv":
        buf = io.StringIO()
        pd.DataFrame(rows).to_csv(buf, index=False)
        return buf.getvalue().rstrip("\n")
    head = [f"candidate {d['candidate']}: {d['status']}", f"  reason: {d['reason']}"]
    if "front" in d:
        head.append(f"  front: {d['front']} ({d['ranking']}), crowding {_g(d['crowding'])}, "
                    f"summed constraint violation {_g(d['cv'])}")
        if d["constraints"]:
            cu = d.get("constraint_units", {})
            head.append("  constraints g <= 0: " + ", ".join(
                f"{k} {_with_unit(v, cu.get(k, ''))}" for k, v in d["constraints"].items()))
    head += ["", "  design variables:"]
    head += [f"    {p['name']:>8} = {_g(p['value'], 6):>10} "
             f"{'' if p['units'] == '1' else p['units']}" for p in d["params"]]
    head += ["", "  metrics:"]
    for m in d["metrics"]:
        # the joint by its name (R1, as the tables); a pure number's unit 1 left out
        value = m["joint"] if "joint" in m else _g(m["value"], 6)
        unit = "" if "joint" in m or m["units"] == "1" else m["units"]
        head.append(f"    {m['name']:>20} = {value:>10} {unit:<4}  {m['long_name']}")
    return "\n".join(head if wide else _fit(head))


def browse(path, top=10, candidate=None, fmt="table", wide=False) -> str:
    """The text `pipeline browse` prints: at most 80 columns, unless ``wide``
    (which also lists the file's datasets)."""
    if fmt not in FORMATS:
        raise ValueError(f"unknown format {fmt!r}; known: {', '.join(FORMATS)}")
    if candidate is not None:
        return format_candidate(candidate_details(path, candidate), fmt, wide)
    return format_overview(overview(path, top), fmt, wide)
