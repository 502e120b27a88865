"""numba's compiled code of the installation, copied from the suite's cache, for
a test that runs in a compile cache of its own."""

import os
import shutil
from pathlib import Path

from numba.core.caching import _CacheLocator


def copy_compiled(folders, dest, skip=(), to=None):
    """numba's cache of the package folders ``folders`` (as far as the suite has
    compiled them so far) copied from the suite's (NUMBA_CACHE_DIR) into ``dest``,
    but the files of the modules named in ``skip`` and any half-written file;
    ``to``: the folders whose cache each becomes (a copy of it, its files' times
    kept: numba's cache checks a source's time and size), by default
    ``folders``; returns ``dest``."""
    suite = Path(os.environ["NUMBA_CACHE_DIR"])
    for folder, copy in zip(folders, to or folders):
        name = _subpath(folder)
        if (suite / name).is_dir():
            shutil.copytree(suite / name, Path(dest) / _subpath(copy), ignore=lambda _, names: [
                n for n in names if ".tmp" in n or n.split(".")[0] in skip])
    return Path(dest)


def _subpath(folder):
    """The subfolder of NUMBA_CACHE_DIR that numba caches ``folder``'s kernels in."""
    return _CacheLocator.get_suitable_cache_subpath(str(Path(folder) / "x.py"))
