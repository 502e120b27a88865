"""Adaptive search ([search], pymoo): the sweep's evaluator, its file layout and
journal; resume, threads and Dask give the same file; seeding from a sweep's
front; the study's errors.  Small sizes: the full-size comparison with the
Monte-Carlo sweep is benchmarks/bench_search.py's."""

import re

import h5py
import numpy as np
import pytest

from pipeline.kernels import config as kc
from pipeline.kernels import sweep as ks
from pipeline.runs.search import run_search
from pipeline.runs.search_problem import (FAILED_VIOLATION, SweepBlackBox, hv_scale, pymoo_view,
                                          repair_triangles, buildable_centre)
from pipeline.base.errors import ResultsError
from pipeline.study.reader import load_study
from pipeline.base.errors import StudyError
from pipeline.runs.lifecycle import SweepInterrupted
from pipeline.runs.sweep import build_problem, run_sweep
from pipeline.study.objectives import COLUMN
from pipeline.study.sweep_spec import parameter_rows
from support.naive_pareto import hypervolume_2d_ref
from support.sweep_helpers import assert_same_results, copy_of, kill_9_after_chunks
from pipeline.results.storage import variables

POP, GENS = 24, 5          # 24 + 5 x 24 = 144 evaluations
SEARCH = f"""
[search]
method = "{{method}}"
population = {POP}
generations = {GENS}
seed = 7
"""


def search_toml(studies, method="nsga2", extra=""):
    """The synthesis study with a small [search] section (as text)."""
    text = (studies / "ov7_synthesis.toml").read_text()
    return text + SEARCH.format(method=method) + extra


@pytest.fixture(scope="module")
def small(studies, tmp_path_factory):
    p = tmp_path_factory.mktemp("study") / "small_search.toml"
    p.write_text(search_toml(studies))
    return load_study(p)


@pytest.fixture(scope="module")
def baseline(small, tmp_path_factory):
    out = tmp_path_factory.mktemp("search") / "base.h5"
    run_search(small, out, progress=False)
    return out


def _hv_ref(F, feasible, scale):
    """The hypervolume the search stores, from the definition (naive_pareto): the
    feasible rows' objectives divided by the reference design's, against the
    reference point (1.1, 1.1)."""
    assert F.shape[1] == 2
    Z = F[np.asarray(feasible, bool)] / np.asarray(scale)
    return hypervolume_2d_ref(Z, 1.1)


# ---------------------------------------------------------------- the study
def test_the_shipped_search_study_reads(studies):
    s = load_study(studies / "ov7_search.toml")
    assert s.search.method == "nsga2" and s.search.population == 100
    assert s.search.evaluations == 20000
    synthesis = load_study(studies / "ov7_synthesis.toml")
    assert synthesis.search is None
    # the same problem as the synthesis: variables, bounds, objectives, constraints
    for key in ("variables", "objectives", "stroke_bounds", "margin_min", "mass_model",
                "positions", "triangles"):
        assert getattr(s.sweep, key) == getattr(synthesis.sweep, key), key


BAD = [
    # (change of the [search] section, field, reason)
    (('method = "nsga2"', 'method = "ga"'), "search.method", "must be one of nsga2, smsemoa, "
                                                            "agemoea"),
    ((f"population = {POP}", "population = 1"), "search.population", "at least 2"),
    ((f"population = {POP}", "population = 1000000"), "search.population", "at most 10,000"),
    ((f"population = {POP}", 'population = "many"'), "search.population",
     "expected an integer"),
    ((f"generations = {GENS}", f"generations = {GENS}\nevaluations = 5000"),
     "search.evaluations", "not both"),
    ((f"generations = {GENS}", ""), "search", "give the search's length"),
    ((f"generations = {GENS}", "evaluations = 30"), "search.evaluations",
     "at least population + offspring = 48"),
    ((f"generations = {GENS}", "generations = 0"), "search.generations", "at least 1"),
    ((f"generations = {GENS}", "generations = 2000000000"), "search.generations",
     "at most 1,000,000,000"),
    (("seed = 7", "seed = -1"), "search.seed", "at least 0"),
    (("seed = 7", "seed = 7\noffspring = 0"), "search.offspring", "at least 1"),
    (("seed = 7", "seed = 7\npopulaton = 50"), "search.populaton", "unknown key"),
]


