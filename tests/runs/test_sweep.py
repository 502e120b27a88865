"""Sweeps: metrics against the scene path, resume, engines, refusals."""

import dataclasses
import math
import os

import h5py
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from support import naive
from pipeline.solve.reactions import scene_forces
from pipeline.kernels import config as kc
from pipeline.kernels.metrics import dwell_error
from pipeline.solve.scene import revolution_angles, solve_curves
from pipeline.base.errors import ResultsError
from pipeline.study.reader import load_study
from pipeline.base.errors import StudyError
from pipeline.runs.lifecycle import SweepInterrupted
from pipeline.runs.sweep import build_problem, run_sweep
from pipeline.study.sweep_spec import apply_design, parameter_rows
from pipeline.study.sampling import draw_candidates
from support.sweep_helpers import (SYNTHESIS_CHUNK, SYNTHESIS_N, assert_same_results, copy_of,
                                   kill_9_after_chunks)
from support.tolerances import DWELL_VS_NAIVE_REL, SWEEP_VS_SCENE_REL
from pipeline.results.storage import variables

N, CHUNK = SYNTHESIS_N, SYNTHESIS_CHUNK      # the session's sweep's


@pytest.fixture(scope="module")
def synthesis(studies):
    return load_study(studies / "ov7_synthesis.toml")


@pytest.fixture(scope="module")
def baseline(synthesis_sweep, tmp_path_factory):
    """This module's copy of the session's sweep of the main job's study."""
    return copy_of(synthesis_sweep, tmp_path_factory.mktemp("sweep"), "base.h5")


# ---------------------------------------------------------------- dwell kernel
@settings(max_examples=150, deadline=None)
@given(st.lists(st.floats(-3, 3, allow_nan=False), min_size=8, max_size=60),
       st.floats(0.05, 0.95))
def test_dwell_kernel_equals_brute_force(values, frac):
    theta = np.array(values)
    n = len(theta)
    w = max(1, min(n - 1, int(round(frac * n))))
    q = np.empty(n + w + 1, np.int64)
    err, start, full = dwell_error(theta, w, q, q.copy())
    if not np.ptp(theta) > 0:
        assert math.isnan(err)
        return
    delta = w * 360.0 / n
    ref, ref_start = naive.naive_dwell_error(theta, delta)
    assert err == ref and start == ref_start


@pytest.mark.parametrize("delta,expected", [(120.0, 0.0193), (150.0, 0.0712)])
def test_dwell_error_of_mechanism_b(synthesis, delta, expected):
    """DOMAIN.md section 9, 720 positions: 0.0193 (120 deg), 0.0712 (150 deg)."""
    spec = dataclasses.replace(synthesis.sweep, positions=720)
    study = dataclasses.replace(synthesis, output=dataclasses.replace(synthesis.output,
                                                                      dwell_deg=delta))
    pb = build_problem(study, spec)
    st_, met = pb.evaluate_rows(pb.plan.par[None, :].copy(), parallel=False)
    assert st_[0] == kc.OK
    assert round(met[0, 1], 4) == expected


# ---------------------------------------------------------------- against the scene path
def scene_metrics(study, x, positions):
    """Stroke, dwell error, margin, peak reaction of one candidate through the
    scene path (declared mechanism -> compiled plan -> curves -> forces)."""
    spec = study.sweep
    mech = apply_design(study.mechanism, spec, x)
    plan = mech.compile()
    crank = mech.crank
    phis = revolution_angles(crank, positions)
    c = solve_curves(plan, phis, kc.ACCELERATIONS, close_at=crank.phi0 + crank.rot * 2 * math.pi)
    a, b = (plan.point(p) for p in study.output.rocker)
    v = c.pos[:, b] - c.pos[:, a]
    theta = np.unwrap(np.arctan2(v[:, 1], v[:, 0]))
    err, start = naive.naive_dwell_error(theta, study.output.dwell_deg)
    fr = scene_forces(mech, plan, c)
    g = plan.group_names.index("triad")
    return {"status": c.overall, "stroke": spec.stroke_radius * np.ptp(theta),
            "dwell_error": err, "singularity_margin": c.margin[:, g].min(),
            "peak_reaction": fr.magnitude.max(), "peak_M_bal": np.abs(fr.M_bal).max()}


