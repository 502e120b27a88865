"""Self-describing HDF5 files: root attributes name the format and its
version, the software and its version, the date and the study verbatim;
every dataset carries ``units`` and ``long_name``."""

from __future__ import annotations

import datetime as _dt
import json
import os
from contextlib import contextmanager
from pathlib import Path

import h5py
import numpy as np

from ..base.units import unit_text
from ..base.version import __version__
from ..base.errors import ResultsError  # noqa: F401  (raised by every reader of results)
from ..kernels import config as kc

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
    if getattr(study, "cad_reports", None):    # the CAD reports its bodies read
        f.attrs["cad_reports"] = cad_reports_text(study)
    for k, v in extra.items():
        f.attrs[k] = v


def cad_reports_text(study) -> str:
    """The CAD reports a study's bodies read, as the results file keeps them
    ("" for a study without)."""
    reports = getattr(study, "cad_reports", None)
    return json.dumps(reports) if reports else ""


def study_digest(study) -> dict:
    """What identifies the study a run computes, for a journal's manifest:
    its text and the CAD reports its bodies read (the same text with an edited
    report is another mechanism; "" where there is none, as before reports)."""
    import hashlib
    reports = cad_reports_text(study)
    return {"study_sha256": hashlib.sha256(study.text.encode()).hexdigest(),
            "cad_reports_sha256": hashlib.sha256(reports.encode()).hexdigest() if reports
            else ""}


def same_study(f, study) -> bool:
    """Whether the results file ``f`` was computed from ``study``: the same
    text and the same CAD reports."""
    return (attr_text(f.attrs.get("study_toml")) == study.text
            and attr_text(f.attrs.get("cad_reports", "")) == cad_reports_text(study))


# Compression of every chunked dataset: byte shuffle + gzip (deflate) at a low
# level, which every HDF5 reader has (h5dump, HDFView, MATLAB, netCDF-C); LZF is
# readable from h5py alone.
COMPRESSION = dict(compression="gzip", compression_opts=1, shuffle=True)

try:    # ISA-L's deflate: a zlib stream, as zlib's at level 1 (as small), about 5 times sooner
    from isal.isal_zlib import compress as _deflate
except ImportError:     # pragma: no cover - a platform without its wheel
    from zlib import compress as _deflate


