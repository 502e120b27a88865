"""Browsing a sweep results file: its tree, counts by status, the best designs,
one candidate in detail, and one candidate re-run as a scene and drawn
(`pipeline browse`, `pipeline show`).

Works on a sweep file whether or not ``pipeline analyze`` has been run: without
a stored ``/analysis`` the fronts are ranked on the fly (and not stored).
"""

from __future__ import annotations

import io
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from types import SimpleNamespace

import h5py
import numpy as np
import pandas as pd

from .analysis import read_analysis, sweep_objectives, variable_units
from .files import save_figure
from .kernels import config as kc
from .pareto import crowding_distance, knee_point, nondominated_rank
from .storage import ResultsError, attr_text, candidate_ids, open_results, read_units, row_of
from .study import stored_study
from .sweep_file import status_counts

FORMATS = ("table", "json", "csv")

STATUS_HELP = {
    kc.OK: "assembles over the whole revolution",
    kc.NO_ASSEMBLY: "cannot be assembled (cosine-law argument outside [-1, 1])",
    kc.NEWTON_MAXITER: "the class III Newton solver did not converge",
    kc.SINGULAR: "passes a toggle (singular) position",
    kc.BRANCH_JUMP: "jumps assembly branch, or the revolution does not close on its start",
    kc.BAD_GEOMETRY: "impossible ternary triangle or non-positive length",
    kc.NOT_EVALUATED: "not evaluated (unfinished sweep)",
}

# OV-7 cyclogram of the eyelets, main-shaft angle in deg (DOMAIN.md section 9)
OV7_DWELL_START = 240.0
OV7_PHASES = (("dwell", 240.0, 390.0, "#cfe3f7"),
              ("swing forward", 30.0, 130.0, "#fbe3c8"),
              ("swing back", 130.0, 240.0, "#d9efd2"))


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


@dataclass
class Ranking:
    rank: np.ndarray
    crowding: np.ndarray
    knee: int
    representatives: np.ndarray
    stored: bool


def ranking(f) -> Ranking:
    """The stored analysis' fronts, or fronts ranked on the fly."""
    a = read_analysis(f)
    if a is not None:
        return Ranking(a.rank, a.crowding, a.knee, a.representatives, True)
    F = np.stack([f[f"metrics/{o}"][()] for o in sweep_objectives(f)], axis=1)
    rank = nondominated_rank(F, f["candidates/feasible"][()])
    return Ranking(rank, crowding_distance(F, rank), knee_point(F, rank), np.zeros(0, np.int64),
                   False)


def _metric_names(f):
    obj = list(sweep_objectives(f))
    rest = [m for m in ("stroke", "singularity_margin", "dwell_start", "peak_M_bal")
            if m in f["metrics"] and m not in obj]
    return obj, rest


def design_table(f, idx, selection, rk: Ranking) -> pd.DataFrame:
    """One row per candidate index: front, objectives, other metrics, design variables."""
    idx = np.asarray(idx, np.int64)
    obj, rest = _metric_names(f)
    p = f["candidates/params"]
    names = [str(attr_text(x)) for x in p.attrs["names"]]
    units = variable_units(p)
    cols = {"selection": selection if isinstance(selection, list) else [selection] * len(idx),
            "candidate": candidate_ids(f)[idx], "front": rk.rank[idx],
            "crowding": rk.crowding[idx]}
    order = np.argsort(idx, kind="stable")
    for m in obj + rest:
        d = f[f"metrics/{m}"]
        vals = np.empty(len(idx))
        vals[order] = d[np.sort(idx)] if len(idx) else []
        cols[f"{m} [{attr_text(d.attrs.get('units', '1'))}]"] = vals
    P = p[np.sort(idx)] if len(idx) else np.zeros((0, len(names)))
    Pv = np.empty_like(P)
    Pv[order] = P
    for j, (n, u) in enumerate(zip(names, units)):
        cols[f"{n} [{u}]"] = Pv[:, j]
    return pd.DataFrame(cols)


