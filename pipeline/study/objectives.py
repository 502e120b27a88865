"""A sweep's objectives and constraints, read from the kernels' metric rows:
the stored value of each metric (its column and units), the constraints
g <= 0 with their summed violation, and which rows are feasible."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..base.units import unit_text
from ..kernels import config as kc
from ..kernels import sweep as ks
from .sweep_spec import SweepSpec

# a metric's column and units: the catalogue (pipeline.model.metric_catalogue); COLUMN and DERIVED
# are its earlier forms, kept for one release
from ..model.metric_catalogue import BY_NAME, METRICS, metric_values  # noqa: E402,F401
COLUMN = {m.name: (m.column, m.factor) for m in BY_NAME.values() if not m.offset}
DERIVED = {m.name: (m.column, m.factor, m.offset) for m in BY_NAME.values() if m.offset}


def _bound_columns(spec: SweepSpec):
    """(name, metric, sign, limit) of every [sweep.constraints] bound: g = sign
    (value - limit) <= 0."""
    out = []
    for m, lo, hi in spec.bounds:
        if math.isfinite(lo):
            out.append((f"{m}_min", m, -1.0, lo))
        if math.isfinite(hi):
            out.append((f"{m}_max", m, 1.0, hi))
    return out


def constraint_names(has_margin: bool, spec: SweepSpec | None = None):
    """The stored constraints, in column order (the margin only for class III
    plans, then the study's bounds on metrics)."""
    return (["stroke_min", "stroke_max"] + (["singularity_margin_min"] if has_margin else [])
            + [b[0] for b in (_bound_columns(spec) if spec is not None else ())])


def constraint_units(has_margin: bool, spec: SweepSpec):
    """The units of each stored constraint, as ``constraint_names``."""
    return (["mm", "mm"] + (["1"] if has_margin else [])
            + [METRICS[m][0] for _, m, _, _ in _bound_columns(spec)])


def constraints(spec: SweepSpec, metrics, status: np.ndarray, has_margin: bool):
    """g <= 0 per constraint (columns as ``constraint_names``) and the summed
    violation CV (NaN where the candidate failed), from the kernels' metric
    rows.  A bounded metric that a candidate with status OK lacks (NaN: a
    stage-2 metric of a candidate already outside the stroke or margin limits,
    or a value that could not be computed) adds no violation of its own, but
    the candidate is not feasible (``bounded_finite``)."""
    stroke, margin = metrics[:, ks.M_STROKE], metrics[:, ks.M_MARGIN]
    g = [spec.stroke_bounds[0] - stroke, stroke - spec.stroke_bounds[1]]
    if has_margin:
        g.append(spec.margin_min - margin)
    for _, m, sign, limit in _bound_columns(spec):
        g.append(sign * (metric_values(metrics, m) - limit))
    G = np.stack(g, axis=1)
    cv = np.where(status == kc.OK, np.nansum(np.maximum(G, 0.0), axis=1), np.nan)
    return G, cv


def constraints_text(spec: SweepSpec, has_margin: bool) -> str:
    """The constraints the study states, in words with their units ("11 <= stroke
    <= 15 mm, singularity_margin >= 0.3"), or that it states none."""
    out = []
    for m, lo, hi in spec.stated_constraints(has_margin):
        u = unit_text(METRICS[m][0])
        u = "" if u in ("", "1") else f" {u}"
        if math.isfinite(lo) and math.isfinite(hi):
            out.append(f"{lo:g} <= {m} <= {hi:g}{u}")
        else:
            out.append(f"{m} >= {lo:g}{u}" if math.isfinite(lo) else f"{m} <= {hi:g}{u}")
    return ", ".join(out) if out else ("none given ([sweep.constraints]): every design that "
                                       "assembles is feasible")


class Feasibility(NamedTuple):
    """What the constraints say of evaluated rows: ``g`` per constraint (g <= 0
    is met; columns as ``constraint_names``), the summed violation ``cv`` (NaN
    where the candidate failed) and whether each row is ``feasible``."""
    g: np.ndarray
    cv: np.ndarray
    feasible: np.ndarray

    def rows(self, index) -> "Feasibility":
        """The rows ``index`` only."""
        return Feasibility(self.g[index], self.cv[index], self.feasible[index])

    @staticmethod
    def joined(parts) -> "Feasibility":
        """Several blocks of rows, one after the other."""
        return Feasibility(*(np.concatenate([p[i] for p in parts]) for i in range(3)))


def feasibility(spec: SweepSpec, status: np.ndarray, metrics, has_margin: bool) -> Feasibility:
    """The constraints ``g``, the violation ``cv`` and feasibility of the
    kernels' rows (status, metrics): a row is feasible when its status is OK,
    it violates no constraint and its objectives and bounded metrics are
    finite.  (has_margin: the plan has a class III group.)"""
    g, cv = constraints(spec, metrics, status, has_margin)
    objectives = np.stack([metric_values(metrics, o) for o in spec.objectives], axis=1)
    feasible = ((status == kc.OK) & (cv == 0) & np.isfinite(objectives).all(axis=1)
                & bounded_finite(spec, metrics))
    return Feasibility(g, cv, feasible)


def bounded_finite(spec: SweepSpec, metrics):
    """Rows whose bounded metrics (``spec.bounds``) are all finite."""
    ok = np.ones(metrics.shape[0], bool)
    for m, _, _ in spec.bounds:
        ok &= np.isfinite(metric_values(metrics, m))
    return ok


def feasibility_rules(spec: SweepSpec, has_margin: bool):
    """``feasibility`` as two tables, for a kernel that judges rows where they
    were computed (the GPU's, ``runs.gpu_kept``): ``limits``, a row per
    constraint (column, factor, offset, sign, limit: g = sign (value - limit),
    value = row[column] factor (+ offset), violated where g > 0), and
    ``finite``, a row per objective and bounded metric (column, factor, offset:
    its value must be finite).  A row is feasible when its status is OK, no g
    is above 0 (NaN is not: as cv's nansum) and every value of ``finite`` is
    finite; the same as ``feasibility`` (tested)."""
    def metric(name):
        m = BY_NAME[name]
        return [float(m.column), float(m.factor), float(m.offset)]
    limits = [metric("stroke") + [-1.0, spec.stroke_bounds[0]],
              metric("stroke") + [1.0, spec.stroke_bounds[1]]]
    if has_margin:
        limits.append(metric("singularity_margin") + [-1.0, spec.margin_min])
    limits += [metric(m) + [sign, limit] for _, m, sign, limit in _bound_columns(spec)]
    finite = [metric(o) for o in spec.objectives] + [metric(m) for m, _, _ in spec.bounds]
    return (np.array(limits, np.float64).reshape(-1, 5),
            np.array(finite, np.float64).reshape(-1, 3))
