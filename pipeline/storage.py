"""Self-describing HDF5 files: root attributes name the format and its
version, the software and its version, the date and the study verbatim;
every dataset carries ``units`` and ``long_name``."""

from __future__ import annotations

import datetime as _dt
from pathlib import Path

import h5py
import numpy as np

from .version import __version__
from .errors import ResultsError  # noqa: F401  (raised by every reader of results)
from .kernels import config as kc

FORMAT = "pipeline-results"
FORMAT_VERSION = "1.2"     # 1.1: status enums, units per column, dimension scales;
                           # 1.2: sweeps store the failing group (candidates/fail_group)


def attr_text(v):
    """An HDF5 string attribute as str (h5py may hand back bytes)."""
    return v.decode() if isinstance(v, bytes) else v


def status_table():
    return "; ".join(f"{k}={v}" for k, v in kc.STATUS_NAMES.items())


def write_root_attrs(f, kind, study, **extra):
    f.attrs["format"] = FORMAT
    f.attrs["format_version"] = FORMAT_VERSION
    f.attrs["kind"] = kind
    f.attrs["software"] = "pipeline"
    f.attrs["software_version"] = __version__
    f.attrs["created"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    f.attrs["study_name"] = study.name
    f.attrs["study_title"] = study.title
    f.attrs["study_file"] = str(study.path)
    f.attrs["study_toml"] = study.text
    for k, v in extra.items():
        f.attrs[k] = v


# Compression of every chunked dataset: byte shuffle + gzip (deflate) at a low
# level, which every HDF5 reader has (h5dump, HDFView, MATLAB, netCDF-C); LZF is
# readable from h5py alone.
COMPRESSION = dict(compression="gzip", compression_opts=1, shuffle=True)


# The status of a candidate or a position as an HDF5 enumeration: h5dump,
# HDFView and netCDF readers show the names; h5py and NumPy read int8 codes.
STATUS_ENUM = h5py.enum_dtype({name: code for code, name in kc.STATUS_NAMES.items()},
                              basetype="i1")


def units_attr(units):
    """One form for units: a UDUNITS string, or one per column (a list)."""
    if isinstance(units, (list, tuple)):
        units = [str(u) for u in units]
        return units[0] if len(set(units)) == 1 else np.array(units, dtype=h5py.string_dtype())
    return str(units)


def read_units(d, n=None) -> list:
    """The units of each column of dataset ``d`` (``n`` columns): a string
    attribute for all, a list per column; format 1.0 wrote JSON lists or
    comma-separated text, which are read too."""
    import json
    u = d.attrs.get("units", "")
    if isinstance(u, np.ndarray):
        out = [attr_text(x) for x in u]
    else:
        u = attr_text(u)
        try:
            out = json.loads(u) if u.startswith("[") else None
        except ValueError:
            out = None
        if out is None:
            out = [x.strip() for x in u.split(",")] if "," in u else [u]
    n = n if n is not None else (d.shape[1] if d.ndim > 1 else 1)
    if len(out) == 1 and n > 1:
        out = out * n
    return [str(x) for x in out] if len(out) == n else ["?"] * n


def coordinate(group, name, values, units, long_name):
    """A dimension scale ``name`` in ``group`` (names or numbers along a
    dimension): netCDF readers (xarray) see a named dimension with these
    coordinates, h5dump a DIMENSION_LIST."""
    values = list(values)
    if values and isinstance(values[0], str):
        data = np.array(values, dtype=h5py.string_dtype())
    else:
        data = np.asarray(values)
    d = group.create_dataset(name, data=data)
    d.attrs["units"] = units
    d.attrs["long_name"] = long_name
    d.make_scale(name)
    return d


def candidate_ids(f) -> np.ndarray:
    """The sweep's candidate index of every stored row: every candidate (the
    default), or the feasible ones of a sweep run with store = feasible."""
    if "candidate" in f:
        return f["candidate"][()]
    return np.arange(f["candidates/status"].shape[0])


def row_of(f, cid: int) -> int:
    """The stored row of candidate ``cid`` (ValueError if it has none)."""
    ids = candidate_ids(f)
    n = int(f.attrs.get("n_candidates", len(ids)))
    if not 0 <= cid < n:
        raise ValueError(f"candidate {cid} does not exist: the sweep drew {n} candidates "
                         f"(0..{n - 1})")
    j = int(np.searchsorted(ids, cid))
    if j == len(ids) or ids[j] != cid:
        raise ValueError(f"candidate {cid} is not in the file: the sweep kept only its "
                         f"feasible candidates (store = feasible), {len(ids)} of {n}")
    return j


def attach(d, dims):
    """Name the dimensions of dataset ``d``: each entry the name of a dimension
    scale in its group or a group above it (or a dataset of its group, which
    becomes the scale: phi1 of a curves group, t of a dynamics case)."""
    for i, name in enumerate(dims):
        if name is None:
            continue
        g = d.parent
        while True:
            if name in g and isinstance(g[name], h5py.Dataset):
                s = g[name]
                if not h5py.h5ds.is_scale(s.id):
                    s.make_scale(name)
                break
            if g.name == "/":
                raise KeyError(f"no dimension scale {name!r} above {d.name}")
            g = g.parent
        if s.id != d.id:
            d.dims[i].attach_scale(s)


def variables(group) -> list:
    """Names of the group's datasets that hold data (its dimension scales,
    the coordinates, left out)."""
    return [k for k, v in group.items()
            if isinstance(v, h5py.Dataset) and not (h5py.h5ds.is_scale(v.id)
                                                    and k not in ("phi1", "t"))]


def remove_group(f, name):
    """Delete group ``name`` of ``f`` after detaching its datasets from the
    dimension scales they use (a deleted dataset must not stay listed by a
    scale that outlives it)."""
    if name not in f:
        return

    def detach(_, obj):
        if isinstance(obj, h5py.Dataset) and not h5py.h5ds.is_scale(obj.id):
            for i, dim in enumerate(obj.dims):
                for s in list(dim.values()):
                    obj.dims[i].detach_scale(s)
    f[name].visititems(detach)
    del f[name]


def put(group, name, data, units, long_name, dims=None, **attrs):
    """Write one dataset with its units (``units_attr``), long name and named
    dimensions (``attach``)."""
    data = np.asarray(data)
    kw = {}
    if data.ndim >= 1 and data.size > 4096:
        kw = dict(COMPRESSION, chunks=True)
    d = group.create_dataset(name, data=data, **kw)
    d.attrs["units"] = units_attr(units)
    d.attrs["long_name"] = long_name
    for k, v in attrs.items():
        d.attrs[k] = v
    if dims:
        attach(d, dims)
    return d


def open_results(path, kind=None):
    """Open a results file read-only, checking that it is ours (and of ``kind``)."""
    path = Path(path)
    if not path.exists():
        raise ResultsError(path, "file not found")
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise ResultsError(path, f"not a readable HDF5 file ({e})") from None
    if f.attrs.get("format") != FORMAT:
        f.close()
        raise ResultsError(path, "not a pipeline results file (no format attribute "
                                 f"{FORMAT!r}); was it written by `pipeline run`?")
    if kind is not None and f.attrs.get("kind") != kind:
        got = f.attrs.get("kind")
        f.close()
        raise ResultsError(path, f"is a {got} result, this command needs a {kind} result")
    missing = [n for n in REQUIRED.get(attr_text(f.attrs.get("kind")), ()) if n not in f]
    n = {f[k].shape[0] for k in ("candidates/status", "candidates/params", "candidates/feasible")
         if k in f} if attr_text(f.attrs.get("kind")) == "sweep" else set()
    if missing or len(n) > 1:
        f.close()
        what = f"missing {', '.join(missing)}" if missing else "datasets of different lengths"
        raise ResultsError(path, f"damaged or incomplete results file ({what})")
    return f


# what every reader of a kind of results file relies on
REQUIRED = {
    "sweep": ("candidates/status", "candidates/params", "candidates/feasible", "metrics",
              "reference", "progress/chunk_done"),
    "scene": ("mechanism/parameters", "table/phi1", "table/position", "dense/phi1",
              "dense/position"),
}