def best_designs(f, top=10, rk: Ranking | None = None) -> pd.DataFrame:
    """The knee, front 1 spread evenly along the front (at most ``top`` rows),
    the representatives (if analyzed) and the ``top`` best feasible designs per
    objective."""
    rk = rk or ranking(f)
    obj = list(sweep_objectives(f))
    feas = f["candidates/feasible"][()]
    frames = []
    if rk.knee >= 0:
        frames.append(design_table(f, [rk.knee], "knee", rk))
    front = np.flatnonzero(rk.rank == 1)
    if front.size:
        F1 = np.stack([f[f"metrics/{o}"][()][front] for o in obj], axis=1)
        front = front[np.lexsort(F1.T[::-1])]
        if front.size > top:
            front = front[np.unique(np.round(np.linspace(0, front.size - 1, top)).astype(int))]
        frames.append(design_table(f, front, "front 1", rk))
    if rk.representatives.size:
        frames.append(design_table(f, rk.representatives, "representative", rk))
    for o in obj:
        v = f[f"metrics/{o}"][()]
        cand = np.flatnonzero(feas & np.isfinite(v))
        best = cand[np.lexsort((cand, v[cand]))][:top]
        frames.append(design_table(f, best, f"best {o}", rk))
    if not frames:
        return design_table(f, [], "", rk)
    return pd.concat(frames, ignore_index=True)


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
            ana["reference rank"] = int(A.reference["rank"])
            ana["reference dominated by"] = int(A.reference["dominated_by_count"])
            for o, m in A.models.items():
                ana[f"R2 {o}"] = float(m["r2_test"]) if m.get("fitted") else \
                    f"skipped: {attr_text(m.get('reason', ''))}"
        ref = {}
        if "reference" in f:
            for o in info["objectives"]:
                if o in f["reference"]:
                    ref[o] = float(f["reference"][o][0])
        ana["reference design"] = ref
        return {"file": str(path), "info": info, "tree": tree(f), "status": status_counts(f),
                "analysis": ana, "designs": best_designs(f, top, rk)}


# ----------------------------------------------------------------- one candidate
def resolve_candidate(f, cid):
    """The stored row of ``cid``, or the string 'reference': a text is what a
    user types (a candidate number of the sweep, 'knee' or 'reference'); an
    integer is a stored row (the package's own callers).  Rows and candidate
    numbers are the same unless the sweep kept only its feasible candidates
    (store = feasible: ``storage.row_of`` maps them)."""
    n = f["candidates/status"].shape[0]
    if isinstance(cid, (int, np.integer)) and not isinstance(cid, bool):
        if not 0 <= cid < n:
            raise ValueError(f"row {cid} does not exist: the file holds {n} rows")
        return int(cid)
    s = str(cid).strip().lower()
    if s in ("reference", "ref"):
        if "reference" not in f:
            raise ResultsError(f.filename, "has no reference design")
        return "reference"
    if s == "knee":
        k = ranking(f).knee
        if k < 0:
            raise ValueError("there is no knee: no feasible candidate")
        return int(k)
    try:
        i = int(s)
    except ValueError:
        raise ValueError(f"--candidate expects a candidate number, 'knee' or 'reference', "
                         f"got {cid!r}") from None
    return row_of(f, i)


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
            for m in f["metrics"]:
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
            for m in f["metrics"]:
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
                   "front": int(rk.rank[i]), "crowding": float(rk.crowding[i]),
                   "ranking": "stored analysis" if rk.stored else "ranked on the fly"}
        out["params"] = [{"name": n, "value": float(v), "units": u}
                         for n, v, u in zip(names, x, units)]
        rows = []
        for m, v, a in metrics:
            row = {"name": m, "value": v, "units": str(attr_text(a.get("units", ""))),
                   "long_name": str(attr_text(a.get("long_name", "")))}
            if m == "peak_joint" and math.isfinite(v) and 0 <= int(v) < len(joints):
                row["joint"] = joints[int(v)]
            rows.append(row)
        out["metrics"] = rows
        return out