def test_sweep_metrics_match_scene_path(baseline, synthesis):
    with h5py.File(baseline, "r") as f:
        x = f["candidates/params"][()]
        status = f["candidates/status"][()]
        forces = f["candidates/forces_evaluated"][()]
        m = {k: f[f"metrics/{k}"][()] for k in variables(f["metrics"])}
    rng = np.random.default_rng(0)
    picked = list(rng.choice(np.flatnonzero(forces), 5, replace=False))
    picked += list(rng.choice(np.flatnonzero((status == kc.OK) & ~forces), 3, replace=False))
    for i in picked:
        ref = scene_metrics(synthesis, x[i], synthesis.sweep.positions)
        assert ref["status"] == kc.OK
        for key in ("stroke", "dwell_error", "singularity_margin"):
            assert m[key][i] == pytest.approx(ref[key], rel=SWEEP_VS_SCENE_REL, abs=1e-12), (i, key)
        if forces[i]:
            for key in ("peak_reaction", "peak_M_bal"):
                assert m[key][i] == pytest.approx(ref[key], rel=SWEEP_VS_SCENE_REL), (i, key)
        else:
            assert np.isnan(m["peak_reaction"][i])
    # failed candidates fail the scene path too, with the same status
    for i in np.flatnonzero(status != kc.OK)[:4]:
        assert scene_metrics(synthesis, x[i], synthesis.sweep.positions)["status"] == status[i]


def test_a_walk_stopped_at_its_failure_gives_the_sweep_the_same_numbers(synthesis):
    """The sweep's tolerances stop a careful walk at its first failure (T_GO_ON 0;
    a scene's walk solves on past it, to show what can be shown): a failed
    candidate's status, angle and group, and every other number, are the same
    to the bit as with the walk going on (whose work they never read)."""
    problem = build_problem(synthesis, dataclasses.replace(synthesis.sweep, candidates=4000,
                                                           chunk_size=4000))
    assert problem.tols[kc.T_GO_ON] == 0.0
    going_on = problem.tols.copy()
    going_on[kc.T_GO_ON] = 1.0
    _, _, pars = problem.draw_chunk(0)
    status, metrics = problem.evaluate_rows(pars, n_jobs=1)
    status_on, metrics_on = dataclasses.replace(problem, tols=going_on).evaluate_rows(pars,
                                                                                      n_jobs=1)
    assert (status == kc.SINGULAR).sum() >= 100     # (failures that walk past their fold)
    assert np.array_equal(status, status_on)
    assert np.array_equal(metrics, metrics_on, equal_nan=True)


def test_apply_design_matches_parameter_rows(synthesis):
    spec = synthesis.sweep
    plan = synthesis.mechanism.compile()
    x = draw_candidates(spec, 1)[:20]
    rows = parameter_rows(plan, spec, x)
    # Two different routes build the row: array arithmetic over the compiled plan
    # (parameter_rows) and the declared dataclasses changed and recompiled
    # (apply_design).  Both scale the mass data through sweep_spec.scaled_mass_data
    # and agree bit for bit today, but nothing promises that NumPy's array and
    # scalar arithmetic keep rounding alike, so allow a few ulp (4e-16 relative),
    # far below anything a metric could notice.
    for i in range(len(x)):
        np.testing.assert_allclose(apply_design(synthesis.mechanism, spec, x[i]).compile().par,
                                   rows[i], rtol=4e-16, atol=0)


