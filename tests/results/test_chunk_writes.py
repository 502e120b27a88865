"""A sweep's rows written as whole chunks filtered by the package
(``storage.write_rows``: the byte shuffle in NumPy, deflate by ISA-L) hold the
same values as HDF5's own filters would store, read back by h5py, by stdlib zlib
and by h5dump; rows outside whole chunks, and datasets with other filters, go
through HDF5."""

import shutil
import subprocess
import zlib

import h5py
import numpy as np
import pytest

from pipeline.results import storage
from pipeline.results.storage import COMPRESSION, STATUS_ENUM, write_rows

CH = 64


def _cases(n, rng):
    x = rng.normal(size=(n, 3))
    x[::7, 1] = np.nan
    return {"f8_2d": ("f8", x),
            "status": (STATUS_ENUM, rng.integers(0, 6, n).astype(np.int64)),
            "flag": ("?", rng.random(n) < 0.3),
            "group": ("i2", rng.integers(-1, 5, n).astype("i2")),
            "metric": ("f8", np.where(rng.random(n) < 0.2, np.nan, rng.lognormal(size=n)))}


@pytest.fixture
def counted(monkeypatch):
    calls = []
    deflate = storage._deflate
    monkeypatch.setattr(storage, "_deflate", lambda b, level: calls.append(1) or deflate(b, level))
    return calls


@pytest.mark.parametrize("lo, whole", [(0, 2), (CH, 2), (CH // 4, 1), (CH + 3, 1)])
def test_whole_chunks_filtered_here_hold_hdf5s_values(tmp_path, counted, lo, whole):
    """2.5 chunks of rows from ``lo``: the ``whole`` chunks they cover written
    filtered by the package, the rows of chunks covered in part (before them:
    rows appended, store = feasible; after them) by HDF5; every value as
    HDF5's own write stores it."""
    rng = np.random.default_rng(7)
    n = lo + 5 * CH // 2
    path = tmp_path / "rows.h5"
    with h5py.File(path, "w") as f:
        for name, (dtype, values) in _cases(n - lo, rng).items():
            shape = (n,) + values.shape[1:]
            for kind in ("here", "hdf5"):
                d = f.create_dataset(f"{kind}/{name}", shape, dtype,
                                     chunks=(CH,) + values.shape[1:], **COMPRESSION)
                if kind == "here":
                    write_rows(d, lo, values)
                else:
                    d[lo:n] = values
    assert len(counted) == whole * 5       # the whole chunks of each of the five datasets
    first = -(-lo // CH) * CH               # the first whole chunk's first row
    with h5py.File(path, "r") as f:
        for name in _cases(1, rng):
            here, hdf5 = f[f"here/{name}"][()], f[f"hdf5/{name}"][()]
            assert here.dtype == hdf5.dtype and here.tobytes() == hdf5.tobytes(), name
            # the stored chunk is a zlib stream of the shuffled bytes: any reader inflates it
            d = f[f"here/{name}"]
            mask, raw = d.id.read_direct_chunk((first,) + (0,) * (d.ndim - 1))
            rows = here[first:first + CH]
            size = rows.dtype.itemsize
            assert mask == 0
            assert zlib.decompress(raw) == rows.view(np.uint8).reshape(-1, size).T.tobytes()


def test_rows_appended_chunk_by_chunk(tmp_path, counted):
    """Rows appended to a growing dataset (store = feasible) in runs that start
    and end anywhere in a chunk: the same values as HDF5 stores, the chunks
    they fill written filtered here."""
    rng = np.random.default_rng(3)
    sizes = [5, CH - 5, 3 * CH + 7, 11, CH // 2, 2 * CH]
    values = rng.normal(size=sum(sizes))
    with h5py.File(tmp_path / "kept.h5", "w") as f:
        d = f.create_dataset("x", (0,), "f8", maxshape=(None,), chunks=(CH,), **COMPRESSION)
        lo = 0
        for k in sizes:
            d.resize(lo + k, axis=0)
            write_rows(d, lo, values[lo:lo + k])
            lo += k
        assert d[()].tobytes() == values.tobytes()
    assert len(counted) == 4        # chunks 1, 2, 3 (by the third run) and 5 (by the last)


def test_h5dump_reads_chunks_filtered_here(tmp_path):
    """h5dump (hdf5-tools, installed by .ci/run) prints a chunk written here."""
    assert shutil.which("h5dump"), "h5dump is not installed (apt-get install hdf5-tools)"
    values = np.arange(2 * CH, dtype="f8") / 8
    path = tmp_path / "dump.h5"
    with h5py.File(path, "w") as f:
        d = f.create_dataset("x", (2 * CH,), "f8", chunks=(CH,), **COMPRESSION)
        write_rows(d, 0, values)
    out = subprocess.run(["h5dump", "-d", "/x", "-s", str(CH + 3), "-c", "2", str(path)],
                         capture_output=True, text=True, check=True).stdout
    assert f"({CH + 3}): {values[CH + 3]:g}, {values[CH + 4]:g}" in out, out


@pytest.mark.parametrize("make", [dict(compression="gzip", compression_opts=1),   # no shuffle
                                  dict(compression="lzf", shuffle=True),
                                  dict(**COMPRESSION, fletcher32=True)])
def test_other_filters_go_through_hdf5(tmp_path, counted, make):
    """A dataset with another filter pipeline is written by HDF5 alone."""
    values = np.linspace(0, 1, 3 * CH)
    with h5py.File(tmp_path / "other.h5", "w") as f:
        d = f.create_dataset("x", (4 * CH,), "f8", chunks=(CH,), **make)
        write_rows(d, 0, values)
        assert d[:len(values)].tobytes() == values.tobytes()
    assert counted == []