def _geometry_problems(f, x) -> list:
    """Which length or triangle inequality a BAD_GEOMETRY candidate breaks."""
    from .sweep_spec import geometry_problems, parameter_rows
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


WIDTH = 100     # columns of the text output unless --wide


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
    for k, v in ana.items():
        if k == "reference design":
            v = ", ".join(f"{o} {_g(x)}" for o, x in v.items()) or "none"
        elif isinstance(v, float):
            v = _g(v, 3)
        lines.append(f"  {k:>26}: {v}")
    lines += ["", "Best designs:"]
    for sel, df in ov["designs"].groupby("selection", sort=False):
        lines += ["", f"  {sel}:"]
        lines += ["  " + s for s in _table(df.drop(columns="selection"),
                                           None if wide else WIDTH - 2).splitlines()]
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
            head.append("  constraints g <= 0: " + ", ".join(
                f"{k} {_g(v)}" for k, v in d["constraints"].items()))
    head += ["", "  design variables:"]
    head += [f"    {p['name']:>8} = {_g(p['value'], 6):>10} {p['units']}" for p in d["params"]]
    head += ["", "  metrics:"]
    for m in d["metrics"]:
        extra = f" ({m['joint']})" if "joint" in m else ""
        head.append(f"    {m['name']:>20} = {_g(m['value'], 6):>10} {m['units']:<4}{extra}  "
                    f"{m['long_name']}")
    return "\n".join(head if wide else _fit(head))


def browse(path, top=10, candidate=None, fmt="table", wide=False) -> str:
    """The text `pipeline browse` prints: at most 100 columns, unless ``wide``
    (which also lists the file's datasets)."""
    if fmt not in FORMATS:
        raise ValueError(f"unknown format {fmt!r}; known: {', '.join(FORMATS)}")
    if candidate is not None:
        return format_candidate(candidate_details(path, candidate), fmt, wide)
    return format_overview(overview(path, top), fmt, wide)


# ----------------------------------------------------------------- re-running a design
@dataclass
class CandidateRun:
    """One design re-run through the scene path (declared mechanism -> plan)."""
    label: str
    index: object               # int or "reference"
    study: object               # the study with the candidate's mechanism
    plan: object
    x: np.ndarray
    names: list
    units: list
    table: object               # Curves at ``n_table`` positions (drawing)
    dense: object               # Curves at the study's positions (with forces if asked)
    theta: np.ndarray           # rocker angle from its first position, rad
    dwell_error: float
    dwell_start: int            # index into dense of the best window's start
    dwell_w: int                # intervals per window
    status: int
    fail_phi: float             # deg: first crank angle where the re-run failed (NaN: none)

    @property
    def scene(self):
        """What ``plots.draw_positions`` reads."""
        return SimpleNamespace(plan=self.plan, study=self.study, dense=self.dense)


def load_study_from_results(f):
    """The study rebuilt from the TOML stored verbatim in the results file."""
    study = stored_study(f.attrs, f.filename)
    if study is None:
        raise ResultsError(f.filename, "has no stored study (attribute study_toml)")
    return study


