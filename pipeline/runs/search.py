"""Adaptive search: an established multi-objective optimizer from pymoo
(NSGA-II, SMS-EMOA or AGE-MOEA, each with pymoo's own operators and settings)
driving the sweep's evaluator, one generation per batch through the compiled
kernels (``SweepProblem.evaluate_rows``: all cores, or split into Dask tasks).

The problem pymoo sees (the objectives and constraints as F and G, the repair
of triangle inequalities, the front's hypervolume) is search_problem.py's; the
results file's layout and reading it back are search_file.py's.  The first
generation is the project's own Sobol draws (impossible triangles redrawn, as
the sweep does), after the front of an earlier results file if one is given
(``--from``): explore with the Monte-Carlo sweep, then refine.

Every evaluated design is a candidate of the sweep's file layout
(``SweepFile``; generation g in its own block of rows), so analyze, browse,
show, report and export read a search like a sweep.  ``candidates/generation``
says which generation proposed each candidate; ``/search`` holds, per
generation, the evaluations so far and the hypervolume of the feasible front
so far (objectives divided by the study's reference design's, reference point
1.1 in every objective).

Never losing work: every generation's designs and results are saved in the
journal ``OUT.h5.parts`` before they go into the file, the generations
finished within a quarter of a second in one block (one atomic write, as a
sweep's chunk; an interruption saves what is finished).  ``--resume`` re-runs
the algorithm from its seed and answers its asks from the journal instead of
evaluating (checking that the asked designs are the journalled ones, bit for
bit), then goes on: the file is identical to an uninterrupted run's.  The
algorithm runs in this process only; evaluations are per design, so the
numbers do not depend on the thread count or the engine.
"""

from __future__ import annotations

import hashlib
import io
import logging
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..base.files import RunLock
from ..base.progress import ticking
from ..kernels import sweep as ks
from ..kernels.pareto import crowding_distance, nondominated_rank
from ..model.metric_catalogue import ROBUST_OF
from ..results.search_file import SearchFile, search_summary
from .builds import Watch
from .search_problem import FrontTracker, SweepBlackBox, TriangleRepair, _broken, hv_scale
from ..study.search_spec import METHODS, SearchSpec
from ..results.storage import attr_text, hdf5_writing, open_results, same_study, study_digest
from ..base.errors import ResultsError
from ..results.journal import MANIFEST_DEFAULTS, Journal
from .lifecycle import (SaveThenWrite, SweepOutcome, aside_or_done, check_existing, finish_run,
                        journalled, stopping_safely)
from .sweep import build_problem
from ..study.objectives import feasibility
from .problem import SweepProblem
from ..compiler.notice import compile_notice
from ..study.sweep_spec import SweepSpec, parameter_rows
from ..study.sampling import draw_checked

log = logging.getLogger("pipeline")

JOURNAL_KIND = "search"
JOURNAL_VERSION = 1
JOURNAL_EVERY_S = 0.25    # generations finished within this are journalled together (one
                          # atomic write; a generation of 100 takes a few milliseconds)

# ----------------------------------------------------------------- the first generation
def initial_designs(spec: SweepSpec, search: SearchSpec, seeds=None) -> np.ndarray:
    """The first generation: ``seeds`` (an earlier front), then the project's
    Sobol draws seeded by the search's seed (impossible triangles redrawn)
    up to the population."""
    d = len(spec.variables)
    seeds = np.zeros((0, d)) if seeds is None else np.asarray(seeds, float)[:search.population]
    fill = search.population - len(seeds)
    if fill:
        draws = replace(spec, candidates=fill, chunk_size=fill, seed=search.seed,
                        sampler="sobol")
        seeds = np.concatenate([seeds, draw_checked(draws, 0)[0]])
    return np.ascontiguousarray(seeds)