@pytest.mark.parametrize("change,field,reason", BAD, ids=[b[1] + ":" + b[2][:12] for b in BAD])
def test_bad_search_sections_are_refused_naming_file_field_reason(studies, tmp_path, change,
                                                                   field, reason):
    text = search_toml(studies)
    head, tail = text.split("[search]")
    assert change[0] in tail, change
    p = tmp_path / "bad.toml"
    p.write_text(head + "[search]" + tail.replace(change[0], change[1]))
    with pytest.raises(StudyError) as e:
        load_study(p)
    assert e.value.file == str(p) and e.value.field == field and reason in e.value.reason, \
        str(e.value)


def test_a_search_needs_a_sweep_study(studies, tmp_path):
    p = tmp_path / "scene.toml"
    p.write_text((studies / "ov7_class3.toml").read_text() + SEARCH.format(method="nsga2"))
    with pytest.raises(StudyError, match=r"scene.toml: search: a \[search\] section needs "
                                         r"study.kind = \"sweep\""):
        load_study(p)


def test_command_line_refusals(small, studies, tmp_path, capsys, baseline):
    from pipeline.cli import main
    out = str(tmp_path / "x.h5")
    assert main(["run", str(small.path), "-o", out, "--candidates", "100", "-q"]) == 2
    assert "this study's [search] sets its own length" in capsys.readouterr().err
    assert main(["run", str(studies / "ov7_synthesis.toml"), "-o", out, "--from",
                 str(baseline), "-q"]) == 2
    assert "has no [search] section" in capsys.readouterr().err
    # a front of other design variables
    other = tmp_path / "other.toml"
    other.write_text(small.path.read_text().replace('L57 = { param = "triad.L57" }\n', ""))
    assert main(["run", str(other), "-o", out, "--from", str(baseline), "-q"]) == 2
    assert "are not this study's" in capsys.readouterr().err
    assert not (tmp_path / "x.h5").exists()


# ---------------------------------------------------------------- the file
def test_every_candidate_is_stored_like_a_sweep(baseline, small):
    n = POP * (GENS + 1)
    with h5py.File(baseline, "r") as f:
        assert f.attrs["kind"] == "sweep" and f.attrs["complete"]
        assert f.attrs["search_method"] == "nsga2" and f.attrs["seed"] == 7
        assert f.attrs["n_candidates"] == n and f.attrs["n_generations"] == GENS + 1
        gen = f["candidates/generation"][()]
        np.testing.assert_array_equal(gen, np.repeat(np.arange(GENS + 1), POP))
        assert f["candidates/generation"].dims[0][0].name == "/candidate"
        assert f["progress/chunk_done"][()].all()
        h = f["search"]
        np.testing.assert_array_equal(h["evaluations"][()], POP * np.arange(1, GENS + 2))
        assert h["generation"].shape == (GENS + 1,) and h.attrs["method"] == "nsga2"
        assert np.all(np.diff(h["hypervolume"][()]) >= 0) and h["hypervolume"][-1] > 0
        st = f["candidates/status"][()]
        X = f["candidates/params"][()]
        feas = f["candidates/feasible"][()]
        F = np.stack([f[f"metrics/{o}"][()] for o in f.attrs["objectives"]], axis=1)
        scale = f["search"].attrs["hv_scale"]
    # nothing evaluated that could only be BAD_GEOMETRY; everything in the bounds
    assert not (st == kc.BAD_GEOMETRY).any() and not (st == kc.NOT_EVALUATED).any()
    lo = np.array([v.low for v in small.sweep.variables])
    hi = np.array([v.high for v in small.sweep.variables])
    assert ((X >= lo) & (X <= hi)).all()
    for t in small.sweep.triangles:
        assert not t.broken(X).any()
    # the stored history is the hypervolume of the feasible front of each prefix
    with h5py.File(baseline, "r") as f:
        hv = f["search/hypervolume"][()]
    for g in (0, 2, GENS):
        k = POP * (g + 1)
        assert hv[g] == pytest.approx(_hv_ref(F[:k], feas[:k], scale), rel=1e-12)
    assert hv[GENS] > 0
    # the normalisation: the reference design's objectives
    pb = build_problem(small, small.sweep)
    np.testing.assert_array_equal(scale, hv_scale(pb))


