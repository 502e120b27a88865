"""The Python API (pipeline.load_study / run / open) and the tables behind
`pipeline export`: rows equal to the HDF5 datasets, units with every column."""

import h5py
import numpy as np
import pandas as pd
import pytest

import pipeline
from pipeline.cli import main
from pipeline.kernels import config as kc

from support.sweep_helpers import SYNTHESIS_N as N
from support.sweep_helpers import copy_of
from pipeline.results.storage import variables


@pytest.fixture(scope="module")
def sweep(tmp_path_factory, synthesis_sweep):
    """This module's copy of the session's sweep of the main job's study."""
    return copy_of(synthesis_sweep, tmp_path_factory.mktemp("api"), "s.h5")


def test_run_returns_where_it_wrote(tmp_path, studies):
    res = pipeline.run(pipeline.load_study(studies / "ov7_synthesis.toml"), tmp_path / "s.h5",
                       candidates=40)
    assert res.results == tmp_path / "s.h5" and pipeline.open(res.results).shape[0] == 40


def test_the_package_offers_its_api():
    for name in ("load_study", "run", "solve_scene", "open", "tolerance", "compare",
                 "candidates", "scene_tables", "with_units"):
        assert name in dir(pipeline) and callable(getattr(pipeline, name))


def test_open_a_sweep_gives_the_datasets_row_for_row(sweep):
    df = pipeline.open(sweep)
    assert isinstance(df, pd.DataFrame) and len(df) == N
    with h5py.File(sweep, "r") as f:
        names = [n.decode() if isinstance(n, bytes) else n
                 for n in f["candidates/params"].attrs["names"]]
        np.testing.assert_array_equal(df[names].to_numpy(), f["candidates/params"][()])
        codes = f["candidates/status"][()]
        assert list(df["status"]) == [kc.STATUS_NAMES[c] for c in codes]
        np.testing.assert_array_equal(df["feasible"], f["candidates/feasible"][()])
        joints = [j.decode() if isinstance(j, bytes) else j
                  for j in f["metrics"].attrs["joint_names"]]
        for m in variables(f["metrics"]):
            if m == "peak_joint":       # the joint by name, as a scene's CSV names it (R1 ...)
                stored = f[f"metrics/{m}"][()]
                want = [joints[int(i)] if np.isfinite(i) else "" for i in stored]
                assert list(df[m]) == want and set(want) - {""} <= set(joints)
                continue
            np.testing.assert_array_equal(df[m], f[f"metrics/{m}"][()])
        np.testing.assert_array_equal(df["g_stroke_min"], f["candidates/constraints"][:, 0])
        # the failing group by name (the mechanism's groups), empty where none failed
        groups = [g.decode() if isinstance(g, bytes) else g
                  for g in f["candidates/fail_group"].attrs["groups"]]
        fg = f["candidates/fail_group"][()]
        assert list(df["fail_group"]) == [groups[i] if i >= 0 else "" for i in fg]
        failed = (codes != kc.OK) & (codes != kc.BAD_GEOMETRY) & (codes != kc.BRANCH_JUMP)
        assert failed.any() and (df["fail_group"][failed] == "triad").all()
        assert (df["fail_group"][codes == kc.OK] == "").all()
    assert df.attrs["units"]["L12"] == "mm" and df.attrs["units"]["peak_reaction"] == "N"
    front1 = df[df["front"] == 1]
    assert len(front1) >= 1 and front1["feasible"].all()


def test_export_a_sweep(sweep, tmp_path):
    assert main(["export", str(sweep), "--csv", str(tmp_path / "all"), "-q"]) == 0
    assert main(["export", str(sweep), "--csv", str(tmp_path / "feas"), "--feasible",
                 "-q"]) == 0
    assert main(["export", str(sweep), "--csv", str(tmp_path / "f1"), "--front", "1",
                 "-q"]) == 0
    everything = pd.read_csv(tmp_path / "all" / "candidates.csv")
    feas = pd.read_csv(tmp_path / "feas" / "candidates_feasible.csv")
    f1 = pd.read_csv(tmp_path / "f1" / "candidates_front1.csv")
    df = pipeline.open(sweep)
    assert len(everything) == N and len(feas) == int(df["feasible"].sum())
    assert len(f1) == int((df["front"] == 1).sum()) and (f1["front"] == 1).all()
    for col in ("L12 [mm]", "peak_reaction [N]", "dwell_start [deg]", "status", "feasible"):
        assert col in everything.columns, col
    np.testing.assert_allclose(everything["peak_reaction [N]"], df["peak_reaction"],
                               rtol=1e-11)


