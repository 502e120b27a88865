"""The report's explorer: every feasible design of a sweep on a WebGL scatter,
any metric or design variable on either axis and as the colour, log axes where
a column spans decades, a filter on the constraints and on each objective, box
and lasso selection into a table and parallel coordinates, and the front-1
designs, the knee and the reference design each with its cycle (drawing,
output motion, joint reactions) re-run and embedded as data.

It opens zoomed on fronts 1 to ZOOM_FRONTS (the rest of the cloud dimmed
behind, double-click for all of it), where a click opens the nearest design of
the best front within a few pixels: every front-1 design can be clicked at the
first view, whatever crowds it.

This module gathers the data and lays out the section (templates/
explorer.html.j2); the page's script (templates/explorer.js) draws it with
plotly.js (page.py says why Plotly).  Numbers go to the page with
``page.DIGITS`` significant digits, the columns as one block of binary arrays
(page.ArrayBlock) beside the JSON of the rest, both packed (gzip,
page.packed): the explorer shows designs, the file keeps their exact numbers
(``pipeline browse``, ``pipeline show``).
"""

from __future__ import annotations

import logging
import os
import shlex
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..results.storage import attr_text, open_results, variables
from .page import ArrayBlock, json_number, packed, render, script_json

log = logging.getLogger("pipeline")

MAX_POINTS = 100_000       # feasible designs embedded (a seeded sample above it; front 1 always)
# infeasible designs for "all" (a seeded sample): they show where the feasible region
# ends; 5,000 draw that edge and keep the main job's page under 5 MB
MAX_INFEASIBLE = 5_000
ZOOM_FRONTS = 3            # the explorer opens zoomed on fronts 1 to this
# The front-1 designs embedded with their cycle when --drawings does not say: all of
# front 1 up to this many (spread along it above).  Each is a re-run with its
# reactions, about 40 ms on one core, and 25-30 KB of page: 50 designs stay within about
# 2 s and 1.5 MB.  A front of two objectives rarely holds more (22 of 250,000 candidates
# for the main job's study); the knee and the reference design come on top.
EXPLORER_DRAWINGS = 50
LOG_DECADES = 2.0          # positive data spanning more decades than this: a log axis


@dataclass
class Column:
    """One column of the explorer: a metric, a design variable, the front or the
    summed constraint violation."""
    key: str
    label: str
    unit: str
    kind: str               # objective, metric, front, constraint, variable
    values: np.ndarray


