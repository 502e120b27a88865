"""numba's cache of the compiled kernels is never stale (pipeline/kernels/__init__.py):
on import, a cache folder's kernels are dropped when a source they may call has
changed, and only then.  The library's kernels call only the library's; a group
type's the library's and its own (tests/test_architecture.py holds the imports).
So a changed library drops every folder, a changed group type its own folder only,
and a new group type none: the suite's test of a new type (tests/test_group_types.py)
and a designer who adds one keep the library's compiled kernels."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

PKG = Path(__file__).resolve().parents[2] / "pipeline"
MARK = "kernel.mark-1.py311.nbi"       # a cached kernel's index, as numba names them


def test_a_changed_source_drops_only_the_kernels_that_may_call_it(tmp_path):
    pkg = tmp_path / "pipeline"
    shutil.copytree(PKG, pkg, ignore=shutil.ignore_patterns("__pycache__"))
    cache = tmp_path / "numba"
    env = dict(os.environ, PYTHONPATH=str(tmp_path), NUMBA_CACHE_DIR=str(cache))

    def imported():
        """The folders whose marks survived a fresh import, then every folder marked."""
        subprocess.run([sys.executable, "-c", "import pipeline.kernels"], env=env, cwd=tmp_path,
                       check=True)
        kept = {d.name.rsplit("_", 1)[0] for d in cache.iterdir() if (d / MARK).exists()}
        for d in cache.iterdir():
            (d / MARK).write_text("compiled")
        return kept

    types = {d.name for d in (pkg / "group_types").iterdir() if (d / "kernels.py").exists()}
    assert "rrr" in types and len(types) >= 5
    assert imported() == set()                         # a new installation: nothing cached
    assert imported() == {"kernels"} | types           # nothing changed: everything stays
    with open(pkg / "group_types" / "rrr" / "kernels.py", "a") as f:
        f.write("\n# changed\n")
    assert imported() == {"kernels"} | types - {"rrr"}
    (pkg / "group_types" / "zzz").mkdir()
    (pkg / "group_types" / "zzz" / "kernels.py").write_text("# a new type\n")
    assert imported() == {"kernels"} | types           # the new one had nothing cached
    with open(pkg / "kernels" / "geometry.py", "a") as f:
        f.write("\n# changed\n")
    assert imported() == set()                         # the library: every folder