def front_seeds(path, spec: SweepSpec, n: int) -> np.ndarray:
    """Up to ``n`` designs of an earlier results file (a sweep or a search of
    the same variables): its feasible designs inside this study's bounds and
    triangles, front 1 first, then front 2, ..., the least crowded first
    within a front."""
    path = Path(path)
    with open_results(path, "sweep") as f:
        p = f["candidates/params"]
        names = [str(attr_text(x)) for x in p.attrs.get("names", [])]
        params = [str(attr_text(x)) for x in p.attrs.get("params", [])]
        want = [v.name for v in spec.variables]
        if names != want or (params and params != [v.param for v in spec.variables]):
            raise ResultsError(path, f"its design variables ({', '.join(names)}) are not this "
                                     f"study's ({', '.join(want)}); cannot seed the search "
                                     "from it")
        # a robust objective (robust_dwell_error) that the earlier file lacks: its front
        # by the metric the robust one is a quantile of (the designs that matter)
        objectives = [o if f"metrics/{o}" in f else ROBUST_OF.get(o) or o
                      for o in spec.objectives]
        missing = [o for o in objectives if f"metrics/{o}" not in f]
        if missing:
            raise ResultsError(path, f"has no metrics/{missing[0]}, an objective of this study")
        X = p[()]
        feasible = f["candidates/feasible"][()].astype(bool)
        F = np.stack([f[f"metrics/{o}"][()] for o in objectives], axis=1)
    lo = np.array([v.low for v in spec.variables])
    hi = np.array([v.high for v in spec.variables])
    with np.errstate(invalid="ignore"):
        ok = feasible & np.isfinite(F).all(axis=1) & ((X >= lo) & (X <= hi)).all(axis=1)
    ok &= ~_broken(spec.triangles, np.where(np.isfinite(X), X, lo))
    if not ok.any():
        raise ResultsError(path, "holds no feasible design inside this study's bounds to "
                                 "seed the search with")
    rank = nondominated_rank(F, ok)
    crowd = crowding_distance(F, rank)
    idx = np.flatnonzero(rank >= 1)
    order = np.lexsort((idx, -crowd[idx], rank[idx]))
    return np.ascontiguousarray(X[idx[order[:n]]])


# ----------------------------------------------------------------- the algorithm
def make_algorithm(search: SearchSpec, x0: np.ndarray, repair: TriangleRepair, box):
    """The optimizer of ``search.method`` seeded with ``search.seed``, its
    first population ``x0``, pymoo's default operators for that method, as an
    ask (designs) and tell (designs, F, G) pair on arrays.  NSGA-II runs on
    arrays (``nsga2.ArrayNSGA2``: pymoo's NSGA2 bit for bit, without pymoo's
    per-design objects, about 8 ms a generation of 100); the others in pymoo
    itself."""
    if search.method == "nsga2":
        from .nsga2 import ArrayNSGA2
        return ArrayNSGA2(search.population, search.offspring, x0, box.xl, box.xu,
                          search.seed, repair=repair.inside)
    return _InPymoo(search, x0, repair, box)


class _InPymoo:
    """A pymoo algorithm (``METHODS``) driven by ask and tell on arrays."""

    def __init__(self, search: SearchSpec, x0, repair, box):
        import importlib
        from pymoo.core.termination import NoTermination
        module, name = METHODS[search.method]
        cls = getattr(importlib.import_module(module), name)
        self.box = box
        self.algorithm = cls(pop_size=search.population, n_offsprings=search.offspring,
                             sampling=x0, repair=repair)
        self.algorithm.setup(box, termination=NoTermination(), seed=search.seed, verbose=False,
                             progress=False)
        self._pop = None

    def ask(self) -> np.ndarray:
        self._pop = self.algorithm.ask()
        if self._pop is None:
            return np.zeros((0, self.box.n_var))
        return self._pop.get("X")

    def tell(self, X, F, G):
        """The designs asked (or the first of them) with their F and G."""
        from pymoo.problems.static import StaticProblem
        pop = self._pop[:len(X)]
        # pymoo's Evaluator.eval method (not Python's eval): hands the computed F, G to the
        # population and counts the evaluations
        self.algorithm.evaluator.eval(StaticProblem(self.box, F=F, G=G), pop)
        self.algorithm.tell(infills=pop)


