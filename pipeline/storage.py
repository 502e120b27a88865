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
FORMAT_VERSION = "1.0"


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


def put(group, name, data, units, long_name, **attrs):
    """Write one dataset with its units and long name."""
    data = np.asarray(data)
    kw = {}
    if data.ndim >= 1 and data.size > 4096:
        kw = dict(COMPRESSION, chunks=True)
    d = group.create_dataset(name, data=data, **kw)
    d.attrs["units"] = units
    d.attrs["long_name"] = long_name
    for k, v in attrs.items():
        d.attrs[k] = v
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