def test_file_contents(baseline, synthesis):
    with h5py.File(baseline, "r") as f:
        assert f.attrs["kind"] == "sweep" and f.attrs["complete"]
        assert f.attrs["seed"] == synthesis.sweep.seed and f.attrs["sampler"] == "sobol"
        p = f["candidates/params"]
        assert p.shape == (N, 9) and list(p.attrs["names"]) == [
            "L12", "P6x", "P6y", "L23", "L34", "L45", "L35", "L46", "L57"]
        assert p.chunks[0] <= CHUNK and p.compression == "gzip" and p.shuffle
        st_ = f["candidates/status"][()]
        assert st_.dtype == np.int8 and "NO_ASSEMBLY" in f["candidates/status"].attrs["codes"]
        assert set(np.unique(st_)) <= {kc.OK, kc.NEWTON_MAXITER, kc.BRANCH_JUMP, kc.BAD_GEOMETRY,
                                       kc.SINGULAR, kc.NO_ASSEMBLY}
        # impossible ternary triangles are redrawn before solving, and counted
        assert not (st_ == kc.BAD_GEOMETRY).any() and (st_ == kc.OK).any()
        assert f["progress/rejected"][()].sum() > 0.2 * N
        for name in ("dwell_error", "peak_reaction", "stroke", "singularity_margin"):
            d = f[f"metrics/{name}"]
            assert d.attrs["units"] and d.attrs["long_name"]
        failed = st_ != kc.OK
        assert np.isnan(f["metrics/dwell_error"][()][failed]).all()
        fail_phi = f["candidates/fail_phi"][()]
        assert np.isfinite(fail_phi[failed & (st_ != kc.BAD_GEOMETRY)]).all()
        feas = f["candidates/feasible"][()]
        assert feas.any() and (f["candidates/cv"][()][feas] == 0).all()
        lo, hi = synthesis.sweep.stroke_bounds
        s = f["metrics/stroke"][()][feas]
        assert ((s >= lo) & (s <= hi)).all()
        assert f["reference/status"][0] == kc.OK
        # mechanism B at the study's 360 positions, by naive.py's fsolve revolution
        assert synthesis.sweep.positions == 360
        dwell, _, stroke = naive.naive_mech_b_motion(360)
        assert f["reference/dwell_error"][0] == pytest.approx(dwell, rel=DWELL_VS_NAIVE_REL)
        assert f["reference/stroke"][0] == pytest.approx(stroke, rel=DWELL_VS_NAIVE_REL)
        assert not os.path.exists(str(baseline) + ".parts")


