"""Compiled numerical kernels.

Only ``@njit`` code over plain arrays lives here; it imports nothing but numpy,
numba and math.  Study files, HDF5, Dask, plots and the CLI live outside.

numba's on-disk cache checks only the timestamp of a function's own file, so a
cached kernel keeps an old copy of a kernel it calls from another file.  On
import, the cached kernels are therefore dropped whenever any kernel source
changed, here or a group type's (``pipeline/group_types/*/kernels.py``; a
digest of all of them is kept beside the cache).
"""

import hashlib as _hashlib
import os as _os
from pathlib import Path as _Path


def _drop_stale_cache():
    here = _Path(__file__).resolve().parent
    types = sorted(here.parent.glob("group_types/*/kernels.py"))
    sources = sorted(here.glob("*.py")) + types
    digest = _hashlib.sha256(b"".join(p.read_bytes() for p in sources)).hexdigest()
    modules = {p.stem for p in sources}
    package = here / "__pycache__"
    user = _os.environ.get("NUMBA_CACHE_DIR")
    # numba caches in NUMBA_CACHE_DIR when it is set, else beside the sources (here and
    # in each group type's folder): only those folders are checked
    dirs = [_Path(user)] if user else [package] + [t.parent / "__pycache__" for t in types]
    for d in dirs:
        stamp = d / "pipeline_kernels.sha256"
        try:
            if stamp.exists() and stamp.read_text() == digest:
                continue
            if d.exists():
                for f in d.rglob("*.nb[ic]"):
                    if f.name.split(".", 1)[0] in modules and (not d.match("__pycache__")
                                                               or f.parent == d):
                        f.unlink(missing_ok=True)
            d.mkdir(parents=True, exist_ok=True)
            stamp.write_text(digest)
        except OSError:  # a read-only installation: numba then does not cache either
            pass


_drop_stale_cache()
