"""The robust metrics' builds in slices (issue 58, case 8): the work of one
kernel call stays bounded whatever [tolerance.robust] builds asks, progress
is told after every slice, an interruption stops the work at the next slice,
and the numbers are those of one call over every build, bit for bit."""

from __future__ import annotations

import os
import signal
import threading
from dataclasses import replace

import numpy as np
import pytest

from pipeline.runs import builds as bm
from pipeline.runs.builds import BuildEvaluator, Stopped, Watch, build_slices
from pipeline.study.reader import parse_study

from conftest import STUDIES

ROBUST = STUDIES / "ov7_robust_search.toml"


def robust_study(builds=64):
    text = ROBUST.read_text().replace("builds = 64", f"builds = {builds}")
    return replace(parse_study(text, ROBUST), search=None)


@pytest.fixture(scope="module")
def problem():
    from pipeline.runs.sweep import build_problem
    study = robust_study()
    return build_problem(study, study.sweep)


def designs(problem, n=40):
    """The reference design, an infeasible one and drawn designs, some feasible."""
    from pipeline.study.sampling import draw_checked
    from pipeline.study.sweep_spec import parameter_rows
    ref = problem.plan.par
    short = ref.copy()
    short[problem.plan.param("crank.length")] *= 0.5        # half the stroke: infeasible
    x, _ = draw_checked(replace(problem.spec, candidates=n, chunk_size=n), 0)
    return np.ascontiguousarray(np.vstack([ref, short, ref,
                                           parameter_rows(problem.plan, problem.spec, x)]))


@pytest.fixture
def calls(monkeypatch):
    """The rows of every kernel call of the builds, in order."""
    seen = []
    real = BuildEvaluator.raw

    def raw(self, pars, n_jobs=None):
        seen.append(len(pars))
        return real(self, pars, n_jobs)

    monkeypatch.setattr(BuildEvaluator, "raw", raw)
    return seen


@pytest.mark.parametrize("n, b, limit", [(5, 64, 24), (5, 64, 64), (7, 64, 200), (3, 10, 1),
                                         (0, 64, 24), (1, 4096, 4096), (9, 3, 10)])
def test_slices_are_bounded_and_cover_every_build_once(n, b, limit):
    cuts = build_slices(n, b, limit)
    assert all(0 < hi - lo <= limit for lo, hi in cuts)
    assert [lo for lo, _ in cuts] == ([0] if n else []) + [hi for _, hi in cuts[:-1]]
    assert (cuts[-1][1] if cuts else 0) == n * b
    if b <= limit:          # whole designs together where they fit
        assert all(lo % b == 0 for lo, _ in cuts)


def test_a_sweep_of_4096_builds_per_design_is_cut_into_bounded_kernel_calls():
    """The audit's case: 10,000 designs x 4,096 builds was one call."""
    cuts = build_slices(10_000, 4096)
    assert max(hi - lo for lo, hi in cuts) <= bm.SLICE_BUILDS
    with pytest.raises(ValueError, match="at least one build"):
        build_slices(3, 4, 0)


@pytest.mark.parametrize("limit", [7, 64, 100, 10 ** 9])
def test_sliced_builds_give_the_numbers_of_one_call(problem, monkeypatch, calls, limit):
    """Cut inside a design (7), at its end (64), across designs (100): the
    robust columns equal those of one call over every build (10**9, as before
    the slices), bit for bit; no call exceeds its limit."""
    pars = designs(problem)
    monkeypatch.setattr(bm, "SLICE_BUILDS", 10 ** 9)
    want_status, want = problem.evaluate_rows(pars)
    assert len(calls) == 1
    calls.clear()
    monkeypatch.setattr(bm, "SLICE_BUILDS", limit)
    status, rows = problem.evaluate_rows(pars)
    np.testing.assert_array_equal(status, want_status)
    np.testing.assert_array_equal(rows, want)
    assert max(calls) <= limit
    from pipeline.model.metric_catalogue import metric_values
    built = int((~np.isnan(metric_values(rows, "robust_dwell_error"))).sum())
    assert built >= 3        # the reference twice and some drawn designs
    assert calls == [hi - lo for lo, hi in build_slices(built, 64, limit)]


def test_progress_is_told_after_every_slice(problem, monkeypatch, calls):
    pars = designs(problem)
    monkeypatch.setattr(bm, "SLICE_BUILDS", 16)
    told = []
    watch = Watch(lambda n: told.append((n, len(calls))))
    problem.evaluate_rows(pars, watch=watch)
    assert sum(n for n, _ in told) == len(pars)         # every design, once
    assert len(calls) >= 12
    # told after the slices, never more than two slices apart (a slice's share
    # of the designs may round down to none)
    after = [k for _, k in told]
    assert after[0] <= 2 and max(np.diff(after + [len(calls)])) <= 2


def test_a_stopped_watch_stops_the_builds_at_the_next_slice(problem, monkeypatch, calls):
    pars = designs(problem)
    monkeypatch.setattr(bm, "SLICE_BUILDS", 16)
    watch = Watch(lambda n: watch.stop())       # asked to stop after the first slice
    with pytest.raises(Stopped):
        problem.evaluate_rows(pars, watch=watch)
    assert calls == [16]


def test_a_keyboard_interrupt_between_slices_stops_the_sweep_at_the_next_slice(
        tmp_path, monkeypatch, calls):
    """Ctrl-C while the chunk's worker thread is at its builds: the chunk stops
    at its next slice (the hook holds the worker until the interruption has
    reached the main thread: no race, no timing), the chunk queued behind it
    never starts, and the sweep ends as an interruption (its journal kept)."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals reach the main thread only")
    from pipeline.runs import sweep as sm
    from pipeline.runs.lifecycle import SweepInterrupted
    monkeypatch.setattr(bm, "SLICE_BUILDS", 16)
    study = robust_study()
    slices_at_interrupt = []

    class Interrupting(Watch):
        def tell(self, n):
            super().tell(n)
            if not slices_at_interrupt and started and len(calls) > started[0][1]:
                slices_at_interrupt.append(len(calls))
                os.kill(os.getpid(), signal.SIGINT)       # Ctrl-C
                self._stop.wait(60)     # the main thread has it: the chunks are told to stop

    started = []
    real_chunk = sm.SweepProblem.evaluate_chunk

    def evaluate_chunk(self, chunk, *args):
        started.append((chunk, len(calls)))
        return real_chunk(self, chunk, *args)

    monkeypatch.setattr(sm, "Watch", Interrupting)
    monkeypatch.setattr(sm.SweepProblem, "evaluate_chunk", evaluate_chunk)
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(SweepInterrupted,
                           match="interrupted before the first chunk finished"):
            sm.run_sweep(study, tmp_path / "r.h5", candidates=120, chunk_size=40,
                         progress=False)
    finally:
        signal.signal(signal.SIGINT, old)
    assert slices_at_interrupt, "the first chunk has no feasible design: draw others"
    assert len(calls) == slices_at_interrupt[0]     # no slice after the interruption
    assert [c for c, _ in started] == [0]          # the queued chunk never started
