"""numba's compiled code of the installation, copied from the suite's cache, for
a test that runs in a compile cache of its own."""

import os
import shutil
from pathlib import Path

from numba.core.caching import _CacheLocator


def copy_compiled(folders, dest, skip=()):
    """numba's cache of the package folders ``folders`` (as far as the suite has
    compiled them so far) copied from the suite's (NUMBA_CACHE_DIR) into ``dest``,
    but the files of the modules named in ``skip`` and any half-written file;
    returns ``dest``."""
    suite = Path(os.environ["NUMBA_CACHE_DIR"])
    for folder in folders:
        name = _CacheLocator.get_suitable_cache_subpath(str(Path(folder) / "x.py"))
        if (suite / name).is_dir():
            shutil.copytree(suite / name, Path(dest) / name, ignore=lambda _, names: [
                n for n in names if ".tmp" in n or n.split(".")[0] in skip])
    return Path(dest)