# ---------------------------------------------------------------- never lose work
def test_interrupted_then_resumed_equals_uninterrupted(baseline, synthesis, tmp_path):
    out = tmp_path / "r.h5"
    with pytest.raises(SweepInterrupted, match="--resume"):
        run_sweep(synthesis, out, candidates=N, chunk_size=CHUNK, progress=False,
                  stop_after_chunks=2)
    with h5py.File(out, "r") as f:
        assert f["progress/chunk_done"][()].sum() == 2 and not f.attrs["complete"]
    with pytest.raises(ResultsError, match="unfinished run; continue it with --resume"):
        run_sweep(synthesis, out, candidates=N, chunk_size=CHUNK, progress=False)
    # --resume alone: the candidate count and chunk size come from the journal
    run_sweep(synthesis, out, progress=False, resume=True)
    assert_same_results(baseline, out)
    # a finished file: --resume says so, without repeating --candidates either
    assert run_sweep(synthesis, out, progress=False, resume=True).results == out
    with pytest.raises(ResultsError, match="--overwrite replaces it"):
        run_sweep(synthesis, out, candidates=N, chunk_size=CHUNK, progress=False)
    run_sweep(synthesis, out, candidates=N // 2, chunk_size=CHUNK, progress=False,
              overwrite=True)
    with h5py.File(out, "r") as f:
        assert f["candidates/status"].shape == (N // 2,) and f.attrs["complete"]


def test_kill_9_then_resume_equals_uninterrupted(baseline, synthesis, tmp_path):
    """A real kill -9 of a running sweep (held after its 5th journal entry, so the
    kill always lands mid-run), then --resume."""
    out = tmp_path / "k.h5"
    n, chunk = 6000, 100
    left = kill_9_after_chunks(["run", synthesis.path, "-o", out, "--candidates", n,
                                "--chunk-size", chunk, "-q"], tmp_path / "k.h5.parts", 5)
    assert left == 5
    run_sweep(synthesis, out, candidates=n, chunk_size=chunk, progress=False, resume=True)
    ref = tmp_path / "ref.h5"
    run_sweep(synthesis, ref, candidates=n, chunk_size=chunk, progress=False)
    assert_same_results(ref, out)


def test_cli_interrupt_says_how_to_resume(synthesis, tmp_path, capsys, monkeypatch):
    import pipeline.runs.sweep as sw
    from pipeline.cli import main
    real = sw.run_sweep
    monkeypatch.setattr(sw, "run_sweep", lambda *a, **k: real(*a, **k, stop_after_chunks=1))
    out = tmp_path / "i.h5"
    code = main(["run", str(synthesis.path), "-o", str(out), "--candidates", "600",
                 "--chunk-size", "300", "-q"])
    assert code == 130
    err = capsys.readouterr().err
    assert "1 of 2 chunks saved" in err and "--resume" in err


def test_damaged_file_is_rebuilt_from_the_journal(synthesis, tmp_path, baseline):
    out = tmp_path / "d.h5"
    with pytest.raises(SweepInterrupted):
        run_sweep(synthesis, out, candidates=N, chunk_size=CHUNK, progress=False,
                  stop_after_chunks=1)
    out.write_bytes(out.read_bytes()[:5000])   # as if killed in the middle of a write
    run_sweep(synthesis, out, candidates=N, chunk_size=CHUNK, progress=False, resume=True)
    assert_same_results(baseline, out)


def test_refusals(synthesis, tmp_path, baseline, studies):
    other = load_study(studies / "ov7_synthesis.toml")
    other = dataclasses.replace(other, text=other.text.replace("seed = 20261121", "seed = 1"),
                                sweep=dataclasses.replace(other.sweep, seed=1))
    with pytest.raises(ResultsError, match="another study"):
        run_sweep(other, baseline, candidates=N, chunk_size=CHUNK, progress=False, resume=True)
    with pytest.raises(ResultsError, match="another study"):
        run_sweep(synthesis, baseline, candidates=N + 1, chunk_size=CHUNK, progress=False,
                  resume=True)
    foreign = tmp_path / "foreign.h5"
    with h5py.File(foreign, "w") as f:
        f["x"] = 1
    with pytest.raises(ResultsError, match="not a pipeline results file"):
        run_sweep(synthesis, foreign, candidates=N, progress=False, resume=True)
    junk = tmp_path / "junk.h5"
    junk.write_bytes(b"\x89HDF\r\n" + b"0" * 100)
    with pytest.raises(ResultsError, match="truncated or not an HDF5 file"):
        run_sweep(synthesis, junk, candidates=N, progress=False, resume=True)
    assert junk.read_bytes() == b"\x89HDF\r\n" + b"0" * 100   # untouched
    # resuming a complete run changes nothing
    before = baseline.read_bytes()
    run_sweep(synthesis, baseline, candidates=N, chunk_size=CHUNK, progress=False, resume=True)
    assert baseline.read_bytes() == before


# ---------------------------------------------------------------- engines and threads
@pytest.mark.parametrize("jobs", [1, 3])
def test_thread_count_does_not_change_results(synthesis, tmp_path, baseline, jobs):
    """One thread, or three chunks side by side (each on a thread, the last in
    ranges): the baseline's file."""
    out = tmp_path / "t1.h5"
    run_sweep(synthesis, out, candidates=N, chunk_size=CHUNK, progress=False, n_jobs=jobs)
    assert_same_results(baseline, out)


class _Chunks:
    """A sweep problem that records how each chunk is drawn and evaluated."""
    device, robust, friction = "cpu", None, None

    def __init__(self, chunk_size=1000):
        import threading
        self.drawn, self.evaluated, self.lock = [], [], threading.Lock()
        self.spec = dataclasses.make_dataclass("Spec", ["chunk_size"])(chunk_size)

    def draw_chunk(self, c, draw=None):
        self.drawn.append(c)
        return ("drawn", c)

    def evaluate_chunk(self, c, parallel, n_jobs, watch, drawn):
        import time
        assert drawn == ("drawn", c)
        time.sleep(0.01 * (c % 3))      # chunks end out of their order
        with self.lock:
            self.evaluated.append((c, n_jobs))
        return (c,)


@pytest.mark.parametrize("jobs", [1, 2, 3])
def test_chunks_side_by_side_come_back_in_order(jobs):
    """On k > 1 threads k chunks run side by side, each whole on one thread
    (the last shared out in ranges on all k); drawn in order; yielded in order."""
    from pipeline.base.limits import MAX_CHUNK
    from pipeline.runs.sweep import _chunks
    problem = _Chunks()
    todo = [0, 1, 2, 3, 5, 8, 9]
    assert [r[0] for r in _chunks(problem, todo, None, jobs)] == todo
    assert problem.drawn == todo
    threads = dict(problem.evaluated)
    assert threads == {c: (jobs if c == 9 or jobs == 1 else 1) for c in todo}
    problem.robust = "builds"          # robust builds share their own work out
    problem.evaluated.clear()
    list(_chunks(problem, todo, None, jobs))
    assert {k for _, k in problem.evaluated} == {jobs}
    big = _Chunks(chunk_size=MAX_CHUNK)     # one chunk of the largest size at a time
    list(_chunks(big, todo, None, jobs))
    assert {k for _, k in big.evaluated} == {jobs}


@pytest.mark.parametrize("processes", [False, True], ids=["threads", "worker-processes"])
def test_dask_cluster_equals_local(synthesis, tmp_path, baseline, processes):
    """The same file from a Dask cluster as from the local run, bit for bit: with
    workers in this process, and with two worker processes (the problem is
    pickled to them; each loads the kernels from the session's compile cache,
    which they inherit through the environment)."""
    import dask.distributed as distributed
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=processes,
                                  dashboard_address=None) as cluster:
        out = tmp_path / "dask.h5"
        run_sweep(synthesis, out, candidates=N, chunk_size=CHUNK, progress=False,
                  scheduler=cluster.scheduler_address)
        if processes:       # the workers are other processes, with the session's caches
            with distributed.Client(cluster) as client:
                seen = client.run(lambda: (os.getpid(), os.environ.get("PIPELINE_CACHE_DIR")))
            assert len(seen) == 2 and os.getpid() not in {pid for pid, _ in seen.values()}
            assert {d for _, d in seen.values()} == {os.environ["PIPELINE_CACHE_DIR"]}
    assert_same_results(baseline, out)
    with h5py.File(out, "r") as f:
        assert f.attrs["engine"] == "dask"


