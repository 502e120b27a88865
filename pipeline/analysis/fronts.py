"""Analysis of a sweep: Pareto fronts of the feasible candidates, which design
variables drive each objective, and a few representative trade-off designs.

``analyze(path)`` reads a sweep results file and writes the group
``/analysis`` into the same file (replacing an earlier one: the analysis is a
pure function of the file and the study seed, so re-running it gives the same
numbers):

* ``pareto_rank`` [N] (1 = non-dominated among the feasible candidates, 0 =
  infeasible), ``crowding`` [N] (NSGA-II, within each front), ``knee``;
* ``front1/`` the non-dominated designs sorted by the first objective
  (``index``, ``objectives``, ``params``, ``crowding``);
* ``reference/`` where the study's own design stands among the candidates
  (the front it would join, how many feasible candidates dominate it, which
  front-1 members do);
* ``importance/<objective>/`` a tree ensemble fitted on the feasible
  candidates with a held-out split (R^2) and permutation importances of the
  design variables on the held-out set;
* ``representatives/`` front-1 members nearest the centroids of a k-means
  clustering of the normalised front-1 objectives.

All objectives are minimised (DOMAIN.md section 9).  Every random choice
(subsampling, split, boosting, k-means) is seeded with the study seed.
"""

from __future__ import annotations

import datetime as _dt
import logging
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..base.version import __version__
from ..base.files import RunLock, replacing
from ..base.units import unit_text
from ..kernels import config as kc
from ..kernels.pareto import crowding_distance, knee_point, nondominated_rank
from ..results.storage import (attr_text, candidate_ids, coordinate, hdf5_image, open_results, put,
                               read_units, remove_group, results_output, variables)
from ..base.errors import ResultsError
from ..study.reader import stored_study
from .refined import REFINED_FRONTS, refine_fronts, refined_reference, write_refined

log = logging.getLogger("pipeline")

GROUP = "analysis"
DEFAULT_OBJECTIVES = ("dwell_error", "peak_reaction")
MIN_MODEL_SAMPLES = 20        # fewer feasible candidates than this: no model
MAX_MODEL_SAMPLES = 20_000    # feasible candidates used for a model (train + test)
TEST_FRACTION = 0.25
N_BOOST = 200                 # boosting iterations
N_REPEATS = 5                 # permutation-importance repeats
MAX_PERMUTATION_ROWS = 2500   # held-out rows shuffled per variable and repeat
KMEANS_N_INIT = 10


# ----------------------------------------------------------------- reading
@dataclass
class SweepData:
    """The parts of a sweep results file the analysis reads."""
    path: Path
    attrs: dict
    names: list               # design-variable names
    units: list               # their units
    params: np.ndarray        # (N, P)
    status: np.ndarray        # (N,) int8
    feasible: np.ndarray      # (N,) bool
    objectives: tuple         # names
    objective_units: list
    F: np.ndarray             # (N, m) objective values
    reference: dict = field(default_factory=dict)
    ids: np.ndarray | None = None   # (N,) the candidate index of each row (store = feasible)
    metric_units: dict = field(default_factory=dict)   # every stored metric's units

    def id(self, i) -> int:
        """The sweep's candidate index of row ``i``."""
        return int(i) if self.ids is None else int(self.ids[i])

    @property
    def n(self):
        return self.params.shape[0]

    @property
    def seed(self):
        return int(self.attrs.get("seed", 0)) % 2 ** 32


def sweep_objectives(f) -> tuple:
    """The study's objectives (root attribute ``objectives``), all minimised."""
    obj = f.attrs.get("objectives")
    if obj is None or len(obj) == 0:
        obj = DEFAULT_OBJECTIVES
    names = tuple(str(attr_text(o)) for o in np.atleast_1d(obj))
    missing = [o for o in names if f"metrics/{o}" not in f]
    if missing:
        raise ResultsError(f.filename, f"objective {missing[0]!r} has no dataset metrics/"
                                       f"{missing[0]}; the file is damaged or not a sweep")
    return names


