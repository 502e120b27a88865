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
import warnings
from dataclasses import dataclass, replace

import numpy as np

from ..kernels import config as kc
from ..kernels import sweep as ks
from ..model.metric_catalogue import BY_NAME, metric_values
from ..study.sweep_spec import SweepSpec
from ..study.tolerance_spec import ToleranceSpec, drawn

log = logging.getLogger("pipeline")

# the metrics a build's quality is read from (indices, angles of peaks and residuals
# are not quantities to tolerance)
TOLERANCED_METRICS = ("stroke", "dwell_error", "law_error", "singularity_margin",
                      "min_transmission_angle", "peak_acceleration", "peak_reaction",
                      "peak_M_bal")
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

    def status_counts(self):
        codes, counts = np.unique(self.status, return_counts=True)
        return {kc.STATUS_NAMES.get(int(c), str(int(c))): int(n) for c, n in zip(codes, counts)}


# ----------------------------------------------------------------- the evaluator
def available_metrics(study, plan):
    """The toleranced metrics this mechanism has (forces need bodies, the law
    error a motion law, the transmission angle a dyad or a class III group,
    the singularity margin a class III group)."""
    from ..solve.peaks import transmission_items
    mech, out = study.mechanism, study.output
    has_margin = bool(np.isin(plan.codes, kc.CLASS3_GROUPS).any())
    keep = []
    for m in TOLERANCED_METRICS:
        stage = BY_NAME[m].stage
        if ((stage == "forces" and not mech.bodies) or (stage == "law" and out.motion_law is None)
                or (stage == "transmission" and not transmission_items(mech))
                or (m == "singularity_margin" and not has_margin)):
            continue
        keep.append(m)
    return tuple(keep)


def stroke_radius(plan, study):
    """A scene's stroke radius: the working point's distance from the output
    rocker's pivot at the first position (as ``solve.peaks.scene_motion``)."""
    from ..solve.scene import revolution_angles, solve_curves
    crank = study.mechanism.crank
    pos = solve_curves(plan, revolution_angles(crank, 1), kc.POSITIONS).pos[0]
    a, w = plan.point(study.output.rocker[0]), plan.point(study.output.working_point)
    r = math.hypot(pos[w, 0] - pos[a, 0], pos[w, 1] - pos[a, 1])
    if not math.isfinite(r):
        raise ValueError(f"{study.path}: the design does not assemble at its first position")
    return r


def evaluation_spec(study, plan, metrics) -> SweepSpec:
    """The sweep settings every build is evaluated with: every metric computed
    for every build that assembles (no stroke or margin limit gates the force
    stage; the constraints are applied afterwards)."""
    base = study.sweep
    if base is None:
        positions = study.output.dense_positions
        base = SweepSpec(variables=(), candidates=1, seed=0, sampler="sobol",
                         positions=positions, chunk_size=1, metrics=(), objectives=(),
                         stroke_radius=stroke_radius(plan, study), stroke_bounds=(0.0, 0.0),
                         margin_min=0.0, mass_model=(), scheduler=None)
    return replace(base, metrics=tuple(metrics), objectives=(), bounds=(), triangles=(),
                   stroke_bounds=(-math.inf, math.inf), margin_min=-math.inf, device="cpu",
                   store="all")


class BuildEvaluator:
    """A design's builds through the compiled kernels: parameter rows in,
    (status, metric values) out."""

    def __init__(self, study, mech, metrics=None):
        from .sweep import build_problem
        if study.output.rocker is None:
            raise ValueError(f"{study.path}: a tolerance analysis reads stroke and dwell from "
                             "the output rocker: give output.rocker = [pivot, point]")
        study = replace(study, mechanism=mech)      # (not kept: a worker gets plain arrays)
        self.plan = mech.compile()
        self.metrics = metrics or available_metrics(study, self.plan)
        self.spec = evaluation_spec(study, self.plan, self.metrics)
        self.problem = build_problem(study, self.spec)
        self.arm = working_arm(study, self.plan)

    def raw(self, pars, n_jobs=None):
        """(status, kernel metric rows) of parameter rows."""
        return self.problem.evaluate_rows(np.ascontiguousarray(pars, float), True, n_jobs)

    def __call__(self, pars, n_jobs=None):
        status, rows = self.raw(pars, n_jobs)
        if self.arm is not None:
            # the stroke is the arc of the working point: its arm as built
            rows[:, ks.M_STROKE] *= pars[:, self.arm] / self.plan.par[self.arm]
        return status, self.values(rows), rows

    def values(self, rows):
        return np.stack([metric_values(rows, m) for m in self.metrics], axis=1)


