"""`pipeline run` and `pipeline export` on the scenes, and the self-describing HDF5 file."""

import h5py
import numpy as np
import pandas as pd
import pytest

from pipeline.cli import main
from pipeline.storage import FORMAT, ResultsError, open_results


@pytest.fixture(scope="module")
def class3_run(tmp_path_factory, studies):
    d = tmp_path_factory.mktemp("b")
    out = d / "b.h5"
    assert main(["run", str(studies / "ov7_class3.toml"), "-o", str(out), "-q"]) == 0
    assert main(["export", str(out), "--csv", str(d / "csv"), "-q"]) == 0
    return out, d / "csv"


def test_hdf5_describes_itself(class3_run, studies):
    out, _ = class3_run
    with h5py.File(out, "r") as f:
        assert f.attrs["format"] == FORMAT
        for key in ("format_version", "software", "software_version", "created", "study_name"):
            assert f.attrs[key]
        assert f.attrs["study_toml"] == (studies / "ov7_class3.toml").read_text()
        datasets = []
        f.visititems(lambda n, o: datasets.append(o) if isinstance(o, h5py.Dataset) else None)
        assert len(datasets) > 10
        for d in datasets:
            assert d.attrs["units"] and d.attrs["long_name"], d.name


def test_csv_tables_match_hdf5(class3_run):
    out, csv = class3_run
    pts = pd.read_csv(csv / "points.csv")
    links = pd.read_csv(csv / "links.csv")
    assert list(pts.phi1_deg) == list(range(0, -361, -30))
    for col in ("P8_x", "P8_y", "V8_x", "V8_y", "A8_x", "A8_y", "P3_x"):
        assert col in pts.columns
    assert [c for c in links.columns if c.startswith("phi_")] == [
        "phi_2_3", "phi_3_4", "phi_6_4", "phi_7_5"]
    with h5py.File(out, "r") as f:
        i = list(f["mechanism"].attrs["point_names"]).index("P8")
        np.testing.assert_allclose(pts.V8_x.values, f["table/velocity"][:, i, 0], rtol=1e-11)
        # velocity in m/s = analog [mm/rad] * omega1 / 1000
        np.testing.assert_allclose(f["table/velocity"][:, i, 0],
                                   f["table/position_analog"][:, i, 0] * -94.4 / 1000, rtol=1e-15)
    r = pd.read_csv(csv / "reactions.csv")
    assert list(r.columns[1:4]) == ["R1_x", "R1_y", "R1"] and r.columns[-1] == "M_bal"
    peaks = pd.read_csv(csv / "peaks.csv")
    assert list(peaks.columns) == ["joint", "R_max", "phi1_deg", "d_min_mm"]
    assert list(peaks.joint) == [f"R{k}" for k in range(1, 8)]


def test_pictures_written(class3_run):
    out, _ = class3_run
    for p in (out.with_suffix(".png"), out.with_name("b_forces.png")):
        assert p.exists() and p.stat().st_size > 20_000
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_not_our_file_is_refused(tmp_path, capsys):
    bad = tmp_path / "other.h5"
    with h5py.File(bad, "w") as f:
        f["x"] = 1
    with pytest.raises(ResultsError, match="not a pipeline results file"):
        open_results(bad)
    assert main(["export", str(bad), "--csv", str(tmp_path / "c")]) == 2
    assert "not a pipeline results file" in capsys.readouterr().err
    txt = tmp_path / "t.h5"
    txt.write_text("hello")
    assert main(["export", str(txt), "--csv", str(tmp_path / "c")]) == 2


def test_bad_study_exit_code(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text("[study]\nkind = 'scene'\n")
    assert main(["run", str(p), "-o", str(tmp_path / "x.h5")]) == 2
    err = capsys.readouterr().err
    assert "s.toml" in err and "study.name" in err