def rerun_candidate(path, cid, *, forces=True, n_table=12, positions=None) -> CandidateRun:
    """Re-run one candidate (index, 'knee' or 'reference') as a scene: the study
    rebuilt from the file, the design applied, curves at the study's positions
    and, if ``forces``, the reactions at the operating speed."""
    from .kernels.metrics import dwell_error
    from .scene import revolution_angles, solve_curves
    from .sweep_spec import apply_design
    with open_results(path, "sweep") as f:
        i = resolve_candidate(f, cid)
        study = load_study_from_results(f)
        p = f["candidates/params"]
        names = [str(attr_text(x)) for x in p.attrs["names"]]
        units = variable_units(p)
        x = f["reference/params"][()] if i == "reference" else p[i]
        number = i if i == "reference" else int(candidate_ids(f)[i])
    if not np.isfinite(x).all():
        raise ValueError(f"candidate {i} was never evaluated (unfinished sweep)")
    spec = study.sweep
    mech = apply_design(study.mechanism, spec, x)
    plan = mech.compile()
    crank = mech.crank
    n = positions or spec.positions
    close = crank.phi0 + crank.rot * 2.0 * math.pi
    dense = solve_curves(plan, revolution_angles(crank, n), kc.ACCELERATIONS, close_at=close)
    table = solve_curves(plan, revolution_angles(crank, n_table), kc.POSITIONS)
    if forces and dense.overall == kc.OK and mech.bodies:
        from .forces import scene_forces
        dense.forces = scene_forces(mech, plan, dense)
    a, b = (plan.point(q) for q in study.output.rocker)
    v = dense.pos[:, b] - dense.pos[:, a]
    ang = np.arctan2(v[:, 1], v[:, 0])
    theta = np.full(n, np.nan)
    bad = np.flatnonzero((dense.status != kc.OK) | ~np.isfinite(ang))
    k = int(bad[0]) if bad.size else n          # solved positions before the failure
    if k:
        theta[:k] = np.unwrap(ang[:k]) - ang[0]
    fail_phi = float(np.rad2deg(dense.fail_phi)) if dense.overall != kc.OK else math.nan
    if k < n:   # draw no table position beyond the failure of the revolution
        past = crank.rot * (table.phi - dense.phi[k]) >= 0
        table.pos[past] = np.nan
    w = int(round(study.output.dwell_deg * n / 360))
    q = np.empty(n + w + 1, np.int64)
    err, start, _ = dwell_error(np.ascontiguousarray(theta), w, q, q.copy())
    label = "reference design" if i == "reference" else f"candidate #{number}"
    return CandidateRun(label, i, replace(study, mechanism=mech), plan, np.asarray(x, float),
                        names, units, table, dense, theta, float(err), int(start), w,
                        int(dense.overall), fail_phi)


def _spans(a, b, period=360.0):
    """The interval [a, b] (0 < b - a <= period) as pieces inside [0, period]."""
    lo = a % period
    hi = lo + (b - a)
    if hi <= period:
        return [(lo, hi)]
    return [(lo, period), (0.0, hi - period)]


def _headroom(ax, values, frac=0.45):
    """Room above the curves for the legend."""
    lo, hi = float(np.nanmin(values)), float(np.nanmax(values))
    span = hi - lo if hi > lo else 1.0
    ax.set_ylim(lo - 0.05 * span, hi + frac * span)


