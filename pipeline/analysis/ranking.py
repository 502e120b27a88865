"""The fronts of a sweep results file and the designs they rank best: the
stored analysis' fronts, or fronts ranked on the fly (and not stored) where
``pipeline analyze`` has not been run; the knee, front 1, the representatives
and the best feasible designs per objective as a table."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from .fronts import read_analysis, sweep_objectives, variable_units
from ..kernels.pareto import crowding_distance, knee_point, nondominated_rank
from ..results.storage import attr_text, candidate_ids


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