def log_axis(values) -> bool:
    """A log axis suits ``values`` when all the finite ones are positive and
    span more than LOG_DECADES decades."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    if v.size < 2 or not (v > 0).all():
        return False
    return bool(np.log10(v.max() / v.min()) > LOG_DECADES)


def zoomed_rows(rank) -> np.ndarray:
    """Which designs (Pareto ranks ``rank``, 0 = infeasible) the explorer opens
    zoomed on: fronts 1 to ZOOM_FRONTS."""
    rank = np.asarray(rank)
    return (rank >= 1) & (rank <= ZOOM_FRONTS)


def command_path(path) -> str:
    """The results file as a command typed in the current folder would name it:
    as given when relative, relative to the current folder when it lies below it,
    else absolute; quoted for the shell."""
    p = Path(path)
    if p.is_absolute():
        try:
            p = p.resolve().relative_to(Path.cwd().resolve())
        except ValueError:
            p = p.resolve()
    return shlex.quote(os.path.normpath(str(p)))


def show_command(path, cid) -> str:
    """The command that draws design ``cid`` (a number or 'reference')."""
    return f"pipeline show {command_path(path)} --candidate {cid}"


def explorer_rows(data, ana):
    """(rows embedded, feasible count, infeasible count): every feasible design
    with finite objectives (a seeded sample of MAX_POINTS of them above it,
    front 1 always), then a seeded sample of MAX_INFEASIBLE of the evaluated
    infeasible designs (those that failed have no objectives, but their design
    variables show where the feasible region ends)."""
    feas = np.flatnonzero(data.feasible & np.isfinite(data.F).all(axis=1))
    infeas = np.flatnonzero(~data.feasible & np.isfinite(data.params).all(axis=1))
    rng = np.random.default_rng(data.seed)
    shown = feas
    if feas.size > MAX_POINTS:
        front = np.asarray(ana.front1, np.int64)
        rest = np.setdiff1d(feas, front)
        keep = rng.choice(rest, max(MAX_POINTS - front.size, 0), replace=False)
        shown = np.sort(np.concatenate([front, keep]))
    grey = infeas
    if infeas.size > MAX_INFEASIBLE:
        grey = np.sort(rng.choice(infeas, MAX_INFEASIBLE, replace=False))
    return np.concatenate([shown, grey]).astype(np.int64), feas.size, infeas.size


def read_columns(path, rows, data, ana) -> list[Column]:
    """The explorer's columns at ``rows``: the objectives, the other metrics,
    the front (Pareto rank, 0 = infeasible), the summed constraint violation and
    the design variables."""
    cols = []
    with open_results(path, "sweep") as f:
        g = f["metrics"]
        n = f["candidates/status"].shape[0]
        names = list(data.objectives) + sorted(
            m for m in variables(g) if m not in data.objectives and g[m].shape == (n,))
        for m in names:
            d = g[m]
            kind = "objective" if m in data.objectives else "metric"
            cols.append(Column(m, m, str(attr_text(d.attrs.get("units", "1"))), kind,
                               d[()][rows]))
        cols.append(Column("front", "Pareto front", "1", "front", ana.rank[rows]))
        if "candidates/cv" in f:
            cols.append(Column("cv", "constraint violation", "1", "constraint",
                               f["candidates/cv"][()][rows]))
    for j, (name, unit) in enumerate(zip(data.names, data.units)):
        key = name if name not in {c.key for c in cols} else f"variable {name}"
        cols.append(Column(key, name, str(unit), "variable", data.params[rows, j]))
    return cols


def reference_values(path, columns, ana):
    """The reference design's value in each column it has (None: no reference)."""
    with open_results(path, "sweep") as f:
        if "reference" not in f:
            return None
        g = f["reference"]
        params = g["params"][()] if "params" in g else None
        out, j = {}, 0
        for c in columns:
            if c.kind == "variable":
                if params is not None and j < len(params):
                    out[c.key] = json_number(params[j])
                j += 1
            elif c.kind in ("objective", "metric") and c.key in g:
                out[c.key] = json_number(np.ravel(g[c.key][()])[0])
    out["front"] = int(ana.reference.get("rank", 0))
    return out


def design_picks(ana, n) -> list[int]:
    """The front-1 rows whose cycle is embedded: all of front 1 when it holds at
    most ``n``, else ``n`` spread evenly along it (it is sorted by the first
    objective); the knee and the representative designs always (when n > 0:
    the report draws them from these cycles)."""
    front = [int(i) for i in ana.front1]
    if n <= 0:
        return []
    if len(front) > n:
        at = np.unique(np.round(np.linspace(0, len(front) - 1, n)).astype(int))
        front = [front[k] for k in at]
    for i in [ana.knee, *ana.representatives]:
        if i >= 0 and int(i) not in front:
            front.append(int(i))
    return front


