"""Results files that any HDF5 tool opens: h5dump prints the numbers and the
status names (gzip, HDF5 enumerations), xarray sees named dimensions in every
group (dimension scales), units in one UDUNITS form per column; and files of
format 1.0 are still read."""

import re
import shutil
import subprocess
import warnings

import h5py
import numpy as np
import pytest

import pipeline
from pipeline.kernels import config as kc
from pipeline.results.storage import read_units


@pytest.fixture(scope="module")
def files(tmp_path_factory, studies, synthesis_sweep):
    from support.sweep_helpers import copy_of
    d = tmp_path_factory.mktemp("formats")
    sweep = copy_of(synthesis_sweep, d, "sweep.h5")
    from pipeline.analysis.fronts import analyze
    analyze(sweep)
    scenes = [pipeline.run(studies / f"{s}.toml", d / f"{s}.h5", pictures=False).results
              for s in ("ov7_class3", "takeup_dynamics", "cam_rocker_input")]
    return [sweep] + scenes


def _groups(path):
    out = ["/"]
    with h5py.File(path, "r") as f:
        f.visititems(lambda n, o: out.append(n) if isinstance(o, h5py.Group) else None)
    return out


def test_h5dump_prints_numbers_and_status_names(files):
    """h5dump (Debian's hdf5-tools, which .ci/run installs: never skipped) prints
    the first candidate's dwell error and status by name."""
    assert shutil.which("h5dump"), "h5dump is not installed (apt-get install hdf5-tools)"
    sweep = files[0]
    out = subprocess.run(["h5dump", "-d", "/metrics/dwell_error", str(sweep)],
                         capture_output=True, text=True, check=True).stdout
    assert "DATA {" in out and "(0): " in out
    with h5py.File(sweep, "r") as f:
        first = f["metrics/dwell_error"][0]
    assert (f"{first:.6g}" in out) if np.isfinite(first) else "nan" in out
    out = subprocess.run(["h5dump", "-d", "/candidates/status", str(sweep)],
                         capture_output=True, text=True, check=True).stdout
    with h5py.File(sweep, "r") as f:
        first = kc.STATUS_NAMES[int(f["candidates/status"][0])]
    assert "H5T_ENUM" in out and '"NEWTON_MAXITER"' in out
    assert re.search(rf"\(0\): {first}\b", out), (first, out[:2000])


def test_xarray_opens_every_group_with_named_dimensions(files):
    import xarray as xr
    for path in files:
        for g in _groups(path):
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                ds = xr.open_dataset(path, group=g, engine="h5netcdf")
            assert not [d for d in ds.sizes if str(d).startswith("phony")], (path, g)
    ds = xr.open_dataset(files[0], group="candidates", engine="h5netcdf")
    assert ds["params"].dims == ("candidate", "variable")
    with h5py.File(files[0], "r") as f:
        params, G = f["candidates/params"][()], f["candidates/constraints"][()]
        names = list(f["candidates/constraints"].attrs["names"])
        metrics = {m: f["metrics"][m][()] for m in ("stroke", "dwell_error")}
    # the README's recipe: each group opened alone has its coordinates, and the
    # values are the stored ones
    np.testing.assert_array_equal(ds["params"].sel(variable="L12").values, params[:, 0])
    np.testing.assert_array_equal(ds["constraints"].sel(constraint=names[-1]).values, G[:, -1])
    np.testing.assert_array_equal(ds["candidate"].values, np.arange(len(params)))
    m = xr.open_dataset(files[0], group="metrics", engine="h5netcdf")
    assert "candidate" in m.coords and "candidate" not in m.data_vars
    for k, v in metrics.items():
        np.testing.assert_array_equal(m[k].sel(candidate=2).values, v[2])
    ref = xr.open_dataset(files[0], group="reference", engine="h5netcdf")
    assert list(ref["variable"].values) == list(ds["variable"].values)
    prog = xr.open_dataset(files[0], group="progress", engine="h5netcdf")
    assert int(prog["status_counts"].sel(counted="feasible").sum()) == int(ds["feasible"].sum())
    root = xr.open_dataset(files[0], engine="h5netcdf")
    assert list(root["variable"].values)[:2] == ["L12", "P6x"]
    dense = xr.open_dataset(files[1], group="dense", engine="h5netcdf")
    assert dense["position"].dims == ("phi1", "point", "axis")
    np.testing.assert_array_equal(dense["phi1"].values, pipeline.open(files[1])["points"]["phi1"])


def test_units_are_one_form(files):
    """A UDUNITS string, or one per column: never JSON text, 'mixed' or 'a, b'."""
    for path in files:
        with h5py.File(path, "r") as f:
            def check(name, obj):
                if isinstance(obj, h5py.Dataset):
                    u = obj.attrs["units"]
                    texts = [u] if isinstance(u, str) else [x.decode() if isinstance(x, bytes)
                                                            else x for x in u]
                    for t in texts:
                        assert t and not t.startswith("[") and "," not in t and t != "mixed", \
                            (name, u)
                    if not isinstance(u, str):
                        assert len(texts) == obj.shape[-1], name
            f.visititems(check)
    with h5py.File(files[1], "r") as f:
        units = read_units(f["mechanism/parameters"], f["mechanism/parameters"].shape[0])
        names = list(f["parameter"].asstr()[()])
        assert units[names.index("crank.length")] == "mm"
        assert units[names.index("crank.phiM0")] == "rad"
        assert units[names.index("ternary 3-4-5.mass")] == "kg"       # ov7_class3's bodies
        assert units[names.index("ternary 3-4-5.J_S")] == "kg·m²"


def test_format_1_0_files_are_still_read(files, tmp_path):
    """Format 1.0 wrote units as JSON text and 'mm, mm, 1', and the status as
    plain int8: such a file still opens as a table."""
    old = tmp_path / "old.h5"
    shutil.copy(files[0], old)
    with h5py.File(old, "r+") as f:
        f.attrs["format_version"] = "1.0"
        p = f["candidates/params"]
        p.attrs["units"] = '["mm", "mm", "mm", "mm", "mm", "mm", "mm", "mm", "mm"]'
        f["candidates/constraints"].attrs["units"] = "mm, mm, 1"
        st = f["candidates/status"][()]
        del f["candidates/status"]
        f["candidates/status"] = st.astype(np.int8)
    df = pipeline.open(old)
    new = pipeline.open(files[0])
    assert df.attrs["units"]["L12"] == "mm" and df.attrs["units"]["g_singularity_margin_min"] == "1"
    assert list(df["status"]) == list(new["status"])
    assert (df["status"] == "OK").sum() == int((st == kc.OK).sum())