def test_parquet_round_trips(sweep, tmp_path, capsys):
    """Parquet export (pyarrow is a [test] dependency: this always runs): every
    column of the candidates' table, back as written."""
    assert main(["export", str(sweep), "--parquet", str(tmp_path / "pq"), "-q"]) == 0
    back = pd.read_parquet(tmp_path / "pq" / "candidates.parquet")
    df = pipeline.open(sweep)
    assert len(back) == len(df)
    for col in ("peak_reaction", "dwell_error", "L12", "feasible"):
        np.testing.assert_array_equal(back[col], df[col], err_msg=col)


def test_parquet_without_pyarrow_says_how_to_get_it(sweep, tmp_path, capsys, monkeypatch):
    """Without pyarrow (hidden from the import system) the export says what to install."""
    import sys
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    rc = main(["export", str(sweep), "--parquet", str(tmp_path / "pq"), "-q"])
    assert rc == 2 and "pip install pyarrow" in capsys.readouterr().err


def test_open_a_scene(tmp_path, studies):
    res = pipeline.run(studies / "ov7_base.toml", tmp_path / "a.h5", pictures=False)
    tables = pipeline.open(res.results)
    assert set(tables) == {"points", "links", "peaks", "cyclogram"}
    cyc = tables["cyclogram"]          # [cycle]: the eyelet's boundaries, cycle angle psi
    assert list(cyc["boundary"]) == ["dwell start", "forward start", "back start"]
    assert list(cyc["required"]) == pytest.approx([240.0, 30.0, 130.0])
    assert list(cyc["phase_error"]) == pytest.approx(list(cyc["design"] - cyc["required"]))
    assert cyc.attrs["units"]["phase_error"] == "deg"
    pts = tables["points"]
    with h5py.File(res.results, "r") as f:
        np.testing.assert_array_equal(pts["phi1"], f["dense/phi1"][()])
        i = [n.decode() if isinstance(n, bytes) else n
             for n in f["mechanism"].attrs["point_names"]].index("P9")
        np.testing.assert_array_equal(pts["P9_x"], f["dense/position"][:, i, 0])
    assert pipeline.with_units(pts).columns[1].endswith("[mm]")


def test_export_options_that_do_not_apply_are_refused(sweep, tmp_path, capsys):
    assert main(["export", str(sweep), "--csv", str(tmp_path), "--every", "3"]) == 2
    assert "--every" in capsys.readouterr().err
    assert main(["export", str(sweep)]) == 2
    assert "--csv DIR, --parquet DIR, --dxf DIR or --study OUT.toml" in capsys.readouterr().err


def test_pictures_are_figures_the_caller_saves(studies, tmp_path):
    """Plot functions return a matplotlib Figure and save nothing themselves."""
    import matplotlib
    from matplotlib.figure import Figure

    from pipeline.views import plots
    from pipeline.views.dynamics_plots import dynamics_figure
    before = set(tmp_path.iterdir())
    res = pipeline.solve_scene(studies / "ov7_class3.toml")
    for fig in (plots.scene_figure(res), plots.forces_figure(res)):
        assert isinstance(fig, Figure) and fig.axes
        matplotlib.pyplot.close(fig)
    dyn = pipeline.solve_scene(studies / "takeup_dynamics.toml")
    fig = dynamics_figure(dyn.dynamics[0])
    assert isinstance(fig, Figure)
    matplotlib.pyplot.close(fig)
    assert set(tmp_path.iterdir()) == before
    with pytest.raises(ValueError, match="pipeline.run"):
        pipeline.solve_scene(studies / "ov7_synthesis.toml")


def test_tolerance_in_memory_writes_nothing(studies, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    a = pipeline.tolerance(studies / "ov7_class3.toml", samples=64,
                           metrics=["stroke", "dwell_error"])
    t = a.table()
    assert list(t.index) == ["stroke", "dwell_error"] and t.loc["stroke", "units"] == "mm"
    assert t.loc["stroke", "p05"] < t.loc["stroke", "design"] < t.loc["stroke", "p95"]
    assert t.loc["dwell_error", "std"] > 0 and a.yield_ == 1.0
    assert not list(tmp_path.iterdir())
    with pytest.raises(ValueError, match="not a metric of a build"):   # as the command says
        pipeline.tolerance(studies / "ov7_class3.toml", samples=64, metrics=["peak_joint"])


def test_two_selections_exported_into_one_folder_keep_both(sweep, tmp_path):
    """--feasible then --front 1 into the same folder: two files, each named for
    what it holds (neither overwrites the other)."""
    out = tmp_path / "tables"
    for extra in (["--feasible"], ["--front", "1"], ["--front", "2"]):
        assert main(["export", str(sweep), "--csv", str(out), "-q", *extra]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == ["candidates_feasible.csv", "candidates_front1.csv",
                     "candidates_fronts1-2.csv"]
    feas = pd.read_csv(out / "candidates_feasible.csv")
    f1 = pd.read_csv(out / "candidates_front1.csv")
    assert len(f1) < len(feas) and (f1["front"] == 1).all()