def test_samplers_stay_in_bounds_and_chunks_are_independent(synthesis):
    for sampler in ("uniform", "lhs", "sobol"):
        spec = dataclasses.replace(synthesis.sweep, sampler=sampler, candidates=1000,
                                   chunk_size=250)
        lo = np.array([v.low for v in spec.variables])
        hi = np.array([v.high for v in spec.variables])
        chunks = [draw_candidates(spec, c) for c in (3, 0, 2, 1)]
        again = draw_candidates(spec, 2)
        np.testing.assert_array_equal(chunks[2], again)
        allx = np.concatenate(chunks)
        assert ((allx >= lo) & (allx <= hi)).all()
        assert len(np.unique(allx[:, 0])) == 1000


# ---------------------------------------------------------------- no wasted candidates
def test_redrawn_designs_follow_rejection_sampling(synthesis):
    """Draws that break the ternary triangle are redrawn: every row buildable,
    deterministic per chunk, and distributed as plain rejection sampling
    (two-sample Kolmogorov-Smirnov per variable, fixed seeds)."""
    from scipy.stats import ks_2samp

    from pipeline.study.sampling import draw_checked
    spec = dataclasses.replace(synthesis.sweep, sampler="uniform", candidates=40000,
                               chunk_size=40000)
    x, rejected = draw_checked(spec, 0)
    t = spec.triangles[0]
    assert not t.broken(x).any() and rejected[0] > 0.2 * len(x)
    x2, rejected2 = draw_checked(spec, 0)
    np.testing.assert_array_equal(x, x2)
    assert rejected2[0] == rejected[0]
    rng = np.random.default_rng(12345)
    lo = np.array([v.low for v in spec.variables])
    hi = np.array([v.high for v in spec.variables])
    ref = lo + rng.random((120000, len(lo))) * (hi - lo)
    ref = ref[~t.broken(ref)][:len(x)]
    for j in range(len(lo)):
        assert ks_2samp(x[:, j], ref[:, j]).pvalue > 1e-3, spec.variables[j].name


def test_narrow_bounds_that_cannot_build_the_triangle_are_refused(studies, tmp_path):
    text = (studies / "ov7_synthesis.toml").read_text().replace(
        'L45 = { param = "triad.L45" }', 'L45 = { param = "triad.L45", min = 300.0, max = 310.0 }')
    p = tmp_path / "narrow.toml"
    p.write_text(text)
    with pytest.raises(StudyError, match="buildable ternary link"):
        load_study(p)


def test_bad_geometry_names_the_inequality(synthesis):
    """The words behind a BAD_GEOMETRY status (browse, scene summaries): which
    inequality, with the three lengths; a non-positive length by name."""
    from pipeline.study.sweep_spec import geometry_problems
    plan = synthesis.mechanism.compile()
    assert geometry_problems(plan, plan.par) == []
    par = plan.par.copy()
    par[plan.param("triad.L35")] = 400.0
    assert geometry_problems(plan, par) == [
        "ternary link of 'triad': L35 = 400 mm >= L34 + L45 = 81 + 104.5 = 185.5 mm "
        "(no triangle)"]
    par = plan.par.copy()
    par[plan.param("crank.length")] = 0.0
    assert geometry_problems(plan, par) == ["crank.length = 0 mm is not a length (> 0)"]