def candidate_figure(run: CandidateRun, caption_extra=""):
    """The design at 12 positions, its output motion over the OV-7 cyclogram and
    against the crank angle, and its joint reactions against the crank angle.
    Returns the Figure."""
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    from .plots import draw_positions

    study, crank = run.study, run.study.mechanism.crank
    n = run.dense.phi.shape[0]
    phi = np.rad2deg(run.dense.phi)
    fig = plt.figure(figsize=(15, 9.5), layout="constrained")
    gs = fig.add_gridspec(3, 2, width_ratios=[1.0, 1.25])
    ax = fig.add_subplot(gs[:, 0])
    draw_positions(ax, run.scene, run.table, highlight=0)
    ax.set_title(f"{run.label}: {run.table.pos.shape[0]} positions (thick: phi1 = "
                 f"{np.rad2deg(run.table.phi[0]):g} deg), dotted: point paths", fontsize=10)
    if run.status != kc.OK:
        ax.text(0.5, 0.97, f"{kc.STATUS_NAMES.get(run.status, run.status)}: "
                f"{STATUS_HELP.get(run.status, '')}\nno position drawn past the failure",
                transform=ax.transAxes, ha="center", va="top", fontsize=9, color="C3",
                bbox=dict(boxstyle="round", fc="white", ec="C3", alpha=0.9))
    params = "\n".join(f"{nm} = {v:.2f} {u}" for nm, v, u in zip(run.names, run.x, run.units))
    ax.text(0.02, 0.02, params, transform=ax.transAxes, fontsize=8, family="monospace",
            va="bottom", bbox=dict(boxstyle="round", fc="white", ec="0.7", alpha=0.9))

    ax1 = fig.add_subplot(gs[0, 1])
    ax2 = fig.add_subplot(gs[1, 1])
    ax3 = fig.add_subplot(gs[2, 1])
    delta = study.output.dwell_deg
    radius = study.sweep.stroke_radius
    caption = ""
    if np.isfinite(run.theta).all() and run.dwell_start >= 0:
        s, w = run.dwell_start, run.dwell_w
        step = 360.0 / n
        win = (s + np.arange(w + 1)) % n
        th = np.rad2deg(run.theta - run.theta[win].mean())
        lo, hi = th[win].min(), th[win].max()
        # cycle angle: the best window moved to start at 240 deg of the main shaft
        psi = (np.arange(n) * step - s * step + OV7_DWELL_START) % 360.0
        order = np.argsort(psi)
        xs = np.append(psi[order], 360.0)
        ys = np.append(th[order], th[order][0])
        for name, a, b, col in OV7_PHASES:
            for k, (x0, x1) in enumerate(_spans(a, b)):
                ax1.axvspan(x0, x1, color=col, alpha=0.8, lw=0, label=name if k == 0 else None)
        for k, (x0, x1) in enumerate(_spans(OV7_DWELL_START, OV7_DWELL_START + w * step)):
            ax1.add_patch(Rectangle((x0, lo), x1 - x0, hi - lo, fill=False, hatch="///",
                                    ec="C3", lw=1.0,
                                    label=f"best {delta:g} deg window: residual {hi - lo:.3g} deg"
                                    if k == 0 else None))
        ax1.plot(xs, ys, "k-", lw=1.4, label="theta")
        _headroom(ax1, th)
        ax1.set_xlim(0, 360)
        ax1.set_xticks(np.arange(0, 361, 30))
        ax1.set_xlabel("main-shaft cycle angle [deg] (motion shifted: best window at 240)")
        ax1.set_ylabel("theta - dwell position [deg]")
        sec = ax1.secondary_yaxis("right", functions=(lambda d: np.deg2rad(d) * radius,
                                                      lambda mm: np.rad2deg(mm / radius)))
        sec.set_ylabel("eyelet arc [mm]")
        ax1.legend(fontsize=7, ncol=2, loc="upper right")
        ax1.grid(alpha=0.3)
        ax1.set_title(f"Output motion over the OV-7 cyclogram: dwell error "
                      f"{run.dwell_error:.4g}, stroke {radius * np.ptp(run.theta):.2f} mm",
                      fontsize=10)
        shift = (OV7_DWELL_START - s * step) % 360.0
        start_phi = phi[s]
        caption = (f"Motion shown shifted by {shift:g} deg: the best {delta:g} deg dwell window, "
                   f"found at phi1 = {start_phi:g} deg, is aligned with the OV-7 dwell "
                   f"(240 -> {(OV7_DWELL_START + delta) % 360:g} deg of the main shaft), as the "
                   "crank mounting phase would align it.")
        ax2.plot(phi, th, "k-", lw=1.2)
        _headroom(ax2, th)
        for k in range(w):        # the best window, sample by sample (wraps at 360)
            a_, b_ = phi[win[k]], phi[win[k]] + crank.rot * step
            ax2.axvspan(min(a_, b_), max(a_, b_), color="C3", alpha=0.18, lw=0,
                        label="best dwell window" if k == 0 else None)
        ax2.set_xlabel("crank angle phi1 [deg]")
        ax2.set_ylabel("theta - dwell position [deg]")
        ax2.grid(alpha=0.3)
        ax2.legend(fontsize=7, loc="upper right")
        ax2.set_title("Output motion against the crank angle (as computed)", fontsize=10)
        if crank.rot < 0:
            ax2.invert_xaxis()
    else:
        what = kc.STATUS_NAMES.get(run.status, run.status)
        where = f" at phi1 = {run.fail_phi:g} deg" if math.isfinite(run.fail_phi) else ""
        ax1.text(0.5, 0.5, f"no dwell window: the design fails ({what}{where})",
                 ha="center", va="center", transform=ax1.transAxes)
        ax1.set_axis_off()
        if np.isfinite(run.theta).any():
            ax2.plot(phi, np.rad2deg(run.theta), "k-", lw=1.2)
            ax2.set_ylabel("theta - theta(phi1 = 0) [deg]")
            ax2.grid(alpha=0.3)
            if crank.rot < 0:
                ax2.invert_xaxis()
        if math.isfinite(run.fail_phi):
            ax2.axvline(run.fail_phi, color="C3", lw=1.5, label=f"{what}{where}")
            ax2.legend(fontsize=7, loc="upper right")
            if not np.isfinite(run.theta).any():
                ax2.set_xlim(0, crank.rot * 360.0)
        ax2.set_xlabel("crank angle phi1 [deg]")
        ax2.set_title("Output motion against the crank angle, up to the failure", fontsize=10)
    fr = run.dense.forces
    if fr is not None:
        mag = fr.magnitude
        for j, name in enumerate(fr.joint_names):
            ax3.plot(phi, mag[:, j], label=name, lw=1.1)
        j, k = np.unravel_index(int(np.nanargmax(mag)), mag.shape)[::-1]
        ax3.annotate(f"peak {mag[k, j]:.0f} N ({fr.joint_names[j]}, {phi[k]:g} deg)",
                     (phi[k], mag[k, j]), textcoords="offset points", xytext=(6, -4),
                     fontsize=8)
        ax3.set_ylabel("|R| [N]")
        _headroom(ax3, mag)
        ax3.legend(fontsize=7, ncol=len(fr.joint_names), loc="upper right")
        if crank.rot < 0:
            ax3.invert_xaxis()
        ax3.set_title(f"Joint reactions at omega1 = {crank.omega1:g} rad/s", fontsize=10)
    else:
        ax3.text(0.5, 0.5, "no force analysis (the design does not assemble over the whole "
                 "revolution)", ha="center", va="center", transform=ax3.transAxes)
        ax3.set_yticks([])
        ax3.set_xticks([])
    ax3.set_xlabel("crank angle phi1 [deg]")
    ax3.grid(alpha=0.3)
    fig.suptitle(f"{study.title}: {run.label} ({kc.STATUS_NAMES.get(run.status, run.status)})"
                 + (f" {caption_extra}" if caption_extra else ""), fontsize=11)
    if caption:
        fig.text(0.5, 0.0, caption, ha="center", va="bottom", fontsize=9, style="italic",
                 wrap=True)
        fig.get_layout_engine().set(rect=(0, 0.025, 1, 0.975))
    return fig


