"""A sweep that keeps only its feasible rows (`--store feasible`): analyze, report,
pipeline.open and export read it as they read a full file.  The two files are
the same study and the same draws (the session's sweep: same candidate count
and chunk size), so every number of the feasible file is held against the full
file's feasible rows."""

import h5py
import numpy as np
import pandas as pd
import pytest

import pipeline
from pipeline.cli import main
from pipeline.kernels import config as kc
from support.naive_pareto import brute_force_rank
from support.sweep_helpers import SYNTHESIS_CHUNK, SYNTHESIS_N, copy_of
from pipeline.results.storage import variables


@pytest.fixture(scope="module")
def files(tmp_path_factory, synthesis_sweep, studies):
    d = tmp_path_factory.mktemp("feasible")
    full = copy_of(synthesis_sweep, d, "full.h5")
    feas = d / "feasible.h5"
    assert main(["run", str(studies / "ov7_synthesis.toml"), "--candidates", str(SYNTHESIS_N),
                 "--chunk-size", str(SYNTHESIS_CHUNK), "--store", "feasible", "-o", str(feas),
                 "-q"]) == 0
    for path in (full, feas):
        assert main(["analyze", str(path), "-q"]) == 0
    with h5py.File(full, "r") as f:
        keep = f["candidates/feasible"][()]
    assert 50 <= keep.sum() < SYNTHESIS_N
    return full, feas, keep


def test_the_file_holds_the_feasible_rows_and_the_counts(files):
    full, feas, keep = files
    with h5py.File(full, "r") as a, h5py.File(feas, "r") as b:
        np.testing.assert_array_equal(b["candidate"][()], np.flatnonzero(keep))
        np.testing.assert_array_equal(b["candidates/params"][()], a["candidates/params"][()][keep])
        np.testing.assert_array_equal(b["candidates/status"][()], a["candidates/status"][()][keep])
        for m in variables(a["metrics"]):
            np.testing.assert_array_equal(b[f"metrics/{m}"][()], a[f"metrics/{m}"][()][keep],
                                          err_msg=m)
        # every chunk's count of each status, then of the feasible ones
        counts = b["progress/status_counts"][()].sum(axis=0)
        status = a["candidates/status"][()]
        for code in range(len(kc.STATUS_NAMES)):
            assert counts[code] == (status == code).sum(), kc.STATUS_NAMES[code]
        assert counts[-1] == keep.sum()


def test_xarray_names_the_kept_rows_by_their_sweep_numbers(files):
    """The groups' coordinates are the root's (hard links): the grown
    ``candidate`` scale is the same in /candidates and /metrics."""
    import xarray as xr
    full, feas, keep = files
    for g in ("candidates", "metrics"):
        ds = xr.open_dataset(feas, group=g, engine="h5netcdf")
        np.testing.assert_array_equal(ds["candidate"].values, np.flatnonzero(keep))
    ds = xr.open_dataset(feas, group="candidates", engine="h5netcdf")
    with h5py.File(full, "r") as a:
        k = int(np.flatnonzero(keep)[0])
        assert float(ds["params"].sel(candidate=k, variable="L12")) == a["candidates/params"][k, 0]


def test_open_gives_the_rows_with_their_sweep_numbers(files):
    full, feas, keep = files
    a, b = pipeline.open(full), pipeline.open(feas)
    assert len(b) == keep.sum() and b["feasible"].all()
    np.testing.assert_array_equal(b["candidate"], np.flatnonzero(keep))
    want = a[keep].reset_index(drop=True)
    for col in ("L12", "P6x", "dwell_error", "peak_reaction", "stroke", "status"):
        np.testing.assert_array_equal(b[col], want[col], err_msg=col)


def test_analyze_ranks_the_same_fronts(files):
    """The fronts of the feasible file are those of a brute-force dominance test,
    and the full file's on its feasible rows; the knee is the same candidate."""
    full, feas, keep = files
    with h5py.File(full, "r") as a, h5py.File(feas, "r") as b:
        objectives = [o.decode() if isinstance(o, bytes) else o for o in b.attrs["objectives"]]
        F = np.stack([b[f"metrics/{o}"][()] for o in objectives], axis=1)
        rank = b["analysis/pareto_rank"][()]
        np.testing.assert_array_equal(rank, brute_force_rank(F, np.ones(len(F), bool)))
        np.testing.assert_array_equal(rank, a["analysis/pareto_rank"][()][keep])
        ids = b["candidate"][()]
        assert ids[b["analysis/knee"][()]] == a["analysis/knee"][()]
        np.testing.assert_array_equal(ids[b["analysis/front1/index"][()]],
                                      a["analysis/front1/index"][()])


def test_report_and_browse_name_the_sweep_numbers(files, tmp_path, capsys, monkeypatch):
    """The knee is named by its sweep number (the full file's knee) in the report
    and by browse, with the full file's numbers."""
    import json

    from pipeline.views import report
    monkeypatch.setattr(report, "EXPLORER_DRAWINGS", 1)      # the test's time, not the page's
    full, feas, keep = files
    with h5py.File(full, "r") as a:
        knee = int(a["analysis/knee"][()])
        dwell = float(a["metrics/dwell_error"][knee])
    assert main(["report", str(feas), "-o", str(tmp_path / "r.html"), "-q"]) == 0
    page = (tmp_path / "r.html").read_text()
    assert f"#{knee}: " in page                   # the summary's knee line
    capsys.readouterr()
    assert main(["browse", str(feas), "--candidate", "knee", "--format", "json"]) == 0
    shown = json.loads(capsys.readouterr().out)
    assert shown["candidate"] == knee and shown["front"] == 1 and shown["feasible"]
    assert json.dumps(dwell) in json.dumps(shown)     # its dwell error, every digit


def test_export_equals_the_full_files_feasible_export(files, tmp_path):
    full, feas, keep = files
    assert main(["export", str(feas), "--csv", str(tmp_path / "b"), "-q"]) == 0
    assert main(["export", str(full), "--csv", str(tmp_path / "a"), "--feasible", "-q"]) == 0
    a = pd.read_csv(tmp_path / "a" / "candidates_feasible.csv")
    b = pd.read_csv(tmp_path / "b" / "candidates.csv")
    assert len(b) == keep.sum()
    pd.testing.assert_frame_equal(a, b)
