"""Tolerance analysis of one design: the builds of a machine whose every
dimension lies somewhere within its tolerance, run through the sweep's
compiled kernels.

* **Builds**: scrambled Sobol points of the toleranced dimensions
  (``pipeline.study.tolerance_spec``), each deviation normal with the
  tolerance as 3 sigma or uniform within it; every build is evaluated exactly
  as a sweep candidate (assembly over the revolution, stroke, dwell, law,
  transmission, forces at the operating speed).  A build that cannot be
  assembled keeps its status and counts against the yield; it is never dropped.
  The masses stay the design's (a tenth of a millimetre does not change a
  link's mass that matters).
* **Yield**: the share of builds that assemble and meet the constraints (a
  sweep candidate: its [sweep.constraints]; a scene: [tolerance.constraints]).
* **Sensitivities**: d metric / d dimension at the design, per unit of the
  dimension (mm or deg), by central differences of the exact solution with two
  steps h and h/2 and Richardson's extrapolation; the step starts at 1e-3
  sigma of the dimension and is checked (the two estimates agree to 1e-4, or
  the difference is below 1e-9 of the metric over one sigma); where it is
  not, a step 100 times smaller is tried; where that fails too the metric is
  not differentiable there (a peak that moves between grid positions) and the
  sensitivity is flagged.
* **Linear prediction**: sigma_lin = sqrt(sum (dm/dx_i sigma_i)^2), beside
  the sampled standard deviation: where the two differ the linear picture
  fails (curvature, a kink, failed builds).
* **One at a time**: each dimension alone at -tolerance and +tolerance,
  exactly (the tornado chart).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import numpy as np

from ..kernels import config as kc
from ..model.metric_catalogue import BY_NAME, metric_values
from ..study.tolerance_spec import ToleranceSpec, drawn
from .builds import BuildEvaluator, build_rows, deviations
from ..compiler.notice import compile_notice

log = logging.getLogger("pipeline")

STEP = 1e-3             # first step of the central differences, in sigmas of the dimension
STEP_RETRY = 1e-2       # the second step, relative to the first
AGREE = 1e-4            # the two estimates of a step agree to this (relative) ...
FLAT = 1e-9             # ... or differ by less than this much of the metric over one sigma


@dataclass
class ToleranceAnalysis:
    """Everything a tolerance analysis found for one design."""
    label: str                  # "scene", "candidate #241851", "reference design"
    spec: ToleranceSpec
    dimensions: tuple           # Dimension: every toleranced dimension of the design
    metrics: tuple              # metric names, columns of ``values``
    nominal: np.ndarray         # (m,) the design's metrics
    nominal_status: int
    deltas: np.ndarray          # (n, d) deviation of each drawn dimension (mm, deg)
    status: np.ndarray          # (n,) int8 per build
    values: np.ndarray          # (n, m)
    meets: np.ndarray           # (n,) bool: assembles and meets the constraints
    constraints: tuple          # (metric, min, max) the builds are held to
    sensitivity: np.ndarray     # (m, D) per unit of each dimension (all dimensions)
    checked: np.ndarray         # (m, D) bool: the step check held
    one_at_a_time: np.ndarray   # (m, D, 2) the metric at -tolerance, +tolerance
    wall_s: float

    @property
    def drawn(self):
        return drawn(self.dimensions)

    @property
    def units(self):
        return [BY_NAME[m].units for m in self.metrics]

    @property
    def yield_(self) -> float:
        return float(self.meets.mean())

    def sigma_sampled(self):
        """Sample standard deviation of each metric over the builds that assemble."""
        out = np.full(len(self.metrics), np.nan)
        for k in range(len(self.metrics)):
            v = self.values[:, k]
            v = v[(self.status == kc.OK) & np.isfinite(v)]
            if len(v) > 1:
                out[k] = float(np.std(v, ddof=1))
        return out

    def sigma_linear(self):
        """sqrt(sum (dm/dx_i sigma_i)^2) over the drawn dimensions."""
        s = np.array([d.sigma for d in self.dimensions])
        return np.sqrt(np.nansum((self.sensitivity * s[None, :]) ** 2, axis=1))

    def contributions(self):
        """(m, D): |dm/dx_i| sigma_i, each dimension's share of the linear sigma."""
        s = np.array([d.sigma for d in self.dimensions])
        return np.abs(self.sensitivity) * s[None, :]

    def quantiles(self, q):
        """The q-quantile of each metric over the builds that assemble."""
        out = np.full(len(self.metrics), np.nan)
        for k in range(len(self.metrics)):
            v = self.values[:, k]
            v = v[(self.status == kc.OK) & np.isfinite(v)]
            if len(v):
                out[k] = float(np.quantile(v, q))
        return out

    def table(self):
        """One row per metric: units, the design's value, mean, std, the linear
        prediction of the std, 5th, 50th and 95th percentiles (a DataFrame)."""
        import pandas as pd
        ok = self.status == kc.OK
        mean = [float(np.mean(v[np.isfinite(v)])) if np.isfinite(v).any() else np.nan
                for v in (self.values[ok, k] for k in range(len(self.metrics)))]
        return pd.DataFrame({"units": self.units, "design": self.nominal, "mean": mean,
                             "std": self.sigma_sampled(), "std_linear": self.sigma_linear(),
                             "p05": self.quantiles(0.05), "p50": self.quantiles(0.5),
                             "p95": self.quantiles(0.95)},
                            index=pd.Index(self.metrics, name="metric"))

    def status_counts(self):
        codes, counts = np.unique(self.status, return_counts=True)
        return {kc.STATUS_NAMES.get(int(c), str(int(c))): int(n) for c, n in zip(codes, counts)}