def default_show_output(path, index) -> Path:
    path = Path(path)
    tag = "reference" if index == "reference" else f"candidate{index}"
    return path.with_name(f"{path.stem}_{tag}.png")


def show(path, cid, out=None) -> dict:
    """`pipeline show`: re-run a candidate and draw it; returns a summary."""
    run = rerun_candidate(path, cid)
    out = Path(out) if out else default_show_output(path, run.index)
    with open_results(path, "sweep") as f:
        stored = None
        if run.index != "reference":
            stored = float(f["metrics/dwell_error"][run.index]) if "dwell_error" in f["metrics"] \
                else None
            st = int(f["candidates/status"][run.index])
        else:
            st = int(f["reference/status"][0])
    import matplotlib.pyplot as plt
    fig = candidate_figure(run)
    save_figure(fig, out, dpi=100)
    plt.close(fig)
    info = {"candidate": run.index, "status": kc.STATUS_NAMES.get(run.status, run.status),
            "stored status": kc.STATUS_NAMES.get(st, st), "picture": str(out)}
    if np.isfinite(run.dwell_error):
        info["dwell error"] = f"{run.dwell_error:.4g}" + (
            f" (stored {stored:.4g})" if stored is not None and np.isfinite(stored) else "")
    if run.dense.forces is not None:
        info["peak reaction"] = f"{np.nanmax(run.dense.forces.magnitude):.1f} N"
    return info