def variable_units(d) -> list:
    """Units of the design variables (one per column)."""
    return read_units(d, d.shape[-1])


def read_sweep(path) -> SweepData:
    """Read a sweep results file (ResultsError if it is not one)."""
    with open_results(path, "sweep") as f:
        for need in ("candidates/params", "candidates/status", "candidates/feasible"):
            if need not in f:
                raise ResultsError(path, f"has no dataset {need}; the sweep file is damaged")
        d = f["candidates/params"]
        names = [str(attr_text(x)) for x in d.attrs.get("names", [])] or \
            [f"x{j}" for j in range(d.shape[1])]
        objectives = sweep_objectives(f)
        F = np.stack([f[f"metrics/{o}"][()] for o in objectives], axis=1).astype(np.float64)
        ref = {}
        if "reference" in f:
            g = f["reference"]
            for k in variables(g):
                ref[k] = g[k][()]
        return SweepData(
            path=Path(path), attrs={k: f.attrs[k] for k in f.attrs}, names=names,
            units=variable_units(d), params=d[()], status=f["candidates/status"][()],
            feasible=f["candidates/feasible"][()].astype(bool), objectives=objectives,
            objective_units=[unit_text(attr_text(f[f"metrics/{o}"].attrs.get("units", "1")))
                             for o in objectives],
            F=F, reference=ref, ids=candidate_ids(f),
            metric_units={m: unit_text(attr_text(f[f"metrics/{m}"].attrs.get("units", "1")))
                          for m in variables(f["metrics"])})


def has_analysis(f) -> bool:
    """True if the open file carries a complete, current ``/analysis``."""
    if GROUP not in f:
        return False
    g = f[GROUP]
    if not bool(g.attrs.get("complete", False)) or "pareto_rank" not in g:
        return False
    return g["pareto_rank"].shape[0] == f["candidates/status"].shape[0]


# ----------------------------------------------------------------- fronts
def reference_standing(F, feasible, rank, ref_obj):
    """Where a design with objectives ``ref_obj`` stands among the candidates:
    (front it would join, indices of the feasible candidates that dominate it)."""
    ref_obj = np.asarray(ref_obj, float)
    if not np.isfinite(ref_obj).all():
        return 0, np.zeros(0, np.int64)
    with np.errstate(invalid="ignore"):
        dom = feasible & (F <= ref_obj).all(axis=1) & (F < ref_obj).any(axis=1)
    idx = np.flatnonzero(dom).astype(np.int64)
    front = int(rank[idx].max()) + 1 if idx.size else 1
    return front, idx


def _reference_feasible(data: SweepData, spec):
    """The reference design's feasibility, judged like a candidate's."""
    ref = data.reference
    if "status" not in ref or int(np.ravel(ref["status"])[0]) != kc.OK:
        return False, "the reference design does not assemble"
    vals = {k: float(np.ravel(v)[0]) for k, v in ref.items() if k not in ("params", "status")}
    if spec is not None and "stroke" in vals:
        lo, hi = spec.stroke_bounds
        if not lo <= vals["stroke"] <= hi:
            return False, f"stroke {vals['stroke']:.3g} mm outside [{lo:g}, {hi:g}]"
    if spec is not None and np.isfinite(vals.get("singularity_margin", np.nan)) and \
            vals["singularity_margin"] < spec.margin_min:
        return False, f"singularity margin {vals['singularity_margin']:.3g} < {spec.margin_min:g}"
    for m, lo, hi in (spec.bounds if spec is not None else ()):   # [sweep.constraints] bounds
        v = vals.get(m, np.nan)
        if not np.isfinite(v):
            return False, f"{m} not computed"
        if not lo <= v <= hi:
            return False, f"{m} {v:.4g} outside [{lo:g}, {hi:g}]"
    return True, "feasible"


