"""Sweeps written before FRICTION_LOCK (status 7, issue 52) gave progress/status_counts
one column fewer (7 statuses, then the feasible ones): a journal of that time resumes
bit for bit, and a finished file of that time opens, browses and analyzes with the
new status counted 0.  The old formats are fabricated from today's by dropping the
column (store = feasible: the one store that keeps the counts per chunk)."""

import h5py
import numpy as np
import pytest

from pipeline.cli import main
from pipeline.kernels import config as kc
from pipeline.results.sweep_file import COUNTED, status_counts
from pipeline.runs.lifecycle import SweepInterrupted
from pipeline.runs.sweep import run_sweep
from pipeline.study.reader import load_study
from support.sweep_helpers import assert_same_results

N, CHUNK = 60, 20
OLD = [name for name in COUNTED if name != "FRICTION_LOCK"]    # the columns before it


@pytest.fixture(scope="module")
def study(studies):
    return load_study(studies / "ov7_synthesis.toml")


@pytest.fixture(scope="module")
def today(study, tmp_path_factory):
    out = tmp_path_factory.mktemp("old_counts") / "today.h5"
    run_sweep(study, out, candidates=N, chunk_size=CHUNK, progress=False, store="feasible")
    return out


def test_the_new_status_is_the_column_before_the_feasible_ones():
    assert COUNTED[kc.FRICTION_LOCK] == "FRICTION_LOCK" and COUNTED[-1] == "feasible"
    assert len(OLD) == len(COUNTED) - 1 == 8


def test_a_journal_written_before_friction_lock_resumes_bit_for_bit(study, today, tmp_path):
    out = tmp_path / "r.h5"
    with pytest.raises(SweepInterrupted):
        run_sweep(study, out, candidates=N, chunk_size=CHUNK, progress=False,
                  store="feasible", stop_after_chunks=1)
    parts = sorted((tmp_path / "r.h5.parts").glob("chunk_*.npz"))
    assert parts
    for p in parts:          # as the journal of the version before wrote it
        with np.load(p) as z:
            arrays = {k: z[k] for k in z.files}
        assert arrays["counts"].shape == (len(COUNTED),)
        arrays["counts"] = np.delete(arrays["counts"], kc.FRICTION_LOCK)
        with open(p, "wb") as f:
            np.savez(f, **arrays)
    run_sweep(study, out, progress=False, resume=True, store="feasible")
    assert_same_results(today, out)


def _as_before(path):
    """The finished file ``path`` as the version before wrote it: 7 status columns."""
    from pipeline.results.storage import attach, coordinate
    with h5py.File(path, "a") as f:
        c = f["progress/status_counts"][()]
        assert c.shape[1] == len(COUNTED)
        for name in ("progress/status_counts", "progress/counted", "counted"):
            del f[name]
        coordinate(f, "counted", OLD, "1", "a status, or the feasible candidates")
        f["progress/counted"] = f["counted"]
        d = f["progress"].create_dataset("status_counts",
                                         data=np.delete(c, kc.FRICTION_LOCK, axis=1))
        d.attrs.update(units="1", long_name="candidates of each status, and the feasible ones, "
                                            "per chunk", columns=OLD)
        attach(d, ("chunk", "counted"))


def test_a_finished_file_written_before_friction_lock_opens_browses_and_analyzes(
        today, tmp_path, capsys):
    import shutil
    old = tmp_path / "old.h5"
    shutil.copy(today, old)
    _as_before(old)
    with h5py.File(old, "r") as f:
        assert f["progress/status_counts"].shape[1] == len(COUNTED) - 1
        got = status_counts(f)
    with h5py.File(today, "r") as f:
        want = status_counts(f)
    assert got == want and "FRICTION_LOCK" not in got
    assert sum(v["count"] for k, v in got.items() if k in kc.STATUS_NAMES.values()) == N
    capsys.readouterr()
    assert main(["browse", str(old), "--format", "json"]) == 0
    assert '"feasible"' in capsys.readouterr().out
    assert main(["analyze", str(old), "-q"]) == 0
    assert main(["browse", str(old), "--candidate", "knee", "-q"]) == 0