def test_stored_metrics_equal_a_fresh_evaluation(baseline, small):
    """Every stored candidate's status and metrics, evaluated again from its
    stored variables: bit for bit."""
    with h5py.File(baseline, "r") as f:
        X = f["candidates/params"][()]
        st = f["candidates/status"][()]
        m = {k: f[f"metrics/{k}"][()] for k in variables(f["metrics"])}
        forces = f["candidates/forces_evaluated"][()]
        feas = f["candidates/feasible"][()]
    pb = build_problem(small, small.sweep)
    st2, met = pb.evaluate_rows(parameter_rows(pb.plan, pb.spec, X), parallel=False)
    np.testing.assert_array_equal(st, st2)
    for name, (col, factor) in COLUMN.items():
        if name in m:
            np.testing.assert_array_equal(m[name], met[:, col] * factor, err_msg=name)
    np.testing.assert_array_equal(forces, met[:, ks.M_FORCES_DONE] == 1.0)
    # pymoo's feasibility (every g <= 0) is the stored one
    F, G = SweepBlackBox(pb).view(st2, met)
    np.testing.assert_array_equal((G <= 0).all(axis=1), feas)
    assert np.isfinite(F).all() and np.isfinite(G).all()


def test_pymoo_view_makes_failures_violated_constraints(small):
    pb = build_problem(small, small.sweep)
    st = np.array([kc.OK, kc.OK, kc.NEWTON_MAXITER, kc.OK], np.int8)
    met = np.full((4, ks.N_METRICS), np.nan)
    met[:, ks.M_STROKE] = [12.0, 20.0, np.nan, 12.0]
    met[:, ks.M_MARGIN] = [0.9, 0.9, np.nan, 0.9]
    met[:, ks.M_DWELL] = [0.05, 0.05, np.nan, 0.05]
    met[:, ks.M_PEAK_R] = [700.0, np.nan, np.nan, np.nan]   # forces skipped for row 1
    F, G = pymoo_view(pb.spec, st, met, True)
    cv = np.maximum(G, 0).sum(axis=1)
    assert cv[0] == 0                                      # feasible
    assert cv[1] == pytest.approx(5.0)                     # stroke 20 > 15 mm
    assert cv[2] == FAILED_VIOLATION                       # failed: worse than any violation
    assert cv[3] == FAILED_VIOLATION                       # meets g but an objective is NaN
    assert np.isfinite(F).all() and F[0, 1] == 700.0


def test_triangle_repair_moves_only_broken_designs_inside(small):
    spec = small.sweep
    t = spec.triangles[0]
    lo = np.array([v.low for v in spec.variables])
    hi = np.array([v.high for v in spec.variables])
    centre = buildable_centre(spec)
    assert not t.broken(centre[None, :]).any() and ((centre > lo) & (centre < hi)).all()
    X = lo + np.random.default_rng(3).random((2000, len(lo))) * (hi - lo)
    bad = t.broken(X)
    assert bad.sum() > 300
    Y, n = repair_triangles(spec.triangles, centre, X, lo, hi)
    assert n == bad.sum() and not t.broken(Y).any()
    assert ((Y >= lo) & (Y <= hi)).all()
    np.testing.assert_array_equal(Y[~bad], X[~bad])
    # a repaired design lies just inside the boundary, on the line to the centre
    d = (Y[bad] - X[bad]) / (centre - X[bad])
    np.testing.assert_allclose(d, d[:, :1] * np.ones_like(d), rtol=1e-9, atol=1e-12)
    assert (d[:, 0] < 1).all()


# ---------------------------------------------------------------- never lose work
def test_interrupted_then_resumed_equals_uninterrupted(baseline, small, tmp_path):
    out = tmp_path / "r.h5"
    with pytest.raises(SweepInterrupted, match="2 of 6 generations saved.*--resume"):
        run_search(small, out, progress=False, stop_after_generations=2)
    with pytest.raises(ResultsError, match="unfinished run; continue it with --resume"):
        run_search(small, out, progress=False)
    with pytest.raises(SweepInterrupted, match="4 of 6 generations"):
        run_search(small, out, progress=False, resume=True, stop_after_generations=2)
    out.write_bytes(out.read_bytes()[:4000])     # as if killed in the middle of a write
    rows = []
    run_search(small, out, progress=False, resume=True, on_generation=rows.append)
    assert [r["generation"] for r in rows] == list(range(GENS + 1))
    assert_same_results(baseline, out)
    assert not out.with_name(out.name + ".parts").exists()
    # a finished file: --resume says so; a run without --overwrite is refused
    before = out.read_bytes()
    run_search(small, out, progress=False, resume=True)
    assert out.read_bytes() == before
    with pytest.raises(ResultsError, match="--overwrite replaces it"):
        run_search(small, out, progress=False)