def working_arm(study, plan):
    """The parameter column of the working point's arm on the output rocker
    (an attached point based on the rocker's pivot: its length), or None: the
    stroke of a build is its arm times its swing (the sweep's stroke radius
    is the design's arm)."""
    pivot = study.output.rocker[0]
    for label, g in zip(plan.group_names[1:], study.mechanism.groups):
        if (getattr(g, "point", None) == study.output.working_point
                and getattr(g, "base", None) == pivot and f"{label}.length" in plan.par_names):
            return plan.param(f"{label}.length")
    return None


def unit_draws(n, d, seed):
    """n scrambled Sobol points in (0, 1)^d (seeded)."""
    from scipy.stats import qmc
    with warnings.catch_warnings():       # n need not be a power of 2
        warnings.simplefilter("ignore", UserWarning)
        u = qmc.Sobol(d, scramble=True, seed=seed).random(n)
    tiny = 2.0 ** -53
    return np.clip(u, tiny, 1.0 - tiny)


def deviations(dims, n, seed):
    """(n, len(dims)) deviations of dimensions ``dims`` (study units, mm and
    deg): scrambled Sobol points through each dimension's distribution."""
    from scipy.special import ndtri
    u = unit_draws(n, len(dims), seed)
    out = np.empty_like(u)
    for j, d in enumerate(dims):
        if d.distribution == "normal":
            out[:, j] = ndtri(u[:, j]) * d.sigma
        else:
            out[:, j] = (2.0 * u[:, j] - 1.0) * d.tolerance
    return out


def build_rows(plan, par, dims, deltas):
    """Parameter rows of builds: ``par`` (the design's row) with the deviations
    ``deltas`` (n, len(dims), study units) added."""
    rows = np.repeat(np.asarray(par, float)[None, :], deltas.shape[0], axis=0)
    for j, d in enumerate(dims):
        rows[:, plan.param(d.param)] += deltas[:, j] * d.factor
    return rows


# ----------------------------------------------------------------- the analysis
def analyse(study, mech, spec: ToleranceSpec, *, label="design", sweep_spec=None,
            samples=None, n_jobs=None) -> ToleranceAnalysis:
    """The tolerance analysis of design ``mech`` of ``study`` (a scene's own
    mechanism or a sweep candidate's, ``sweep.apply_design``); ``sweep_spec``:
    the sweep whose constraints the builds must meet."""
    from .sweep import compile_notice
    t0 = time.perf_counter()
    with compile_notice():
        ev = BuildEvaluator(study, mech)
        nom_status, nom_values, _ = ev(ev.plan.par[None, :], n_jobs)
    n = spec.samples if samples is None else int(samples)
    dims = spec.dimensions(mech)
    deltas = deviations(drawn(dims), n, spec.seed)
    status, values, rows = ev(build_rows(ev.plan, ev.plan.par, drawn(dims), deltas), n_jobs)
    meets, bounds = _meets(ev, status, values, rows, sweep_spec, spec)
    sens, checked, oat = sensitivities(ev, dims, nom_values[0], n_jobs)
    return ToleranceAnalysis(label, spec, dims, ev.metrics, nom_values[0], int(nom_status[0]),
                             deltas,
                             status, values, meets, bounds, sens, checked, oat,
                             time.perf_counter() - t0)


