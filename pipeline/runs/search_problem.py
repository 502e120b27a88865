"""What the optimizer of an adaptive search sees (the pymoo-facing problem):
the sweep's evaluator as a black box, the repair that keeps proposals inside
the triangle inequalities, and the feasible front so far with its hypervolume.

The problem is the [sweep] section's: its design variables and bounds, its
objectives, its constraints g <= 0 and its feasibility rule.  pymoo sees

* F: the objectives in their stored units; where one is NaN (a failed
  candidate, or forces skipped for a candidate already infeasible) the finite
  stand-in ``FAILED_OBJECTIVE``, which only infeasible candidates carry;
* G: the stored constraints (0 where a failed candidate has none) and one more,
  ``evaluable``: 0 for a candidate whose status is OK (and whose objectives are
  finite if it meets its constraints), ``FAILED_VIOLATION`` otherwise.  A
  failed status is thus a violated constraint, worse than any violation of a
  real one, and pymoo's feasibility (CV = 0) is exactly the stored ``feasible``.

Triangle inequalities of the variables (``sweep_spec.Triangle``) are met by a
**repair**, not a constraint: they are known before solving, so a proposed
design that breaks one is moved along the straight line towards a buildable
centre of the bounds until it is buildable (just inside the boundary; the
buildable part of the box is convex, so the line crosses its boundary once).
No evaluation is spent on a design that could only be BAD_GEOMETRY.

The hypervolume is that of the feasible front, the objectives divided by the
study's reference design's (``hv_scale``), reference point ``HV_REFERENCE``
in every objective.
"""

from __future__ import annotations

import numpy as np
from pymoo.core.problem import Problem
from pymoo.core.repair import Repair

from ..kernels import config as kc
from ..study.objectives import bounded_finite, constraint_names, constraints
from ..model.metric_catalogue import metric_values
from ..kernels.pareto import nondominated_rank
from ..study.search_spec import HV_REFERENCE
from .problem import SweepProblem
from ..study.sweep_spec import SweepSpec, parameter_rows

FAILED_VIOLATION = 1e12   # the `evaluable` constraint of a failed candidate: above any real one
FAILED_OBJECTIVE = 1e12   # pymoo's stand-in for an objective that is NaN (infeasible rows only)
REPAIR_STEP = 1e-3        # a repaired design lies this fraction of the way on past the boundary


# ----------------------------------------------------------------- the problem pymoo sees
def pymoo_view(spec: SweepSpec, status, metrics, has_margin):
    """(F, G) of evaluated rows as pymoo sees them (see the module's text)."""
    F = np.stack([metric_values(metrics, o) for o in spec.objectives], axis=1)
    G, cv = constraints(spec, metrics, status, has_margin)
    finite = np.isfinite(F).all(axis=1) & bounded_finite(spec, metrics)
    evaluable = (status == kc.OK) & ~((cv == 0) & ~finite)
    G = np.concatenate([np.where(np.isnan(G), 0.0, G),
                        np.where(evaluable, 0.0, FAILED_VIOLATION)[:, None]], axis=1)
    return np.where(np.isfinite(F), F, FAILED_OBJECTIVE), G


class SweepBlackBox(Problem):
    """The sweep's evaluator as a vectorised pymoo problem: design-variable
    rows X -> (F, G), one batch through the compiled kernels.  ``run_search``
    drives an algorithm by ask and tell; this works with
    ``pymoo.optimize.minimize`` too."""

    def __init__(self, problem: SweepProblem, evaluate=None):
        spec = problem.spec
        self.sweep = problem
        self.has_margin = problem.has_margin
        self.constraint_labels = constraint_names(self.has_margin, spec) + ["evaluable"]
        self._rows = evaluate or (lambda pars: problem.evaluate_rows(pars))
        super().__init__(n_var=len(spec.variables), n_obj=len(spec.objectives),
                         n_ieq_constr=len(self.constraint_labels),
                         xl=np.array([v.low for v in spec.variables]),
                         xu=np.array([v.high for v in spec.variables]))

    def results(self, X):
        """(status, metrics) of design-variable rows X."""
        return self._rows(parameter_rows(self.sweep.plan, self.sweep.spec, np.asarray(X, float)))

    def view(self, status, metrics):
        return pymoo_view(self.sweep.spec, status, metrics, self.has_margin)

    def _evaluate(self, X, out, *args, **kwargs):
        out["F"], out["G"] = self.view(*self.results(X))