def test_kill_9_then_resume_equals_uninterrupted(studies, tmp_path):
    """A real kill -9 of a running search (held after its 2nd journalled
    block of generations, about half a second in: mid-run), then --resume."""
    p = tmp_path / "long.toml"
    p.write_text(search_toml(studies).replace(f"generations = {GENS}", "generations = 600"))
    out = tmp_path / "k.h5"
    left = kill_9_after_chunks(["run", p, "-o", out, "-q"], tmp_path / "k.h5.parts", 2)
    assert left == 2
    from pipeline.results.journal import Journal
    assert 0 < len(Journal(out).done()) < 601        # killed mid-run: work left to resume
    s = load_study(p)
    run_search(s, out, progress=False, resume=True)
    ref = tmp_path / "ref.h5"
    run_search(s, ref, progress=False)
    assert_same_results(ref, out)


def test_a_journal_that_does_not_replay_is_refused(small, tmp_path):
    """Resuming checks that the algorithm asks for the journalled designs."""
    out = tmp_path / "j.h5"
    with pytest.raises(SweepInterrupted):
        run_search(small, out, progress=False, stop_after_generations=2)
    parts = out.with_name(out.name + ".parts")
    import io
    from pipeline.results.journal import Journal
    # the block that holds generation 1 (with 0, or alone where 0 took over 0.25 s)
    p = next(b for (first, last), b in Journal(out)._blocks().items() if first <= 1 <= last)
    with np.load(p) as z:
        d = dict(z)
    d["x_1"][0, 0] += 1e-9
    buf = io.BytesIO()
    np.savez(buf, **d)
    p.write_bytes(buf.getvalue())
    with pytest.raises(ResultsError, match="generation 1: the algorithm asks for other designs"):
        run_search(small, out, progress=False, resume=True)


def test_another_run_s_journal_is_refused(small, tmp_path, studies):
    out = tmp_path / "o.h5"
    with pytest.raises(SweepInterrupted):
        run_search(small, out, progress=False, stop_after_generations=1)
    p = tmp_path / "other.toml"
    p.write_text(small.path.read_text().replace("seed = 7", "seed = 8"))
    with pytest.raises(ResultsError, match="belongs to another run"):
        run_search(load_study(p), out, progress=False, resume=True)
    # a Monte-Carlo sweep's journal is not a search's
    sw = tmp_path / "sw.h5"
    with pytest.raises(SweepInterrupted):
        run_sweep(load_study(studies / "ov7_synthesis.toml"), sw, candidates=600,
                  chunk_size=300, progress=False, stop_after_chunks=1)
    with pytest.raises(ResultsError, match="interrupted Monte-Carlo sweep"):
        run_search(small, sw, progress=False, resume=True)


# ---------------------------------------------------------------- engines and threads
def test_one_thread_gives_the_same_file(baseline, small, tmp_path):
    out = tmp_path / "t1.h5"
    run_search(small, out, progress=False, n_jobs=1)
    assert_same_results(baseline, out)


def test_dask_cluster_equals_local(baseline, small, tmp_path):
    import dask.distributed as distributed
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        out = tmp_path / "dask.h5"
        run_search(small, out, progress=False, scheduler=cluster.scheduler_address)
    assert_same_results(baseline, out)
    with h5py.File(out, "r") as f:
        assert f.attrs["engine"] == "dask"


@pytest.mark.parametrize("method", ["smsemoa", "agemoea"])
def test_other_methods_run_and_are_deterministic(studies, tmp_path, method):
    p = tmp_path / f"{method}.toml"
    p.write_text(search_toml(studies, method).replace(f"generations = {GENS}",
                                                      "generations = 3"))
    s = load_study(p)
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    run_search(s, a, progress=False)
    run_search(s, b, progress=False, n_jobs=1)
    assert_same_results(a, b)
    with h5py.File(a, "r") as f:
        assert f.attrs["search_method"] == method and f["candidates/feasible"][()].any()


