"""Compiled numerical kernels.

Only ``@njit`` code over plain arrays lives here; it imports nothing but numpy,
numba and math.  Study files, HDF5, Dask, plots and the CLI live outside.

numba's on-disk cache checks only the timestamp of a function's own file, so a
cached kernel keeps an old copy of a kernel it calls from another file.  On
import, the cached kernels are therefore dropped whenever any kernel source
changed, here or a group type's (``pipeline/group_types/*/kernels.py``; a
digest of all of them is kept in each of their cache folders).
"""

import hashlib as _hashlib
import os as _os
from pathlib import Path as _Path


def _cache_folders(sources):
    """The folders numba caches the kernels of ``sources`` in: beside each
    source folder (``__pycache__``), or, with NUMBA_CACHE_DIR set, that
    folder's own subfolder for it (``<name>_<sha1 of its path>``, as numba
    names it: another checkout's or project's are left alone)."""
    user = _os.environ.get("NUMBA_CACHE_DIR")
    folders = sorted({_os.path.dirname(_os.path.abspath(p)) for p in sources})
    if not user:
        return [_Path(f) / "__pycache__" for f in folders]
    return [_Path(user) / f"{_os.path.basename(f)}_{_hashlib.sha1(f.encode()).hexdigest()}"
            for f in folders]


def _drop_stale_cache():
    here = _Path(_os.path.dirname(_os.path.abspath(__file__)))
    sources = sorted(here.glob("*.py")) + sorted(here.parent.glob("group_types/*/kernels.py"))
    digest = _hashlib.sha256(b"".join(p.read_bytes() for p in sources)).hexdigest()
    for d in _cache_folders(sources):
        stamp = d / "pipeline_kernels.sha256"
        try:
            if stamp.exists() and stamp.read_text() == digest:
                continue
            for f in d.glob("*.nb[ic]") if d.exists() else ():
                f.unlink(missing_ok=True)
            d.mkdir(parents=True, exist_ok=True)
            stamp.write_text(digest)
        except OSError:  # a read-only installation: numba then does not cache either
            pass


_drop_stale_cache()
