"""Compiled numerical kernels.

Only ``@njit`` code over plain arrays lives here; it imports nothing but numpy,
numba and math.  Study files, HDF5, Dask, plots and the CLI live outside.

numba's on-disk cache checks only the timestamp of a function's own file, so a
cached kernel keeps an old copy of a kernel it calls from another file.  On
import, the cached kernels are therefore dropped whenever a kernel source they
may call changed (a digest of those sources is kept in each cache folder): the
library's (this folder) when any of its sources changed, a group type's
(``pipeline/group_types/*/kernels.py``) when the library's or its own did.
The library's kernels import nothing of a group type's, and a group type's
nothing of another's (tests/test_architecture.py), so a new or changed group
type leaves the library's compiled kernels and the other types' in place.
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
    library = sorted(here.glob("*.py"))
    types = sorted(here.parent.glob("group_types/*/kernels.py"))
    for sources in [library] + [[k] for k in types]:
        # what the kernels of ``sources`` may call: the library's and their own
        digest = _hashlib.sha256(b"".join(
            p.read_bytes() for p in sorted(set(library) | set(sources)))).hexdigest()
        _drop_unless(_cache_folders(sources)[0], digest)


def _drop_unless(folder, digest):
    """The cached kernels in ``folder`` dropped unless it holds ``digest``."""
    stamp = folder / "pipeline_kernels.sha256"
    try:
        if stamp.exists() and stamp.read_text() == digest:
            return
        for f in folder.glob("*.nb[ic]") if folder.exists() else ():
            f.unlink(missing_ok=True)
        folder.mkdir(parents=True, exist_ok=True)
        stamp.write_text(digest)
    except OSError:  # a read-only installation: numba then does not cache either
        pass


_drop_stale_cache()