def write_rows(d, lo, values, chunk_rows=None):
    """``d[lo:lo + len(values)] = values`` for a dataset made with ``COMPRESSION``
    and chunks of whole rows.  Every whole chunk the rows cover is filtered here
    (the byte shuffle in NumPy, deflate by ISA-L) and written as it is stored
    (``write_direct_chunk``): HDF5's own deflate of a sweep's chunk took a quarter
    of the main thread's time, which on 2 cores the kernels' threads shared.  The
    stored chunk is what HDF5's filters would store (any reader inflates it).
    The rows of a chunk covered in part (before the first whole chunk: rows
    appended with store = feasible; after the last: a sweep's last, short chunk)
    go through HDF5, whose chunk cache keeps that chunk until it is complete.
    ``chunk_rows``: ``direct_chunk_rows(d)``, where the caller keeps it (asking
    HDF5 for the filters took a tenth of a millisecond a dataset)."""
    values = np.asarray(values)
    hi = lo + len(values)
    ch = direct_chunk_rows(d) if chunk_rows is None else chunk_rows
    if not ch:
        d[lo:hi] = values
        return
    a = min(-(-lo // ch) * ch, hi)      # the rows before the first whole chunk: lo .. a
    b = max(a, hi // ch * ch)           # the whole chunks: a .. b
    if a > lo:
        d[lo:a] = values[:a - lo]
    if b > a:
        rows = np.ascontiguousarray(values[a - lo:b - lo], dtype=d.dtype)
        size = d.dtype.itemsize
        offset = (0,) * (rows.ndim - 1)
        for r in range(0, b - a, ch):
            c = rows[r:r + ch].view(np.uint8).reshape(-1, size)
            d.id.write_direct_chunk((a + r,) + offset, _deflate(c.T.tobytes(), 1))
    if hi > b:
        d[b:hi] = values[b - lo:]


def direct_chunk_rows(d):
    """The rows of one chunk of ``d`` where its chunks can be written filtered
    here: chunks of whole rows of a native type, filtered by exactly the byte
    shuffle and then deflate (``COMPRESSION``); else 0."""
    if not d.chunks or d.chunks[1:] != d.shape[1:] or not d.dtype.isnative:
        return 0
    plist = d.id.get_create_plist()
    filters = [plist.get_filter(i)[:1] for i in range(plist.get_nfilters())]
    return d.chunks[0] if filters == [(h5py.h5z.FILTER_SHUFFLE,),
                                      (h5py.h5z.FILTER_DEFLATE,)] else 0


# The status of a candidate or a position as an HDF5 enumeration: h5dump,
# HDFView and netCDF readers show the names; h5py and NumPy read int8 codes.
STATUS_ENUM = h5py.enum_dtype({name: code for code, name in kc.STATUS_NAMES.items()},
                              basetype="i1")


def units_attr(units):
    """One form for units: a string, or one per column (a list), in the
    package's one style (``base.units``: N·m, m/s²)."""
    if isinstance(units, (list, tuple)):
        units = [unit_text(u) for u in units]
        return units[0] if len(set(units)) == 1 else np.array(units, dtype=h5py.string_dtype())
    return unit_text(units)


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
    # a file written before the one style reads in it (N*m -> N·m)
    return [unit_text(x) for x in out] if len(out) == n else ["?"] * n


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
    d.attrs["units"] = units_attr(units)
    d.attrs["long_name"] = long_name
    d.make_scale(name)
    return d


def link_coordinates(group, names):
    """Hard-link the dimension scales ``names`` of the file's root into
    ``group`` (the same datasets, no copy): xarray reads the variables of one
    group only, so a group opened alone (``open_dataset(path, group=...)``)
    has its coordinates only if they are in it.  A scale that grows (the
    ``candidate`` rows of store = feasible) grows in every group at once."""
    root = group.file
    for name in names:
        if name not in group:
            group[name] = root[name]


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


def attach(d, dims, scales=None):
    """Name the dimensions of dataset ``d``: each entry the name of a dimension
    scale in its group or a group above it (or a dataset of its group, which
    becomes the scale: phi1 of a curves group, t of a dynamics case).
    ``scales``: the scales found so far for datasets of ``d``'s group, by name
    (``put``'s, one dict per group object: a scene's file names the same few
    dimensions in every dataset, and each look took a third of its writing)."""
    for i, name in enumerate(dims):
        if name is None:
            continue
        s = scales.get(name) if scales is not None else None
        if s is None:
            s = _scale_above(d, name)
            if scales is not None:
                scales[name] = s
        if s.id != d.id:
            d.dims[i].attach_scale(s)


def _scale_above(d, name):
    """The dimension scale ``name`` for dataset ``d``: a dataset of that name in its
    group or the nearest group above it (made a scale if it is not one)."""
    g = d.parent
    while True:
        s = g.get(name)
        if isinstance(s, h5py.Dataset):
            if not h5py.h5ds.is_scale(s.id):
                s.make_scale(name)
            return s
        if g.name == "/":
            raise KeyError(f"no dimension scale {name!r} above {d.name}")
        g = g.parent


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
        # (the group's own dataset of this name, from now on nearer than any above)
        scales = group.__dict__.setdefault("_pipeline_scales", {})
        scales.pop(name, None)
        attach(d, dims, scales)
    return d


# HDF5's chunk cache per dataset while a run writes: a chunk that rows are appended to
# (store = feasible) stays in it until full, instead of being inflated and deflated again
# at each append (the default 1 MiB holds no chunk of a sweep's params)
WRITE_CACHE = 16 << 20


@contextmanager
def hdf5_writing(path, mode="r+", expendable=True):
    """``h5py.File(path, mode)`` for a file this run can rebuild or throw away,
    closed in a defined order whatever happens.

    When a write fails (a full disk), HDF5 keeps dirty pages it cannot flush: a
    plain close then fails again and leaves objects that crash the interpreter
    when it exits.  So on an error the file's bytes are given up first
    (truncated: the space comes back, and HDF5 can then close it cleanly), and
    the error goes on to the caller.  ``expendable``: a temporary file (given up
    on any error); otherwise (a sweep's own file, rebuilt from its journal by
    --resume) only an input/output error gives it up, and an interruption
    leaves it flushed and readable."""
    from ..base.files import errno_of, naming
    import sys
    # an HDF5 object closed while the block runs (a dataset let go) writes its
    # pages then; if that fails, h5py can only report it as "Exception ignored":
    # such errors are collected here and fail the block instead
    lost, hook = [], sys.unraisablehook

    def collect(u):
        if isinstance(u.exc_value, (OSError, RuntimeError)) and not lost:
            lost.append(u.exc_value)
        elif not isinstance(u.exc_value, (OSError, RuntimeError)):
            hook(u)
    sys.unraisablehook = collect
    f = h5py.File(path, mode, rdcc_nbytes=WRITE_CACHE)
    try:
        yield f
        if lost:
            raise lost[0]
        f.flush()
        if lost:
            raise lost[0]
    except BaseException as e:
        io_error = isinstance(e, (OSError, RuntimeError))
        give_up = expendable or io_error
        if not give_up:
            try:
                f.flush()
            except Exception:
                give_up = True
        if give_up:
            try:
                os.truncate(path, 0)
            except OSError:
                pass
        try:
            f.close()
        except Exception:
            pass
        sys.unraisablehook = hook
        if isinstance(e, RuntimeError) and errno_of(e):
            raise naming(e, path) from None     # the system's error, as an OSError
        raise
    try:
        f.close()
    finally:
        sys.unraisablehook = hook


# free space kept beside a results file that HDF5 writes in place: HDF5 cannot
# recover from a write that fails (its objects are left half-closed and crash the
# interpreter later), so a write that could fill the disk is refused before it starts
HDF5_HEADROOM = 4 << 20


def room_for(path, nbytes: int):
    """Refuse (OSError ENOSPC naming ``path``) an HDF5 write of about ``nbytes``
    into ``path`` where the disk has less than that plus HDF5_HEADROOM free."""
    import errno
    import shutil
    free = shutil.disk_usage(Path(path).parent).free
    if free < nbytes + HDF5_HEADROOM:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))


# the largest file an update is made on in memory (hdf5_image); a larger one is
# updated on disk, in a copy (hdf5_writing)
IMAGE_LIMIT = 2 << 30


@contextmanager
def hdf5_image(target, start=None):
    """An HDF5 file built in memory, its bytes written to ``target`` (a
    temporary file of ``files.replacing``) when the block completes: HDF5 never
    writes to the disk itself, so a full disk is one OSError from that last
    write, and a failure anywhere leaves nothing to clean up.  ``start``: a
    file to begin from (an update of it); one over IMAGE_LIMIT is updated on
    disk in a copy instead."""
    import io
    import shutil
    if start is not None and os.path.getsize(start) > IMAGE_LIMIT:
        shutil.copyfile(start, target)
        with hdf5_writing(target) as f:
            yield f
        return
    buf = io.BytesIO(b"" if start is None else Path(start).read_bytes())
    f = h5py.File(buf, "r+" if start is not None else "w")
    try:
        yield f
    finally:
        f.close()
    with open(target, "wb") as out:
        out.write(buf.getbuffer())


def is_results_file(path, kind=None) -> bool:
    """Whether ``path`` (a link followed) is a results file of this package
    (of ``kind`` if given): an HDF5 file whose root says ``format = FORMAT``.
    Read without HDF5's file lock, so a file a run is writing is still known."""
    try:
        with h5py.File(path, "r", locking=False) as f:
            return (attr_text(f.attrs.get("format")) == FORMAT
                    and (kind is None or attr_text(f.attrs.get("kind")) == kind))
    except (OSError, RuntimeError, ValueError):     # not HDF5, unreadable, damaged
        return False


def results_output(path, *, inputs=(), overwrite=False):
    """``files.check_output`` for a command that writes a results file: an
    existing file is replaced only if it is a results file, with ``overwrite``."""
    from ..base.files import check_output
    return check_output(path, inputs=inputs, replaces=is_results_file, overwrite=overwrite)


def open_results(path, kind=None):
    """Open a results file read-only, checking that it is ours (and of ``kind``)."""
    path = Path(path)
    if not path.exists():
        raise ResultsError(path, "file not found")
    if path.is_dir():
        raise ResultsError(path, "is a folder, not a results file")
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        if "unable to lock file" in str(e) or isinstance(e, BlockingIOError):
            raise ResultsError(path, "another run or program has this file open for writing; "
                                     "wait for it to finish") from None
        raise ResultsError(path, "not a readable HDF5 file (" + " ".join(str(e).split())
                           + ")") from None
    try:
        return _checked(f, path, kind)
    except (RuntimeError, OSError, KeyError) as e:     # damaged bytes inside the file
        f.close()
        raise ResultsError(path, "damaged results file (" + " ".join(str(e).split())
                           + ")") from None


def _checked(f, path, kind):
    if f.attrs.get("format") != FORMAT:
        f.close()
        raise ResultsError(path, "not a pipeline results file (no format attribute "
                                 f"{FORMAT!r}); was it written by `pipeline run`?")
    if kind is not None and f.attrs.get("kind") != kind:
        got = f.attrs.get("kind")
        f.close()
        raise ResultsError(path, f"is a {got} result, this command needs a {kind} result")
    missing = [n for n in REQUIRED.get(attr_text(f.attrs.get("kind")), ()) if n not in f]
    if attr_text(f.attrs.get("store", "all")) == "feasible" and "candidate" not in f:
        missing.append("candidate (the sweep index of each kept row)")
    n = {f[k].shape[0] for k in ("candidates/status", "candidates/params", "candidates/feasible")
         if k in f} if attr_text(f.attrs.get("kind")) == "sweep" else set()
    if missing or len(n) > 1:
        f.close()
        what = f"missing {', '.join(missing)}" if missing else "datasets of different lengths"
        raise ResultsError(path, f"damaged or incomplete results file ({what})")
    bad = unknown_status(f)
    if bad:
        f.close()
        raise ResultsError(path, f"damaged results file: {bad}")
    return f


STATUS_BLOCK = 1 << 22      # status codes checked per read (4 MiB of int8)


def unknown_status(f) -> str | None:
    """The first status code in ``f`` that is not one of the package's, as
    "DATASET[row] = code (known: ...)", else None.  Every status dataset is
    checked (an HDF5 enumeration, or a dataset named status): a code a reader
    would take for some status, or fail on, means the bytes were damaged or
    written by another program."""
    found = []

    def visit(name, obj):
        if not isinstance(obj, h5py.Dataset) or obj.dtype.kind not in "iu":
            return
        enum = h5py.check_enum_dtype(obj.dtype)
        if enum is not None or name.rsplit("/", 1)[-1] == "status":
            known = (set(enum.values()) if enum is not None else set(kc.STATUS_NAMES))
            found.append((name, obj, known))

    f.visititems(visit)
    for name, d, known in found:
        if d.size == 0:
            continue
        codes = np.array(sorted(known))
        rows = d.shape[0] if d.ndim else 1
        step = max(1, STATUS_BLOCK // max(1, d.size // rows))
        for lo in range(0, rows, step):
            block = np.atleast_1d(np.asarray(d[lo:lo + step] if d.ndim else d[()]))
            if block.min() >= codes[0] and block.max() <= codes[-1] and (
                    codes.size == codes[-1] - codes[0] + 1 or np.isin(block, codes).all()):
                continue
            at = np.argwhere(~np.isin(block, codes))[0]
            return (f"{name}[{lo + int(at[0])}] = {int(block[tuple(at)])}, not a status code "
                    f"of the package (known: {', '.join(str(c) for c in codes)})")
    return None


# what every reader of a kind of results file relies on
REQUIRED = {
    "sweep": ("candidates/status", "candidates/params", "candidates/feasible", "metrics",
              "reference", "progress/chunk_done"),
    "scene": ("mechanism/parameters", "table/phi1", "table/position", "dense/phi1",
              "dense/position"),
}