# ----------------------------------------------------------------- models
def fit_importance(X, y, names, seed, *, max_samples=MAX_MODEL_SAMPLES, n_jobs=1,
                   n_repeats=N_REPEATS) -> dict:
    """A gradient-boosted tree ensemble of ``y`` on the design variables ``X``
    with a held-out split, and the permutation importances of the variables on
    the held-out set.

    The target is log10(y) when y > 0 throughout (the objectives span decades
    and their relative differences matter); R^2 is reported on that scale.
    At most ``max_samples`` rows are used (a seeded subsample).  OpenMP threads
    are limited to ``n_jobs`` (the numbers do not depend on it).  Returns a dict
    with ``fitted`` False and a ``reason`` when a model cannot be made."""
    from sklearn.ensemble import HistGradientBoostingRegressor
    from sklearn.inspection import permutation_importance
    from sklearn.model_selection import train_test_split
    from threadpoolctl import threadpool_limits

    ok = np.isfinite(y) & np.isfinite(X).all(axis=1)
    X, y = X[ok], y[ok]
    n = len(y)
    out = {"fitted": False, "n_available": n}
    if n < MIN_MODEL_SAMPLES:
        out["reason"] = (f"only {n} feasible candidates with a finite value; a model needs at "
                         f"least {MIN_MODEL_SAMPLES}")
        return out
    if not np.ptp(y) > 0:
        out["reason"] = "the objective is constant over the feasible candidates"
        return out
    rng = np.random.default_rng(seed)
    if n > max_samples:
        sel = np.sort(rng.choice(n, max_samples, replace=False))
        X, y = X[sel], y[sel]
    log_target = bool((y > 0).all())
    t = np.log10(y) if log_target else y
    Xtr, Xte, ttr, tte = train_test_split(X, t, test_size=TEST_FRACTION, random_state=seed)
    model = HistGradientBoostingRegressor(max_iter=N_BOOST, learning_rate=0.1,
                                          early_stopping=False, random_state=seed)
    with threadpool_limits(limits=max(1, int(n_jobs)), user_api="openmp"):
        model.fit(Xtr, ttr)
        r2_test = float(model.score(Xte, tte))
        r2_train = float(model.score(Xtr, ttr))
        # the split is shuffled: its first rows are a random subset of the test set
        m = min(len(tte), MAX_PERMUTATION_ROWS)
        pi = permutation_importance(model, Xte[:m], tte[:m], n_repeats=n_repeats,
                                    random_state=seed, n_jobs=1)
    out.update(fitted=True, reason="",
               model=f"HistGradientBoostingRegressor(max_iter={N_BOOST}, learning_rate=0.1)",
               target="log10" if log_target else "identity", r2_test=r2_test, r2_train=r2_train,
               n_train=len(ttr), n_test=len(tte), n_permutation=m,
               importance_mean=pi.importances_mean,
               importance_std=pi.importances_std)
    return out


def representatives(F, front_idx, k, seed) -> tuple[np.ndarray, np.ndarray]:
    """Up to ``k`` front-1 members (indices into F, sorted by the first
    objective) nearest the centroids of a k-means clustering of the front-1
    objectives normalised to [0, 1]; and the size of each one's cluster."""
    from sklearn.cluster import KMeans
    idx = np.asarray(front_idx, np.int64)
    if idx.size == 0 or k < 1:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    X = F[idx]
    lo, rng_ = X.min(axis=0), np.ptp(X, axis=0)
    Z = np.where(rng_ > 0, (X - lo) / np.where(rng_ > 0, rng_, 1.0), 0.0)
    distinct = np.unique(Z, axis=0).shape[0]
    k = min(k, distinct)
    if k == idx.size:
        order = np.lexsort(F[idx].T[::-1])
        return idx[order], np.ones(k, np.int64)
    from threadpoolctl import threadpool_limits
    with threadpool_limits(limits=1, user_api="openmp"):   # summation order fixed
        km = KMeans(n_clusters=k, n_init=KMEANS_N_INIT, random_state=seed).fit(Z)
    chosen, sizes = [], []
    for c in range(k):
        d = np.linalg.norm(Z - km.cluster_centers_[c], axis=1)
        d[np.isin(idx, chosen)] = np.inf       # one member per cluster, never twice
        j = int(np.argmin(d))                   # ties: lowest position (front sorted)
        chosen.append(int(idx[j]))
        sizes.append(int((km.labels_ == c).sum()))
    chosen, sizes = np.array(chosen, np.int64), np.array(sizes, np.int64)
    order = np.lexsort(F[chosen].T[::-1])
    return chosen[order], sizes[order]


