"""A status code that is not one of the package's (a damaged file, or one
another program wrote) is refused where a results file is opened, in one line
naming the file, the dataset, the row and the code: `pipeline.open` raised
pandas' raw ValueError, and analyze, show and `browse --candidate` took the
code for some status (issue 58, case 9)."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from pipeline.cli import main
from pipeline.kernels import config as kc
from pipeline.results.storage import open_results, unknown_status
from pipeline.base.errors import ResultsError
from support.sweep_helpers import copy_of


@pytest.fixture()
def damaged(synthesis_sweep, tmp_path):
    """A copy of the session's sweep whose candidate 17 has status 99."""
    path = copy_of(synthesis_sweep, tmp_path, "damaged.h5")
    with h5py.File(path, "r+") as f:
        d = f["candidates/status"]
        raw = d[()].view(np.int8)
        raw[17] = 99
        d[()] = raw.view(d.dtype) if h5py.check_enum_dtype(d.dtype) else raw
        assert int(d[17]) == 99
    return path


def test_the_session_sweep_has_only_known_codes(synthesis_sweep):
    with h5py.File(synthesis_sweep, "r") as f:
        assert unknown_status(f) is None


def test_opening_names_the_dataset_row_and_code(damaged):
    with pytest.raises(ResultsError) as e:
        open_results(damaged)
    text = str(e.value)
    assert str(damaged) in text and "candidates/status[17] = 99" in text
    assert "\n" not in text


@pytest.mark.parametrize("argv", [
    ["analyze", "{f}", "-q"],
    ["browse", "{f}", "--candidate", "17"],
    ["browse", "{f}"],
    ["show", "{f}", "--candidate", "17", "-o", "{d}/c17.png"],
    ["export", "{f}", "--csv", "{d}/tables"],
])
def test_every_command_refuses_it_in_one_line(damaged, argv, capsys):
    before = damaged.read_bytes()
    code = main([a.format(f=damaged, d=damaged.parent) for a in argv])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert err.count("\n") == 0 and "candidates/status[17] = 99" in err, err
    assert damaged.read_bytes() == before


def test_the_public_api_refuses_it(damaged):
    import pipeline
    with pytest.raises(ResultsError, match=r"candidates/status\[17\] = 99"):
        pipeline.open(damaged)


def test_a_code_inside_the_range_that_the_enum_lacks_is_found(tmp_path):
    """The check goes by the file's own enumeration, holes included."""
    enum = h5py.enum_dtype({"A": 0, "C": 2}, basetype="i1")
    with h5py.File(tmp_path / "e.h5", "w") as f:
        f.create_dataset("x/status", data=np.array([0, 2, 1, 0], np.int8), dtype=enum)
        assert unknown_status(f) == "x/status[2] = 1, not a status code of the package " \
                                    "(known: 0, 2)"
        f.create_dataset("y/status", data=np.full((5, 3), kc.OK, np.int8))
        del f["x/status"]
        assert unknown_status(f) is None
        f["y/status"][3, 1] = 77
        assert "y/status[3] = 77" in unknown_status(f)