# ----------------------------------------------------------------- evaluation engines
class _Local:
    """All cores of this machine; ``watch`` (``builds.Watch``) is told of the
    progress within a generation (its robust builds, slice by slice)."""

    def __init__(self, problem: SweepProblem, n_jobs, watch=None):
        if n_jobs is not None and n_jobs < 1:
            raise ValueError(f"--jobs must be at least 1, got {n_jobs}")
        self.problem, self.n_jobs, self.watch = problem, n_jobs, watch

    def __call__(self, pars):
        return self.problem.evaluate_rows(pars, True, self.n_jobs, self.watch)


def evaluate_rows_task(problem, pars):
    """Dask task: rows of one generation on one worker thread."""
    return problem.evaluate_rows(pars, parallel=False)


class _Dask:
    """A generation split into tasks (at least one per worker thread, at most
    the sweep's chunk size each), gathered in order."""

    def __init__(self, problem: SweepProblem, client):
        self.client = client
        self.remote = client.scatter(problem, broadcast=True)
        self.max_rows = problem.spec.chunk_size

    def __call__(self, pars):
        n = len(pars)
        threads = max(1, sum(self.client.nthreads().values()))
        k = min(n, max(threads, math.ceil(n / self.max_rows)))
        cuts = np.linspace(0, n, k + 1).astype(int)
        futures = [self.client.submit(evaluate_rows_task, self.remote, pars[lo:hi], pure=False)
                   for lo, hi in zip(cuts[:-1], cuts[1:])]
        parts = self.client.gather(futures)
        return (np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]))


# ----------------------------------------------------------------- journal
def manifest_for(study, search: SearchSpec, x0, seeded_from, n_seeded):
    import pymoo
    return {"journal_kind": JOURNAL_KIND, "journal_version": JOURNAL_VERSION,
            **study_digest(study),
            "study_file": str(study.path), "method": search.method,
            "population": search.population, "offspring": search.offspring,
            "generations": search.generations, "seed": search.seed,
            "positions": study.sweep.positions, "metric_columns": ks.N_METRICS,
            "pymoo": pymoo.__version__,
            "first_generation_sha256": hashlib.sha256(x0.tobytes()).hexdigest(),
            "seeded_from": str(seeded_from) if seeded_from else "", "seeded": n_seeded}


def _save_first(journal: Journal, x0):
    buf = io.BytesIO()
    np.save(buf, x0)
    journal._atomic(journal.dir / "first_generation.npy", buf.getvalue())


def _load_first(journal: Journal):
    p = journal.dir / "first_generation.npy"
    try:
        return np.load(p)
    except (OSError, ValueError) as e:
        raise ResultsError(p, f"damaged journal ({e}); the search cannot be resumed: run it "
                              "again into a new file") from None


def _check_existing(out: Path, journal: Journal, study, want, resume, overwrite):
    def journal_diff(man):
        if man.get("journal_kind") != JOURNAL_KIND:
            raise ResultsError(journal.dir, "belongs to an interrupted Monte-Carlo sweep, not a "
                                            "search; refusing to mix results")
        # resumed without --from: the first generation is the journal's
        skip = {"study_file", "seeded_from"} | (set() if want.get("seeded_from")
                                                 else {"first_generation_sha256", "seeded"})
        return [k for k in want if k not in skip
                and man.get(k, MANIFEST_DEFAULTS.get(k)) != want[k]]

    check_existing(out, journal, resume, overwrite, journal_diff=journal_diff,
                   same_results=lambda f: (same_study(f, study) and
                                           attr_text(f.attrs.get("kind_detail", "")) == "search"),
                   what="search", other="or a Monte-Carlo sweep")


# ----------------------------------------------------------------- running
def run_search(study, out, *, seed_from=None, resume=False, overwrite=False, scheduler=None,
               client=None, n_jobs=None, progress=True, on_generation=None,
               stop_after_generations=None) -> SweepOutcome:
    """Run (or resume) the [search] of a sweep study into ``out``, its first
    generation seeded with the front of the results file ``seed_from`` if
    given.  ``on_generation(row)`` is called after every generation with its
    history row (generation, evaluations, hypervolume, ...)."""
    if study.search is None:
        raise ValueError(f"{study.path}: no [search] section; it runs as a Monte-Carlo sweep")
    out = Path(out)
    if seed_from is not None and Path(seed_from).resolve() == out.resolve():
        raise ValueError(f"--from {seed_from}: that is the output file; seed from another one")
    scheduler = scheduler or study.sweep.scheduler
    with RunLock(out):
        return _run_locked(study, out, seed_from, resume, overwrite, scheduler, client, n_jobs,
                           progress, on_generation, stop_after_generations)