# ----------------------------------------------------------------- the analysis
def _study_spec(data: SweepData):
    """The study's sweep spec, rebuilt from the TOML stored in the file (None if
    the file has none)."""
    study = stored_study(data.attrs, data.path)
    return study.sweep if study is not None else None


def compute(data: SweepData, n_representatives=5, *, max_samples=MAX_MODEL_SAMPLES,
            n_jobs=1, stage=None) -> dict:
    """Every number of the analysis (no file I/O but the refinement's scenes): the
    refinement on ``n_jobs`` processes (``refine_fronts``), the models on as many
    threads; the numbers do not depend on it."""
    feas = data.feasible
    try:
        study = stored_study(data.attrs, data.path)
    except ValueError:           # a study this version cannot read: no refinement
        study = None
    F, refined = refine_fronts(data, study, stage, n_jobs)
    rank = nondominated_rank(F, feas)
    crowd = crowding_distance(F, rank)
    knee = knee_point(F, rank)
    front = np.flatnonzero(rank == 1)
    front = front[np.lexsort(F[front].T[::-1])] if front.size else front.astype(np.int64)
    res = {"rank": rank, "crowding": crowd, "knee": int(knee), "front1": front.astype(np.int64),
           "F": F, "refined": refined}

    # the study's reference design
    ref_obj = np.array([float(np.ravel(data.reference.get(o, [np.nan]))[0])
                        for o in data.objectives])
    ref_obj = refined_reference(data, study, refined, ref_obj)
    spec = study.sweep if study is not None else None   # None: judged without constraints
    ref_feasible, ref_note = _reference_feasible(data, spec)
    ref_rank, dominators = reference_standing(F, feas, rank, ref_obj)
    res["reference"] = {"objectives": ref_obj, "feasible": ref_feasible, "note": ref_note,
                        "rank": ref_rank, "dominated_by": dominators,
                        "dominators_front1": dominators[rank[dominators] == 1]}

    # models: one per objective, on the feasible candidates (the grid's values: all alike)
    X = data.params[feas]
    res["models"] = {o: fit_importance(X, data.F[feas, j], data.names, data.seed,
                                       max_samples=max_samples, n_jobs=n_jobs)
                     for j, o in enumerate(data.objectives)}
    reps, sizes = representatives(F, front, n_representatives, data.seed)
    res["representatives"] = reps
    res["cluster_size"] = sizes
    return res


def write(path, data: SweepData, res: dict, elapsed: float):
    """Write (or replace) ``/analysis`` of the results file: on a copy, renamed
    over the file when complete, so a failure (a full disk, a kill) leaves the
    sweep as it was."""
    path = Path(path)
    with RunLock(path, "a sweep or another analysis is writing this file"), \
            replacing(path) as tmp, hdf5_image(tmp, start=path) as f:
        _write_group(f, data, res, elapsed)