def explorer_payload(path, data, ana, drawings=None) -> tuple[dict, list, ArrayBlock]:
    """Everything explorer.js draws, as JSON-ready data, the columns, and the
    block of binary arrays (ids, feasible, each column's values) that the
    data's ``{"dtype", "offset", "length"}`` entries point into."""
    from .explorer_designs import design_cycles
    t0 = time.perf_counter()
    n_drawings = EXPLORER_DRAWINGS if drawings is None else int(drawings)
    rows, n_feas, n_infeas = explorer_rows(data, ana)
    cols = read_columns(path, rows, data, ana)
    near = zoomed_rows(ana.rank[rows])
    pos = {int(r): k for k, r in enumerate(rows)}
    ids = rows if data.ids is None else data.ids[rows]
    ref = reference_values(path, cols, ana)
    picks = design_picks(ana, n_drawings)
    designs = design_cycles(path, picks, data, reference=n_drawings > 0 and ref is not None)
    knee = pos.get(int(ana.knee), -1) if ana.knee >= 0 else -1
    block = ArrayBlock()
    payload = {
        "ids": block.add(ids),
        "feasible": block.add(data.feasible[rows]),
        "front1": [pos[int(i)] for i in ana.front1 if int(i) in pos],
        "knee": knee,
        "zoom_fronts": ZOOM_FRONTS,
        # the axis a column gets: log where the designs it opens on (fronts 1 to
        # ZOOM_FRONTS; all of them without a front) span decades
        "columns": [{"key": c.key, "label": c.label, "unit": c.unit, "kind": c.kind,
                     "log": log_axis(c.values[near] if near.any() else c.values),
                     "values": block.add(c.values)} for c in cols],
        "objectives": list(data.objectives),
        "variables": [c.key for c in cols if c.kind == "variable"],
        "reference": ref,
        "designs": designs,
        "command": f"pipeline show {command_path(path)} --candidate ",
        "counts": {"candidates": int(data.n), "feasible": int(n_feas),
                   "feasible_shown": int(data.feasible[rows].sum()),
                   "infeasible": int(n_infeas),
                   "infeasible_shown": int((~data.feasible[rows]).sum())},
    }
    log.info("report: explorer data: %d designs, %d columns, %d re-run (%.1f s)", len(rows),
             len(cols), len(designs), time.perf_counter() - t0)
    return payload, cols, block


def explorer_html(path, data, ana, drawings=None) -> str:
    """The explorer's section of the page (its script comes with the page)."""
    return explorer_section(path, data, ana, drawings)[0]


def explorer_section(path, data, ana, drawings=None) -> tuple[str, set]:
    """The explorer's section of the page, and the keys (candidate numbers as
    text, 'reference') of the designs whose cycle it embeds, which the rest of
    the page may draw (explorer.js: elements of class design-drawing and
    design-animation)."""
    if data.F.shape[1] < 2:
        return '<p class="note">The explorer plots two objectives; this study has one.</p>', set()
    if not (data.feasible & np.isfinite(data.F).all(axis=1)).any():
        return '<p class="note">No feasible design to explore.</p>', set()
    payload, cols, block = explorer_payload(path, data, ana, drawings)
    n = payload["counts"]
    objectives = []
    for c in cols:
        if c.kind == "objective":
            v = c.values[np.isfinite(c.values)]
            objectives.append({"key": c.key, "label": c.label, "unit": c.unit,
                               "lo": f"{v.min():.4g}" if v.size else "",
                               "hi": f"{v.max():.4g}" if v.size else ""})
    sampled = n["feasible_shown"] < n["feasible"]
    return render(
        "explorer.html.j2", columns=cols, objectives=objectives,
        x=data.objectives[0], y=data.objectives[1], n_points=payload["ids"]["length"],
        n_designs=len(payload["designs"]), has_knee=payload["knee"] >= 0,
        has_reference=payload["reference"] is not None,
        feasible_note=(f" ({n['feasible_shown']:,} of {n['feasible']:,}, a seeded sample with "
                       "all of front 1)" if sampled else f" ({n['feasible']:,})"),
        all_note=(f" (with {n['infeasible_shown']:,} of the {n['infeasible']:,} infeasible "
                  "designs" + (", a seeded sample" if n["infeasible_shown"] < n["infeasible"]
                               else "") + ")" if n["infeasible"] else ""),
        zoom_fronts=ZOOM_FRONTS, data=packed(script_json(payload)),
        arrays=block.packed()), set(payload["designs"])
