"""A design's builds through the sweep's compiled kernels: the evaluator of
parameter rows with every metric computed for every build that assembles
(``BuildEvaluator``), the scrambled Sobol deviations of the toleranced
dimensions, and the robust metrics of a sweep or a search (``RobustBuilds``:
a quantile of a metric, or the yield, over each design's builds).  The
tolerance analysis of one design is ``pipeline.runs.tolerance``'s."""

from __future__ import annotations

import logging

import math
import threading
import warnings
from dataclasses import replace

import numpy as np

from ..kernels import config as kc
from ..kernels import sweep as ks
from ..model.metric_catalogue import (BY_NAME, ROBUST_COLUMN, ROBUST_OF, TOLERANCED_METRICS,
                                      metric_values)
from ..study.sweep_spec import SweepSpec
from ..study.tolerance_spec import ToleranceSpec, drawn
from .problem import plain_problem


def available_metrics(study, plan):
    """The toleranced metrics this mechanism has (forces need bodies, friction
    [mechanism.friction], the law error a motion law, the transmission angle a dyad or a class III group,
    the singularity margin a class III group)."""
    from ..model.mechanism import transmission_items
    mech, out = study.mechanism, study.output
    has_margin = plan.has_continued
    keep = []
    for m in TOLERANCED_METRICS:
        stage = BY_NAME[m].stage
        if ((stage in ("forces", "friction") and not mech.bodies)
                or (stage == "friction" and mech.friction is None)
                or (stage == "law" and out.motion_law is None)
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
        if study.output.rocker is None:
            raise ValueError(f"{study.path}: a tolerance analysis reads stroke and dwell from "
                             "the output rocker: give output.rocker = [pivot, point]")
        study = replace(study, mechanism=mech)      # (not kept: a worker gets plain arrays)
        self.plan = mech.compile()
        self.metrics = tuple(metrics or available_metrics(study, self.plan))
        if "stroke" not in self.metrics:        # the arm scales it; constraints read it
            self.metrics = ("stroke",) + self.metrics
        self.spec = evaluation_spec(study, self.plan, self.metrics)
        self.problem = plain_problem(study, self.spec)
        if mech.friction is not None:   # the force metrics with friction, and its own
            from .sweep_friction import SweepFriction
            self.problem.friction = SweepFriction(mech, self.plan)
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
        tol = study.tolerance or ToleranceSpec()
        self.names = tuple(names)
        self.spec = spec.nominal()     # a design's own constraints, robust bounds apart
        self.quantile = tol.robust.quantile
        self.iso_class = tol.iso_class
        self.dims = drawn(tol.dimensions(study.mechanism))
        self.deltas = deviations(self.dims, tol.robust.builds, tol.seed)
        base = [ROBUST_OF[n] for n in self.names if ROBUST_OF[n]]
        if "build_yield" in self.names:
            base += ["stroke"] + [m for m, _, _ in self.spec.bounds]
        plan = study.mechanism.compile()
        if plan.has_continued:
            base.append("singularity_margin")
        self.builds = BuildEvaluator(study, study.mechanism, tuple(dict.fromkeys(base)))
        self.has_margin = "singularity_margin" in base
        self.columns = [plan.param(d.param) for d in self.dims]
        self.factors = np.array([d.factor for d in self.dims])

    def describe(self) -> str:
        return (f"{', '.join(self.names)}: {len(self.deltas)} builds per design that meets its "
                f"constraints, quantile {self.quantile:g}, tolerances of "
                f"{len(self.dims)} dimensions: ISO 2768-{self.iso_class} at the reference "
                "design's sizes for every design (pipeline tolerance --candidate: at the "
                "design's own sizes)")

    def fill(self, pars, status, rows, n_jobs=None, parallel=True, watch=None):
        """Write the robust columns of ``rows`` (n, N_ROW) of the designs
        ``pars`` whose nominal ``status`` and rows meet the constraints.  The
        builds go through the kernels in slices of at most ``SLICE_BUILDS``
        (``build_slices``): the work of one call stays bounded whatever the
        builds per design, and between two slices ``watch`` (a ``Watch``'s
        share of this call's designs) is told of the progress and may stop
        the work.  A build's numbers never depend on its slice."""
        from ..study.objectives import constraints
        _, cv = constraints(self.spec, rows, status, self.has_margin)
        idx = np.flatnonzero((status == kc.OK) & (cv == 0))
        if not len(idx):
            return
        B = len(self.deltas)
        n_rows = len(pars) + len(idx) * B       # the nominal rows, done, and the builds
        shift = self.deltas * self.factors
        # per build only what the robust columns need: whether it meets the
        # constraints, and the metric each quantile is of (a failed build: the worst)
        meets = np.empty(len(idx) * B, bool)
        of = [ROBUST_OF[n] for n in self.names if n != "build_yield"]
        worst = np.empty((len(idx) * B, len(of)))
        for lo, hi in build_slices(len(idx), B):
            if watch is not None:
                watch.check()
            build = np.repeat(pars[idx[lo // B:-(-hi // B)]], B, axis=0)[lo % B:][:hi - lo]
            build[:, self.columns] += shift[np.arange(lo, hi) % B]
            st, vals, brows = self.builds(build, n_jobs if parallel else 1)
            _, bcv = constraints(self.spec, brows, st, self.has_margin)
            meets[lo:hi] = (st == kc.OK) & (bcv == 0)
            for j, m in enumerate(of):
                v = vals[:, self.builds.metrics.index(m)]
                worst[lo:hi, j] = np.where((st == kc.OK) & np.isfinite(v), v, np.inf)
            if watch is not None:
                watch.reached((len(pars) + hi) / n_rows)
        j = 0
        for name in self.names:
            col = ROBUST_COLUMN[name]
            if name == "build_yield":
                rows[idx, col] = meets.reshape(len(idx), B).mean(axis=1)
                continue
            v = worst[:, j].reshape(len(idx), B)
            j += 1
            # interpolated between order statistics (a smoother objective than a single
            # build's value); a quantile that reaches a failed build is infinite
            with np.errstate(invalid="ignore"):
                q = np.quantile(v, self.quantile, axis=1)
            rows[idx, col] = np.where(np.isnan(q), np.inf, q)


SLICE_BUILDS = 4096     # builds per kernel call of the robust metrics: 0.07 s on 2 cores for
                        # ov7's dwell error (57,000 builds/s), so that progress is told and an
                        # interruption answered well within 2 s, whatever [tolerance.robust]
                        # builds asks (10,000 designs x 4,096 builds was one call of 80 s)


def build_slices(designs, builds, limit=None):
    """(lo, hi) ranges over the ``designs * builds`` build rows of a batch
    (design-major), each at most ``limit`` (``SLICE_BUILDS``) rows: whole
    designs together where several fit, a design's builds cut where one
    does not."""
    limit = SLICE_BUILDS if limit is None else int(limit)
    if limit < 1:
        raise ValueError(f"a slice holds at least one build, got {limit}")
    step = builds * max(1, limit // builds) if builds <= limit else limit
    total = designs * builds
    return [(lo, min(lo + step, total)) for lo in range(0, total, step)]


class Stopped(Exception):
    """A ``Watch`` was asked to stop: raised between two slices of the work."""


class Watch:
    """Between two kernel calls of a long evaluation (a chunk's robust builds,
    run in slices): the progress told to ``tick(n)`` in candidates (from the
    thread that computes, under a lock), and a stop that another thread asks
    for (``stop()``: the next ``check`` raises ``Stopped``)."""

    def __init__(self, tick=None):
        self._tick = tick
        self._stop = threading.Event()
        self._lock = threading.Lock()

    def stop(self):
        self._stop.set()

    def check(self):
        if self._stop.is_set():
            raise Stopped("stopped between two slices of the work")

    def tell(self, n):
        if n and self._tick is not None:
            with self._lock:
                self._tick(n)

    def share(self, n):
        """The part of this watch that one call of ``n`` candidates reports."""
        return _Share(self, n)


class _Share:
    """One call's ``n`` candidates, told as the fraction of its work done rises."""

    def __init__(self, watch, n):
        self.watch, self.n, self.told = watch, n, 0

    def check(self):
        self.watch.check()

    def reached(self, fraction):
        k = min(self.n, int(self.n * fraction))
        if k > self.told:
            self.watch.tell(k - self.told)
            self.told = k


def robust_for(study, spec: SweepSpec):
    """The builds of the robust metrics a sweep asks for (``RobustBuilds``), or None."""
    names = [m for m in dict.fromkeys(spec.metrics + spec.objectives)
             if m in ROBUST_COLUMN or m == "build_loss"]
    if not names:
        return None
    names = ["build_yield" if m == "build_loss" else m for m in names]
    builds = RobustBuilds(study, spec, dict.fromkeys(names))
    # which tolerance classes, said (pipeline tolerance --candidate says its own)
    logging.getLogger(__name__).info("robust metrics %s", builds.describe())
    return builds