def _run_locked(study, out, seed_from, resume, overwrite, scheduler, client, n_jobs, progress,
                on_generation, stop_after):
    search, spec = study.search, study.sweep
    journal = Journal(out)
    # said at once: the first generation's draw and the kernels' load take a second or more
    log.info("%s: an adaptive search, population %d, into %s", study.name, search.population,
             out)
    seeds = front_seeds(seed_from, spec, search.population) if seed_from else None
    with ticking("drawing the first generation", after=1.0, say_done=False):
        x0 = initial_designs(spec, search, seeds)   # the sampler's import: a second or more
    n_seeded = 0 if seeds is None else len(seeds)
    want = manifest_for(study, search, x0, seed_from, n_seeded)
    _check_existing(out, journal, study, want, resume, overwrite)
    done = aside_or_done(out, journal, resume, overwrite, search_summary)
    if done is not None:
        return done
    if journal.exists():
        man = journal.manifest()
        x0 = _load_first(journal)
        seed_from, n_seeded = man.get("seeded_from") or None, int(man.get("seeded", 0))
    problem = build_problem(study, spec)
    attrs = {"search_method": search.method, "population": search.population,
             "offspring": search.offspring, "generations": search.generations,
             "pymoo_version": want["pymoo"], "seeded_from": str(seed_from) if seed_from else "",
             "n_seeded": n_seeded}

    def run_generations(client):
        return _generations(study, out, journal, problem, x0, client, n_jobs, progress,
                            on_generation, stop_after, attrs)
    # the first generation goes into the journal before the manifest that makes one
    return journalled(out, journal, want, "generation", scheduler, client, run_generations,
                      first=lambda journal: _save_first(journal, x0))


def _compile_the_search_steps(search, x0, problem, scale):
    """The optimizer's compiled steps (its survival, mating and duplicate check)
    and the front's sorting, compiled now, inside the compile notice, by two
    generations of a throwaway optimizer told made-up objectives: else they
    compile in the first generations, seconds with the bar at 0 %.  The run's
    own optimizer, its random draws and its front are untouched."""
    box = SweepBlackBox(problem)
    algorithm = make_algorithm(search, x0, TriangleRepair(problem.spec), box)
    tracker = FrontTracker(scale)
    made_up = np.random.default_rng(0)
    for _ in range(2):
        X = algorithm.ask()
        if len(X) == 0:
            break
        F = made_up.random((len(X), box.n_obj))
        G = made_up.random((len(X), box.n_ieq_constr)) - 0.5    # some feasible, some not
        algorithm.tell(X, F, G)
        tracker.add(F, (G <= 0).all(axis=1))