def _write_group(f, data: SweepData, res: dict, elapsed: float):
    names, units = data.names, data.units
    obj, ou = list(data.objectives), data.objective_units
    remove_group(f, GROUP)
    g = f.create_group(GROUP)
    g.attrs.update(
        long_name="Pareto fronts, parameter importances and representative designs",
        objectives=obj, sense="minimize", seed=data.seed, software="pipeline",
        software_version=__version__,
        created=_dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        n_candidates=data.n, n_feasible=int(data.feasible.sum()),
        n_fronts=int(res["rank"].max(initial=0)), elapsed_s=elapsed, complete=False)
    if "objective" not in g:
        coordinate(g, "objective", obj, "1", "objective (minimised)")
    put(g, "pareto_rank", res["rank"].astype(np.int32), "1",
        "Pareto front of the candidate (1 = non-dominated; 0 = infeasible)",
        dims=("candidate",))
    put(g, "crowding", res["crowding"], "1",
        "NSGA-II crowding distance within the candidate's front (inf at the ends)",
        dims=("candidate",))
    put(g, "knee", np.int64(res["knee"]), "1",
        "candidate index of the knee of front 1 (-1: empty front)")

    fr = g.create_group("front1")
    fr.attrs["long_name"] = "non-dominated feasible designs, sorted by the first objective"
    idx = res["front1"]
    coordinate(fr, "member", np.arange(len(idx)), "1", "member of front 1")
    put(fr, "index", idx, "1", "candidate index", dims=("member",))
    ranked = res["refined"]["ranked_on"]
    put(fr, "objectives", res["F"][idx].reshape(len(idx), len(obj)), list(ou),
        "objectives (minimised) the fronts are ranked on" + (
            f" ({', '.join(ranked)} refined between positions: /{GROUP}/refined)"
            if ranked else ""), dims=("member", "objective"), names=obj)
    put(fr, "params", data.params[idx].reshape(len(idx), len(names)), list(units),
        "design variables", dims=("member", "variable"), names=names)
    put(fr, "crowding", res["crowding"][idx], "1", "crowding distance within front 1",
        dims=("member",))

    ref = res["reference"]
    rg = g.create_group("reference")
    rg.attrs["long_name"] = "the study's reference design among the candidates"
    rg.attrs["feasibility"] = ref["note"]
    put(rg, "objectives", ref["objectives"], list(ou), "objectives of the reference "
        "design", dims=("objective",), names=obj)
    put(rg, "feasible", np.bool_(ref["feasible"]), "1",
        "the reference design meets the study's constraints")
    put(rg, "rank", np.int32(ref["rank"]), "1", "front the reference design would join "
        "among the feasible candidates (1 = nobody dominates it; 0 = objectives not finite)")
    put(rg, "dominated_by_count", np.int64(len(ref["dominated_by"])), "1",
        "number of feasible candidates that dominate the reference design")
    coordinate(rg, "dominator", np.arange(len(ref["dominated_by"])), "1",
               "feasible candidate that dominates the reference design")
    coordinate(rg, "front1_dominator", np.arange(len(ref["dominators_front1"])), "1",
               "front-1 member that dominates the reference design")
    put(rg, "dominated_by", ref["dominated_by"], "1",
        "indices of the feasible candidates that dominate the reference design",
        dims=("dominator",))
    put(rg, "dominators_front1", ref["dominators_front1"], "1",
        "indices of the front-1 members that dominate the reference design",
        dims=("front1_dominator",))

    ig = g.create_group("importance")
    ig.attrs["long_name"] = ("gradient-boosted tree model of each objective on the design "
                             "variables (feasible candidates): held-out R^2 and permutation "
                             "importances")
    ig.attrs["variables"] = names
    for o, m in res["models"].items():
        og = ig.create_group(o)
        og.attrs["fitted"] = m["fitted"]
        og.attrs["reason"] = m.get("reason", "")
        og.attrs["n_available"] = m["n_available"]
        if not m["fitted"]:
            continue
        og.attrs.update(model=m["model"], target=m["target"], n_train=m["n_train"],
                        n_test=m["n_test"], n_permutation=m["n_permutation"],
                        n_repeats=N_REPEATS)
        put(og, "mean", m["importance_mean"], "1", "permutation importance: mean drop of "
            "the held-out R^2 when the variable is shuffled", dims=("variable",), names=names)
        put(og, "std", m["importance_std"], "1", "permutation importance: standard "
            "deviation over the repeats", dims=("variable",), names=names)
        put(og, "r2_test", np.float64(m["r2_test"]), "1",
            f"held-out R^2 of the model ({m['target']} target)")
        put(og, "r2_train", np.float64(m["r2_train"]), "1",
            f"training R^2 of the model ({m['target']} target)")

    write_refined(f, g, data, res["refined"])

    rp = g.create_group("representatives")
    rp.attrs["long_name"] = ("front-1 designs nearest the k-means centroids of the "
                             "normalised front-1 objectives")
    rp.attrs["method"] = f"KMeans(n_init={KMEANS_N_INIT}, random_state=seed)"
    coordinate(rp, "representative", np.arange(len(res["representatives"])), "1",
               "representative design")
    put(rp, "index", res["representatives"], "1", "candidate index", dims=("representative",))
    put(rp, "cluster_size", res["cluster_size"], "1", "front-1 members in its cluster",
        dims=("representative",))
    g.attrs["complete"] = True