# ----------------------------------------------------------------- triangles: a repair
def buildable_centre(spec: SweepSpec) -> np.ndarray:
    """A point strictly inside the bounds and every triangle: the mean of the
    buildable points of a fixed uniform probe of the box (the buildable part is
    convex, so its points' mean is inside it)."""
    lo = np.array([v.low for v in spec.variables])
    hi = np.array([v.high for v in spec.variables])
    if not spec.triangles:
        return 0.5 * (lo + hi)
    x = lo + np.random.default_rng(0).random((40000, len(lo))) * (hi - lo)
    ok = ~_broken(spec.triangles, x)
    return x[ok].mean(axis=0)


def _broken(triangles, x):
    bad = np.zeros(x.shape[0], bool)
    for t in triangles:
        bad |= t.broken(x)
    return bad


def _slack(t, x):
    """The three inequalities of triangle ``t`` as g < 0 (linear in x)."""
    a, b, c = t.sides(x)
    return np.stack([a - b - c, b - a - c, c - a - b], axis=1)


def repair_triangles(triangles, centre, X, lo, hi):
    """(X with every design that breaks a triangle moved towards ``centre``
    until it is buildable, number of designs moved).  Designs that are
    buildable are returned unchanged, bit for bit."""
    X = np.array(X, float)
    bad = _broken(triangles, X)
    if not bad.any():
        return X, 0
    x = X[bad]
    need = np.zeros(len(x))
    for t in triangles:
        gx, gc = _slack(t, x), _slack(t, centre[None, :])
        with np.errstate(divide="ignore", invalid="ignore"):
            cross = np.where(gx >= 0, gx / (gx - gc), 0.0)
        need = np.maximum(need, cross.max(axis=1))
    step = need + REPAIR_STEP * (1.0 - need)
    y = np.clip(x + step[:, None] * (centre - x), lo, hi)
    y[_broken(triangles, y)] = centre       # rounding at the boundary: the centre itself
    X[bad] = y
    return X, int(bad.sum())


class TriangleRepair(Repair):
    """pymoo's repair hook: proposals that break a triangle inequality moved
    inside it (``repair_triangles``); ``count`` counts them."""

    def __init__(self, spec: SweepSpec):
        super().__init__()
        self.triangles = spec.triangles
        self.centre = buildable_centre(spec)
        self.lo = np.array([v.low for v in spec.variables])
        self.hi = np.array([v.high for v in spec.variables])
        self.count = 0

    def _do(self, problem, X, **kwargs):
        return self.inside(X)

    def inside(self, X):
        """X with its broken designs moved inside (counted in ``count``)."""
        if not self.triangles:
            return X
        X, n = repair_triangles(self.triangles, self.centre, X, self.lo, self.hi)
        self.count += n
        return X


def hv_scale(problem: SweepProblem) -> np.ndarray:
    """The normalisation of the objectives: the reference design's values (1
    where a value is not a positive number)."""
    st, met = problem.evaluate_rows(np.ascontiguousarray(problem.plan.par[None, :]), False)
    ref = np.array([metric_values(met, o)[0] for o in problem.spec.objectives])
    return np.where((st[0] == kc.OK) & np.isfinite(ref) & (ref > 0), ref, 1.0)


class FrontTracker:
    """The feasible front of every candidate so far (objectives divided by
    ``scale``) and its hypervolume against HV_REFERENCE."""

    def __init__(self, scale):
        from pymoo.indicators.hv import HV
        self.scale = np.asarray(scale, float)
        self.front = np.zeros((0, len(self.scale)))
        self.feasible = 0
        self._hv = HV(ref_point=np.full(len(self.scale), HV_REFERENCE))

    def add(self, F, feasible) -> float:
        feasible = np.asarray(feasible, bool)
        self.feasible += int(feasible.sum())
        Z = np.concatenate([self.front, F[feasible] / self.scale])
        self.front = Z[nondominated_rank(Z) == 1] if len(Z) else Z
        return self.hypervolume

    @property
    def hypervolume(self) -> float:
        return float(self._hv(self.front)) if len(self.front) else 0.0


def hypervolume(F, feasible, scale) -> float:
    """Hypervolume of the feasible rows of F, normalised as the search's."""
    t = FrontTracker(scale)
    return t.add(np.asarray(F, float), feasible)