# ----------------------------------------------------------------- the analysis
def analyse(study, mech, spec: ToleranceSpec, *, label="design", sweep_spec=None,
            samples=None, n_jobs=None, source=None) -> ToleranceAnalysis:
    """The tolerance analysis of design ``mech`` of ``study`` (a scene's own
    mechanism or a sweep candidate's, ``sweep.apply_design``); ``sweep_spec``:
    the sweep whose constraints the builds must meet.  A design that does not
    assemble is refused (its builds deviate from nothing): ``source``, the
    file it came from, names it."""
    t0 = time.perf_counter()
    _check_friction(study, mech, spec, sweep_spec, source)
    if sweep_spec is not None:      # a build has no builds of its own: robust bounds apart
        sweep_spec = sweep_spec.nominal()
    with compile_notice():
        ev = BuildEvaluator(study, mech, _wanted(spec, sweep_spec, mech))
        nom_status, nom_values, nom_rows = ev(ev.plan.par[None, :], n_jobs)
    if nom_status[0] != kc.OK:
        why = failure_text(label, ev.plan, nom_status[0], nom_rows[0])
        raise ValueError(f"{source or study.path}: {why}")
    n = spec.samples if samples is None else int(samples)
    dims = spec.dimensions(mech)
    deltas = deviations(drawn(dims), n, spec.seed)
    status, values, rows = ev(build_rows(ev.plan, ev.plan.par, drawn(dims), deltas), n_jobs)
    meets, bounds = _meets(ev, status, values, rows, sweep_spec, spec)
    sens, checked, oat = sensitivities(ev, dims, nom_values[0], n_jobs)
    return ToleranceAnalysis(label, spec, dims, ev.metrics, nom_values[0], int(nom_status[0]),
                             deltas, status, values, meets, bounds, sens, checked, oat,
                             time.perf_counter() - t0)


def failure_text(label, plan, status, row):
    """'the DESIGN does not assemble: STATUS at phi1 = X deg in group G; ...'
    from a kernel's metric row of the design."""
    from ..kernels import sweep as ks
    phi, group = row[ks.M_FAIL_PHI], row[ks.M_FAIL_GROUP]
    where = f" at phi1 = {math.degrees(phi):.2f} deg" if math.isfinite(phi) else ""
    if math.isfinite(group):
        where += f" in group {plan.group_names[int(group)]}"
    return (f"the {label} does not assemble: {kc.STATUS_NAMES.get(int(status), int(status))}"
            f"{where}; a tolerance analysis needs a design that assembles over the whole "
            "revolution (its builds deviate from it)")