def summary(data: SweepData, res: dict, elapsed: float) -> dict:
    """What `pipeline analyze` prints."""
    F, obj = res["F"], data.objectives
    drawn = int(data.attrs.get("n_candidates", data.n))
    out = {"results": str(data.path),
           "candidates": drawn if drawn == data.n else f"{drawn} ({data.n} feasible stored)",
           "feasible": int(data.feasible.sum()), "fronts": int(res["rank"].max(initial=0)),
           "front 1": len(res["front1"])}
    if not data.attrs.get("complete", True):
        out["warning"] = "the sweep is unfinished: only evaluated candidates are ranked"

    def fmt(i):       # with units (a pure number's 1 left out)
        return ", ".join(f"{o} {F[i, j]:.4g}" + ("" if u in ("", "1") else f" {u}")
                         for j, (o, u) in enumerate(zip(obj, data.objective_units)))
    if res["knee"] >= 0:
        out["knee"] = f"#{data.id(res['knee'])}: {fmt(res['knee'])}"
    if not out["feasible"]:
        out["note"] = ("no candidate is feasible, so there is no front: the constraints are " +
                       _constraints_words(data))
    ref = res["reference"]
    if ref["rank"] > 0 and ref["feasible"]:
        out["reference design"] = (
            f"front {ref['rank']} (feasible); dominated by {len(ref['dominated_by'])} "
            f"candidates, {len(ref['dominators_front1'])} of them on front 1")
    elif not ref["feasible"]:    # an infeasible design is on no front
        out["reference design"] = f"infeasible ({ref['note']}): on no front" + (
            f"; {len(ref['dominated_by'])} feasible candidates dominate it, "
            f"{len(ref['dominators_front1'])} of them on front 1" if ref["rank"] > 0 else "")
    else:
        out["reference design"] = "objectives not finite: not ranked"
    for o, m in res["models"].items():
        if m["fitted"]:
            top = np.argsort(-m["importance_mean"])[:3]
            out[f"model {o}"] = (f"held-out R^2 {m['r2_test']:.3f} ({m['target']}, "
                                 f"n_test {m['n_test']}); top: " + ", ".join(
                                     f"{data.names[j]} {m['importance_mean'][j]:.3f}"
                                     for j in top))
        else:
            out[f"model {o}"] = f"skipped: {m['reason']}"
    r = res["refined"]
    if len(r["rows"]):
        failed = int((r["status"] != kc.OK).sum())
        out["refined peaks"] = (
            f"{len(r['rows'])} designs of fronts 1-{REFINED_FRONTS}: " +
            ", ".join(r["metrics"]) + " refined between positions as their scenes refine "
            f"them (/{GROUP}/refined)" +
            (f"; fronts ranked on the refined {', '.join(r['ranked_on'])}"
             if r["ranked_on"] else "") +
            (f"; {failed} scenes failed (their grid values ranked)" if failed else ""))
    out["representatives"] = " ".join(f"#{data.id(i)}" for i in res["representatives"]) or \
        "none"
    out["time"] = f"{elapsed:.1f} s"
    return out