def _meets(ev, status, values, rows, sweep_spec, spec):
    """(builds that assemble and meet the constraints, the constraints as
    (metric, min, max))."""
    ok = status == kc.OK
    if sweep_spec is not None:
        from ..study.objectives import bounded_finite, constraints
        has_margin = bool(np.isin(ev.plan.codes, kc.CLASS3_GROUPS).any())
        _, cv = constraints(sweep_spec, rows, status, has_margin)
        meets = ok & (cv == 0) & bounded_finite(sweep_spec, rows)
        bounds = [("stroke", *sweep_spec.stroke_bounds)]
        if has_margin:
            bounds.append(("singularity_margin", sweep_spec.margin_min, math.inf))
        return meets, tuple(bounds) + tuple(sweep_spec.bounds)
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


# ----------------------------------------------------------------- robust metrics
class RobustBuilds:
    """The robust metrics of a sweep or a search (``metric_catalogue.ROBUST``):
    every design that meets its constraints nominally is built ``builds``
    times within the study's tolerances (the same scrambled Sobol deviations
    for every design: common draws make designs comparable), and the quantile
    of a metric over its builds, or the share of builds that meet the
    constraints, fills the design's robust columns.  The other designs cannot
    be on a feasible front: NaN.  The tolerances are the reference design's
    (its size classes) for every design.  Picklable (a Dask worker gets it
    with its problem)."""

    def __init__(self, study, spec: SweepSpec, names):
        from ..model.metric_catalogue import ROBUST_OF
        tol = study.tolerance or ToleranceSpec()
        self.names = tuple(names)
        self.spec = spec
        self.quantile = tol.robust.quantile
        self.dims = drawn(tol.dimensions(study.mechanism))
        self.deltas = deviations(self.dims, tol.robust.builds, tol.seed)
        base = [ROBUST_OF[n] for n in self.names if ROBUST_OF[n]]
        if "build_yield" in self.names:
            base += ["stroke"] + [m for m, _, _ in spec.bounds if BY_NAME[m].stage != "robust"]
        plan = study.mechanism.compile()
        if np.isin(plan.codes, kc.CLASS3_GROUPS).any():
            base.append("singularity_margin")
        self.builds = BuildEvaluator(study, study.mechanism, tuple(dict.fromkeys(base)))
        self.has_margin = "singularity_margin" in base
        self.columns = [plan.param(d.param) for d in self.dims]
        self.factors = np.array([d.factor for d in self.dims])

    def describe(self) -> str:
        return (f"{', '.join(self.names)}: {len(self.deltas)} builds per design that meets its "
                f"constraints, quantile {self.quantile:g}, tolerances of "
                f"{len(self.dims)} dimensions (the reference design's)")

    def fill(self, pars, status, rows, n_jobs=None, parallel=True):
        """Write the robust columns of ``rows`` (n, N_ROW) of the designs
        ``pars`` whose nominal ``status`` and rows meet the constraints."""
        from ..model.metric_catalogue import ROBUST_COLUMN, ROBUST_OF
        from ..study.objectives import constraints
        nominal = replace(self.spec, bounds=tuple(b for b in self.spec.bounds
                                                   if BY_NAME[b[0]].stage != "robust"))
        _, cv = constraints(nominal, rows, status, self.has_margin)
        idx = np.flatnonzero((status == kc.OK) & (cv == 0))
        if not len(idx):
            return
        B = len(self.deltas)
        build = np.repeat(pars[idx], B, axis=0)
        build[:, self.columns] += np.tile(self.deltas * self.factors, (len(idx), 1))
        st, vals, brows = self.builds(build, n_jobs if parallel else 1)
        ok = (st == kc.OK).reshape(len(idx), B)
        for name in self.names:
            col = ROBUST_COLUMN[name]
            if name == "build_yield":
                _, bcv = constraints(nominal, brows, st, self.has_margin)
                meets = ((st == kc.OK) & (bcv == 0)).reshape(len(idx), B)
                rows[idx, col] = meets.mean(axis=1)
                continue
            v = vals[:, self.builds.metrics.index(ROBUST_OF[name])].reshape(len(idx), B)
            v = np.where(ok & np.isfinite(v), v, np.inf)     # a failed build: the worst
            # interpolated between order statistics (a smoother objective than a single
            # build's value); a quantile that reaches a failed build is infinite
            with np.errstate(invalid="ignore"):
                q = np.quantile(v, self.quantile, axis=1)
            rows[idx, col] = np.where(np.isnan(q), np.inf, q)
