"""The run's life shared by sweeps and searches (runs/lifecycle.py): every
finished unit is journalled before it is written into the results file,
whatever the cadence of each; an interruption keeps every finished unit and
says how many are saved; a file to be written again whole is written no more.
And the results writer writes the constraints and feasibility it is handed
(the runs layer judges the rows, study.objectives.feasibility)."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from pipeline.runs.lifecycle import SaveThenWrite, SweepInterrupted, stopping_safely


class _File:
    def __init__(self, events):
        self.events = events

    def flush(self):
        self.events.append(("flush",))


class _Journal:
    def __init__(self, events):
        self.events = events

    def done(self):
        return sorted({u for e in self.events if e[0] == "save" for u in e[1]})


class _Bar:
    closed = False

    def close(self):
        self.closed = True


def _record(events, **cadence):
    r = SaveThenWrite(lambda units: events.append(("save", units)), **cadence)
    r.open(_File(events), lambda units: events.append(("write", units)))
    return r


def test_each_unit_is_journalled_then_written_at_once():
    events = []
    r = _record(events, flush_every_s=3600.0)
    for u in range(3):
        r.add(u)
    assert [e for e in events if e[0] != "flush"] == [
        ("save", [0]), ("write", [0]), ("save", [1]), ("write", [1]),
        ("save", [2]), ("write", [2])]


def test_units_kept_back_are_journalled_before_they_are_written():
    events = []
    r = _record(events, save_every_s=3600.0, write_every_s=3600.0)
    for u in range(4):
        r.add(u)
    assert events == []                     # neither cadence has come round
    r.add(4, saved=True)                    # a resumed run's unit: in the journal already
    r.write()
    assert events == [("save", [0, 1, 2, 3]), ("write", [0, 1, 2, 3, 4]), ("flush",)]


def test_a_file_to_be_written_again_gets_no_more_units_but_the_journal_does():
    events = []
    r = _record(events, save_every_s=3600.0, write_every_s=3600.0)
    r.add(0)
    r.stop_writing()
    r.add(1)
    r.write()
    assert events == [("save", [0, 1])]


class _Writeback:
    def __init__(self, events):
        self.events = events

    def kick(self):
        self.events.append(("writeback",))


def test_a_file_to_be_fsynced_when_complete_goes_to_the_disk_after_each_flush():
    events = []
    r = SaveThenWrite(lambda units: events.append(("save", units)),
                      writeback=_Writeback(events))
    r.open(_File(events), lambda units: events.append(("write", units)))
    r.add(0)
    assert events == [("save", [0]), ("write", [0]), ("flush",), ("writeback",)]


def test_the_writeback_syncs_the_file_once_at_a_time_and_close_waits_for_it(
        tmp_path, monkeypatch):
    import threading
    from pipeline.base import files
    started, release, synced = threading.Event(), threading.Event(), []

    def slow_fsync(path):
        started.set()
        release.wait(10)
        synced.append(path)
    monkeypatch.setattr(files, "_fsync", slow_fsync)
    w = files.Writeback(tmp_path / "r.h5")
    w.kick()
    assert started.wait(10)
    w.kick()                    # one under way: no second
    release.set()
    w.close()
    assert synced == [tmp_path / "r.h5"]
    w.kick()                    # a new one after it
    w.close()
    assert synced == [tmp_path / "r.h5"] * 2


@pytest.mark.parametrize("stop", [KeyboardInterrupt, RuntimeError])
def test_an_interruption_or_a_failure_keeps_every_finished_unit(tmp_path, stop):
    events = []
    bar = _Bar()
    r = _record(events, save_every_s=3600.0, write_every_s=3600.0)
    want = SweepInterrupted if stop is KeyboardInterrupt else RuntimeError
    with pytest.raises(want) as e:
        with stopping_safely(tmp_path / "s.h5", _Journal(events), bar, 10, "chunk", r):
            r.add(0)
            r.add(1)
            raise stop
    assert bar.closed
    assert events == [("save", [0, 1])]
    if stop is KeyboardInterrupt:
        assert "interrupted with 2 of 10 chunks saved" in str(e.value)
        assert "--resume" in str(e.value)


def test_the_sweep_file_writes_the_constraints_it_is_handed(studies, tmp_path):
    """SweepFile judges nothing: made-up g, cv and feasibility (unlike any the
    kernels' rows would give) are what it stores, and its per-chunk count of
    feasible candidates counts the flags handed to it."""
    from pipeline.results.sweep_file import SweepFile
    from pipeline.runs.sweep import build_problem
    from pipeline.study.objectives import Feasibility, constraint_names
    from pipeline.study.reader import load_study
    study = load_study(studies / "ov7_synthesis.toml")
    spec = study.sweep.with_candidates(40)
    problem = build_problem(study, spec)
    sf = SweepFile(tmp_path / "s.h5", study, problem)
    sf.create()
    c, x, status, metrics, rejected, _ = problem.evaluate_chunk(0, parallel=False)
    n, k = len(status), len(constraint_names(problem.has_margin, spec))
    made_up = Feasibility(np.arange(n * k, dtype=float).reshape(n, k) - 7.5,
                          np.full(n, 123.25), np.arange(n) % 3 == 0)
    with h5py.File(sf.path, "r+") as f:
        sf.write_chunk(sf.datasets(f), c, x, status, metrics, made_up, rejected)
    with h5py.File(sf.path, "r") as f:
        assert np.array_equal(f["candidates/constraints"][:n], made_up.g)
        assert np.array_equal(f["candidates/cv"][:n], made_up.cv)
        assert np.array_equal(f["candidates/feasible"][:n], made_up.feasible)
        assert f["progress/status_counts"][c][-1] == made_up.feasible.sum()