def _check_friction(study, mech, spec, sweep_spec, source):
    """A friction metric asked of a design without [mechanism.friction] is
    refused in one line (with it, every build's force metrics are those with
    friction: ``runs.sweep_friction`` in the builds' evaluator)."""
    if mech.friction is not None:
        return
    asked = [m for m in _wanted(spec, sweep_spec, mech) or () if BY_NAME[m].stage == "friction"]
    if asked:
        raise ValueError(f"{source or study.path}: tolerance metrics: {asked[0]} needs friction "
                         "in the joints: declare [mechanism.friction]")


def _wanted(spec, sweep_spec, mech):
    """The metrics the study's [tolerance] metrics name, with those its
    constraints bound (None: every metric the mechanism has)."""
    if not spec.metrics:
        return None
    bounds = [b[0] for b in spec.bounds]
    if sweep_spec is not None:
        bounds += [b[0] for b in sweep_spec.bounds]
        if mech.compile().has_continued:
            bounds.append("singularity_margin")
    return tuple(dict.fromkeys(spec.metrics + tuple(bounds)))


def _meets(ev, status, values, rows, sweep_spec, spec):
    """(builds that assemble and meet the constraints, the constraints as
    (metric, min, max))."""
    ok = status == kc.OK
    if sweep_spec is not None:
        from ..study.objectives import bounded_finite, constraints
        has_margin = ev.plan.has_continued
        _, cv = constraints(sweep_spec, rows, status, has_margin)
        meets = ok & (cv == 0) & bounded_finite(sweep_spec, rows)
        return meets, sweep_spec.stated_constraints(has_margin)
    meets = ok.copy()
    for m, lo, hi in spec.bounds:
        v = metric_values(rows, m)
        with np.errstate(invalid="ignore"):
            meets &= np.isfinite(v) & (v >= lo) & (v <= hi)
    return meets, tuple(spec.bounds)


def sensitivities(ev: BuildEvaluator, dims, nominal, n_jobs=None):
    """(dm/dx (m, D) per unit of each dimension, step check held (m, D), the
    metrics at -tolerance and +tolerance (m, D, 2)): one batch of rows."""
    D = len(dims)
    h1 = np.array([STEP * (d.sigma if d.sigma > 0 else 0.01) for d in dims])
    hs = (h1, h1 * STEP_RETRY)
    offsets = []                       # per dimension: +h, -h, +h/2, -h/2 per step, +-tol
    for k in range(D):
        row = []
        for h in hs:
            row += [h[k], -h[k], h[k] / 2, -h[k] / 2]
        row += [-dims[k].tolerance, dims[k].tolerance]
        offsets.append(row)
    offsets = np.array(offsets)                    # (D, 10)
    per = offsets.shape[1]
    deltas = np.zeros((D * per, D))
    for k in range(D):
        deltas[k * per:(k + 1) * per, k] = offsets[k]
    status, values, _ = ev(build_rows(ev.plan, ev.plan.par, dims, deltas), n_jobs)
    values = np.where((status == kc.OK)[:, None], values, np.nan).reshape(D, per, -1)
    m = values.shape[2]
    sens = np.full((m, D), np.nan)
    checked = np.zeros((m, D), bool)
    sigma = np.array([d.sigma for d in dims])
    for k in range(D):
        for level, h in enumerate(hs):
            v = values[k, 4 * level:4 * level + 4]             # +h, -h, +h/2, -h/2
            d_h = (v[0] - v[1]) / (2 * h[k])
            d_h2 = (v[2] - v[3]) / h[k]
            rich = (4.0 * d_h2 - d_h) / 3.0
            err = np.abs(d_h - d_h2)
            with np.errstate(invalid="ignore"):
                good = np.isfinite(rich) & ((err <= AGREE * np.abs(rich)) |
                                            (err * max(sigma[k], h[k]) <= FLAT *
                                             np.abs(nominal)))
            take = np.isnan(sens[:, k]) | (~checked[:, k] & good)
            sens[take, k] = rich[take]
            checked[:, k] |= good
            if checked[:, k].all():
                break
    oat = np.transpose(values[:, 8:10, :], (2, 0, 1))
    return sens, checked, oat