def _constraints_words(data: SweepData) -> str:
    """The stored study's constraints in words (``constraints_text``)."""
    from ..study.objectives import constraints_text
    try:
        spec = _study_spec(data)
    except ValueError:
        spec = None
    if spec is None:
        return "those of a study this version cannot read"
    # a class III plan's margin (NaN elsewhere), where the file keeps it
    has_margin = bool(np.isfinite(np.ravel(data.reference.get("singularity_margin",
                                                             [np.nan]))[:1]).all())
    return constraints_text(spec, has_margin)


def analyze(path, n_representatives=5, *, max_samples=MAX_MODEL_SAMPLES, n_jobs=1) -> dict:
    """Rank the feasible candidates of a sweep results file into Pareto fronts,
    model each objective, pick representative designs, and write ``/analysis``
    into the file.  Returns a summary (for the command line)."""
    if n_representatives < 0:
        raise ValueError(f"the number of representatives must be >= 0, got {n_representatives}")
    if max_samples < 2 * MIN_MODEL_SAMPLES:
        raise ValueError(f"--max-samples must be at least {2 * MIN_MODEL_SAMPLES}")
    if n_jobs is None or n_jobs < 1:
        raise ValueError(f"--jobs must be at least 1, got {n_jobs}")
    # the analysis is written into the file itself: only into a results file, never
    # through a link to nothing (one to a sweep's file updates that file); read as the
    # input first, so that a file that is no sweep's is said as such
    open_results(path, "sweep").close()
    results_output(path, overwrite=True)
    from ..base.progress import ticking
    t0 = time.perf_counter()
    with ticking("analyze") as stage:
        stage.set("reading the candidates")
        data = read_sweep(path)
        stage.set("fronts, parameter importances, representatives")
        res = compute(data, n_representatives, max_samples=max_samples, n_jobs=n_jobs,
                      stage=stage)
        stage.set("fronts, parameter importances, representatives")
        elapsed = time.perf_counter() - t0
        stage.set("writing /analysis")
        write(path, data, res, elapsed)
    log.debug("analysis of %s written in %.1f s", path, elapsed)
    return summary(data, res, elapsed)


# ----------------------------------------------------------------- reading it back
@dataclass
class Analysis:
    """The stored ``/analysis`` group, read back."""
    rank: np.ndarray
    crowding: np.ndarray
    knee: int
    front1: np.ndarray
    representatives: np.ndarray
    reference: dict
    models: dict
    attrs: dict


def read_analysis(f) -> Analysis | None:
    """The stored analysis of an open sweep file (None if absent or stale)."""
    if not has_analysis(f):
        return None
    g = f[GROUP]
    models = {}
    for o, og in g["importance"].items():
        m = {k: (attr_text(v) if isinstance(v, bytes) else v) for k, v in og.attrs.items()}
        for k in og:
            m[k] = og[k][()]
        models[o] = m
    ref = {k: g["reference"][k][()] for k in variables(g["reference"])}
    ref["note"] = attr_text(g["reference"].attrs.get("feasibility", ""))
    return Analysis(rank=g["pareto_rank"][()], crowding=g["crowding"][()],
                    knee=int(g["knee"][()]), front1=g["front1/index"][()],
                    representatives=g["representatives/index"][()], reference=ref,
                    models=models, attrs={k: g.attrs[k] for k in g.attrs})
