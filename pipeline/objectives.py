"""A sweep's objectives and constraints, read from the kernels' metric rows:
the stored value of each metric (its column and units), the constraints
g <= 0 with their summed violation, and which rows are feasible."""

from __future__ import annotations

import math

import numpy as np

from .kernels import config as kc
from .kernels import sweep as ks
from .sweep_spec import METRICS, SweepSpec

# kernel metric column of each stored metric, and a conversion to its units
COLUMN = {
    "dwell_error": (ks.M_DWELL, 1.0),
    "stroke": (ks.M_STROKE, 1.0),
    "singularity_margin": (ks.M_MARGIN, 1.0),
    "dwell_start": (ks.M_DWELL_START, 180.0 / math.pi),
    "newton_iterations": (ks.M_NEWTON_MEAN, 1.0),
    "peak_reaction": (ks.M_PEAK_R, 1.0),
    "peak_joint": (ks.M_PEAK_JOINT, 1.0),
    "peak_phi": (ks.M_PEAK_PHI, 180.0 / math.pi),
    "peak_M_bal": (ks.M_PEAK_MBAL, 1.0),
    "peak_acceleration": (ks.M_PEAK_ACC, 1.0),
    "peak_eps": (ks.M_PEAK_EPS, 1.0),
    "min_transmission_angle": (ks.M_MIN_TRANS, 180.0 / math.pi),
    "law_error": (ks.M_LAW_RMS, 1.0),
    "law_error_max": (ks.M_LAW_MAX, 1.0),
    "law_shift": (ks.M_LAW_SHIFT, 180.0 / math.pi),
}
# metrics derived from a column: (column, factor, offset)
DERIVED = {
    "transmission_deviation": (ks.M_MIN_TRANS, -180.0 / math.pi, 90.0),
}


def metric_values(metrics, name):
    """The stored values (in the metric's units) of metric ``name`` from the
    kernels' metric rows ``metrics`` (n, N_METRICS)."""
    if name in DERIVED:
        col, factor, offset = DERIVED[name]
        return metrics[:, col] * factor + offset
    col, factor = COLUMN[name]
    return metrics[:, col] * factor


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


def bounded_finite(spec: SweepSpec, metrics):
    """Rows whose bounded metrics (``spec.bounds``) are all finite."""
    ok = np.ones(metrics.shape[0], bool)
    for m, _, _ in spec.bounds:
        ok &= np.isfinite(metric_values(metrics, m))
    return ok
