"""`pipeline run` and `pipeline export` on the scenes, and the self-describing HDF5 file."""

import h5py
import numpy as np
import pandas as pd
import pytest

from pipeline.cli import main
from pipeline.results.storage import FORMAT, open_results, read_units
from pipeline.base.errors import ResultsError


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
            assert all(read_units(d)) and d.attrs["long_name"], d.name


def test_csv_tables_match_hdf5(class3_run, tmp_path):
    """Every computed position, units in the headers, the rows equal to the HDF5
    datasets; --every thins the rows."""
    out, csv = class3_run
    pts = pd.read_csv(csv / "points.csv")
    links = pd.read_csv(csv / "links.csv")
    with h5py.File(out, "r") as f:
        n = f["dense/phi1"].shape[0]
        assert n == 360 and len(pts) == n
        # CSV keeps 12 significant digits
        np.testing.assert_allclose(pts["phi1 [deg]"].values, f["dense/phi1"][()], rtol=1e-12,
                                   atol=1e-12)
        i = list(f["mechanism"].attrs["point_names"]).index("P8")
        np.testing.assert_allclose(pts["V8_x [m/s]"].values, f["dense/velocity"][:, i, 0],
                                   rtol=1e-11)
        np.testing.assert_allclose(pts["P8_y [mm]"].values, f["dense/position"][:, i, 1],
                                   rtol=1e-11)
        # velocity in m/s = analog [mm/rad] * omega1 / 1000
        np.testing.assert_allclose(f["dense/velocity"][:, i, 0],
                                   f["dense/position_analog"][:, i, 0] * -94.4 / 1000,
                                   rtol=1e-15)
    for col in ("P8_x [mm]", "A8_y [m/s²]", "P3_x [mm]"):
        assert col in pts.columns
    assert [c for c in links.columns if c.startswith("phi_")] == [
        "phi_2_3 [deg]", "phi_3_4 [deg]", "phi_6_4 [deg]", "phi_7_5 [deg]"]
    assert "omega_2_3 [1/s]" in links.columns and "eps_7_5 [1/s²]" in links.columns
    r = pd.read_csv(csv / "reactions.csv")
    # each joint's header names the bodies it joins and its point, as the pictures do
    assert list(r.columns[1:4]) == ["R1 (ground / crank 1-2 at P1) x [N]",
                                    "R1 (ground / crank 1-2 at P1) y [N]",
                                    "R1 (ground / crank 1-2 at P1) [N]"]
    assert "R5 (ternary 3-4-5 / rocker 5-7-8 at P5) [N]" in r.columns
    # plain ASCII but for the units' one style (N·m: pipeline.base.units)
    assert all(c.replace("·", "").isascii() for c in r.columns)
    assert r.columns[-1] == "M_bal [N·m]" and len(r) == 360
    peaks = pd.read_csv(csv / "peaks.csv")
    assert list(peaks.columns) == ["quantity", "item", "value", "unit", "phi1 [deg]",
                                   "grid_value", "d_min [mm]"]
    reactions = peaks[peaks.quantity == "reaction"]
    assert list(reactions["item"]) == [f"R{k}" for k in range(1, 8)]
    assert (reactions["value"] >= reactions["grid_value"]).all()
    assert reactions["d_min [mm]"].notna().all()
    assert main(["export", str(out), "--csv", str(tmp_path / "thin"), "--every", "30",
                 "-q"]) == 0
    thin = pd.read_csv(tmp_path / "thin" / "points.csv")
    assert list(thin["phi1 [deg]"]) == list(range(0, -360, -30))


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


def test_the_program_collects_its_garbage_seldom_but_still_collects_it(monkeypatch):
    import gc

    from pipeline import cli
    saved = gc.get_threshold()
    seen = []

    def command():
        starts = []

        def count(phase, info):
            if phase == "start":
                starts.append(info["generation"])
        gc.callbacks.append(count)
        try:
            for _ in range(200_000):        # cycles a command leaves behind
                a = []
                a.append(a)
        finally:
            gc.callbacks.remove(count)
        seen.append(len(starts))
        return 0
    monkeypatch.setattr(cli, "main", command)
    gc.set_threshold(700, 10, 10)           # (Python's default, whatever the session set)
    try:
        assert cli.script() == 0
    finally:
        gc.unfreeze()
        gc.set_threshold(*saved)
    # Python's default collects some 280 times over 200,000 allocations
    assert 1 <= seen[0] <= 200_000 // 20_000