def _generations(study, out, journal, problem, x0, client, n_jobs, progress, on_generation,
                 stop_after, attrs):
    search = study.search
    planned = search.sizes()
    box = SweepBlackBox(problem)
    work = journal.working_file(out)      # out, or its replacement in the journal folder
    sfile = SearchFile(work, study, problem, search, planned, attrs)
    with compile_notice() as prep:
        scale = hv_scale(problem)
        sfile.create(scale)
        _compile_the_search_steps(search, x0, problem, scale)

    done = set(journal.done())
    if done:
        log.info("resuming: %d of %d generations already done", len(done), len(planned))
    repair = TriangleRepair(problem.spec)
    algorithm = make_algorithm(search, x0, repair, box)
    tracker = FrontTracker(scale)
    sizes, history = [], []
    computed = evaluated = 0
    bar = _progress(search, progress)
    watch = Watch(bar.update) if client is None else None     # told as a generation goes
    evaluate = _Dask(problem, client) if client is not None else _Local(problem, n_jobs, watch)
    t0 = time.perf_counter()
    # generations finished within a quarter of a second are journalled in one block
    # (one atomic write), written into the file together about once a second
    # (a generation: gen, x, status, metrics, judged, history row, proposals repaired)
    record = SaveThenWrite(lambda gens: journal.save_block([(*g[:4], g[6]) for g in gens]),
                           save_every_s=JOURNAL_EVERY_S, write_every_s=1.0)
    with stopping_safely(out, journal, bar, len(planned), "generation", record), \
            hdf5_writing(work, expendable=False) as f:
        d = sfile.datasets(f)
        record.open(f, lambda gens: sfile.write_many(d, [g[:6] for g in gens]))
        for gen in range(len(planned)):
            repair.count = 0
            told = False
            X = algorithm.ask()
            if len(X) == 0:
                log.info("generation %d: the algorithm proposes nothing new; the search "
                         "ends here", gen)
                break
            if gen in done:     # answered from the journal: nothing is evaluated again
                record.save()       # a block holds consecutive generations
                status, metrics = _journalled(journal, gen, X)
            else:
                status, metrics = evaluate(parameter_rows(problem.plan, problem.spec, X))
                repaired = np.array([repair.count], np.int64)
                told = watch is not None        # the bar was told of these as they went
                computed += len(X)
                evaluated += 1
            F, G = box.view(status, metrics)
            algorithm.tell(X, F, G)
            hv = tracker.add(F, (G <= 0).all(axis=1))
            sizes.append(len(X))
            row = {"generation": gen, "evaluations": sum(sizes), "hypervolume": hv,
                   "front_size": len(tracker.front), "feasible": tracker.feasible,
                   "repaired": repair.count}
            history.append(row)
            if len(X) != planned[gen]:
                record.stop_writing()   # the file is written again, to its true size, below
            judged = feasibility(problem.spec, status, metrics, problem.has_margin)
            record.add((gen, X, status, metrics, judged, row, None if gen in done else repaired),
                       saved=gen in done)
            if not told:
                bar.update(len(X))
            bar.set_postfix_str(f"generation {gen}/{len(planned) - 1}, "
                                f"hypervolume {hv:.4f}", refresh=False)
            if on_generation is not None:
                on_generation(row)
            if stop_after is not None and evaluated >= stop_after:
                raise KeyboardInterrupt  # test hook: an interruption between generations
        record.write()
    wall = time.perf_counter() - t0
    if sizes != planned:
        # a generation came out smaller (pymoo found too few new designs) or the
        # search ended early: the file is written again, to its true size, from the journal
        _rewrite(study, work, journal, problem, search, sizes, attrs, scale, history)
    return finish_run(out, journal, client, wall, prep[0], computed, search_summary,
                      "evaluations")


def _journalled(journal: Journal, gen, X):
    """(status, metrics) of generation ``gen`` from the journal, which must hold
    the designs ``X`` the algorithm asks for now."""
    x, status, metrics, _ = journal.load(gen)
    if x.shape != X.shape or not np.array_equal(x, X):
        raise ResultsError(journal.dir, f"generation {gen}: the algorithm asks for other "
                           "designs than the journal holds (another pymoo or NumPy?); run the "
                           "search again into a new file")
    return status, metrics


def _rewrite(study, work, journal, problem, search, sizes, attrs, scale, history):
    """The search's file written again from the journal, its generations of ``sizes``."""
    sfile = SearchFile(work, study, problem, search, sizes, attrs)
    sfile.create(scale)
    with hdf5_writing(work, expendable=False) as f:
        d = sfile.datasets(f)
        for gen, row in enumerate(history):
            x, status, metrics = journal.load(gen)[:3]
            judged = feasibility(problem.spec, status, metrics, problem.has_margin)
            sfile.write(d, gen, x, status, metrics, judged, row)


def _progress(search: SearchSpec, enabled):
    """A bar on a terminal, plain lines elsewhere (base.progress)."""
    from ..base.progress import bar
    return bar(search.evaluations, unit="eval", desc=f"search {search.method}",
               enabled=enabled, unit_scale=True, smoothing=0.1)