def test_large_generations(studies, tmp_path):
    """Thousands of designs per generation: one batch each through the kernels."""
    p = tmp_path / "large.toml"
    p.write_text(search_toml(studies).replace(f"population = {POP}", "population = 3000")
                 .replace(f"generations = {GENS}", "generations = 1"))
    out = tmp_path / "large.h5"
    run_search(load_study(p), out, progress=False)
    with h5py.File(out, "r") as f:
        assert f["candidates/status"].shape == (6000,)
        # the initial population, then one generation of 3000
        np.testing.assert_array_equal(f["candidates/generation"][()], np.repeat([0, 1], 3000))


def test_a_short_generation_gives_a_file_of_the_true_size(small, tmp_path, monkeypatch):
    """If pymoo proposes fewer designs than asked (too few new ones), the file
    holds exactly the evaluated candidates; resuming gives the same file."""
    import pipeline.runs.search as se
    real = se.make_algorithm

    def short(*a, **k):
        alg = real(*a, **k)
        ask, calls = alg.ask, []

        def fewer():
            pop = ask()
            calls.append(1)
            return pop[:-3] if len(calls) == 3 else pop
        alg.ask = fewer
        return alg
    monkeypatch.setattr(se, "make_algorithm", short)
    out, ref = tmp_path / "s.h5", tmp_path / "ref.h5"
    run_search(small, ref, progress=False)
    with pytest.raises(SweepInterrupted):
        run_search(small, out, progress=False, stop_after_generations=4)
    run_search(small, out, progress=False, resume=True)
    assert_same_results(ref, out)
    with h5py.File(out, "r") as f:
        n = POP * (GENS + 1) - 3
        assert f["candidates/status"].shape == (n,) and f.attrs["n_candidates"] == n
        assert np.bincount(f["candidates/generation"][()])[2] == POP - 3
        assert f["search/evaluations"][-1] == n and f["progress/chunk_done"][()].all()


# ---------------------------------------------------------------- explore, then refine
def test_seeded_from_a_sweep_front(small, studies, tmp_path, capsys, synthesis_sweep):
    from pipeline.analysis.fronts import read_sweep
    from pipeline.cli import main
    from pipeline.kernels.pareto import nondominated_rank
    sweep = copy_of(synthesis_sweep, tmp_path, "sweep.h5")
    out = tmp_path / "refined.h5"
    assert main(["run", str(small.path), "-o", str(out), "--from", str(sweep), "-q"]) == 0
    data = read_sweep(sweep)
    rank = nondominated_rank(data.F, data.feasible)
    front = data.params[rank == 1]
    with h5py.File(out, "r") as f:
        n_seeded = int(f.attrs["n_seeded"])
        assert f.attrs["seeded_from"] == str(sweep)
        X0 = f["candidates/params"][:POP]
    assert n_seeded == POP
    # front 1 first, then the next fronts
    k = min(len(front), POP)
    assert {tuple(r) for r in X0[:k]} <= {tuple(r) for r in front}
    assert (rank[[int(np.flatnonzero((data.params == r).all(axis=1))[0]) for r in X0]] >= 1).all()
    # the refined front is at least as good as the sweep's
    with h5py.File(out, "r") as f:
        hv_search = f["search/hypervolume"][-1]
        scale = f["search"].attrs["hv_scale"]
    assert hv_search >= _hv_ref(data.F, data.feasible, scale)
    # the front the search stores is that of a brute-force dominance test
    with h5py.File(out, "r") as f:
        Fs = np.stack([f[f"metrics/{o}"][()] for o in f.attrs["objectives"]], axis=1)
        feas = f["candidates/feasible"][()]
    assert hv_search == pytest.approx(_hv_ref(Fs, feas, scale), rel=1e-12)
    # the result reads like a sweep: analyze, browse, show, report, export
    for cmd in (["analyze", str(out)], ["browse", str(out), "--top", "3"],
                ["show", str(out), "--candidate", "knee", "-o", str(tmp_path / "k.png")],
                ["report", str(out), "-o", str(tmp_path / "r.html")],
                ["export", str(out), "--csv", str(tmp_path / "csv"), "--front", "1"]):
        assert main(cmd + ["-q"]) == 0, cmd
    capsys.readouterr()
    page = (tmp_path / "r.html").read_text()
    assert "Adaptive search" in page and re.search(r"hypervolume against evaluations", page)
    import pipeline
    df = pipeline.open(out)
    assert (df["generation"].to_numpy() == np.repeat(np.arange(GENS + 1), POP)).all()
