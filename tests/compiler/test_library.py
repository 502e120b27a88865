"""The library compiled once per installation (``pipeline.compiler.beside.
compile_library``, ``python -m pipeline.compiler.plan_path`` by hand): after it, a
scene of any mechanism compiles nothing (issue 53: a new mechanism's scene never
waits for a compile)."""

import json
import subprocess
import sys

import pytest
from conftest import STUDIES
from support.checkout import child_env

_SCENES = """
import json, sys
from pathlib import Path
from numba.core import event
from pipeline.runner import run_study
from pipeline.study.reader import load_study
compiled = {}
for path in sorted(Path(sys.argv[1]).glob("*.toml")):
    study = load_study(path)
    if study.kind != "scene":
        continue
    with event.install_recorder("numba:compile") as rec:
        run_study(study, Path(sys.argv[2]) / (path.stem + ".h5"), pictures=False,
                  progress=False)
    compiled[path.stem] = sorted({e.data["dispatcher"].py_func.__qualname__
                                  for _, e in rec.buffer})
print(json.dumps(compiled))
"""


@pytest.mark.slow
def test_after_the_library_no_scene_compiles(tmp_path):
    """A new installation (every compile cache empty): the library compiled by
    hand, then every shipped scene study run as `pipeline run` runs it (crank
    dynamics, the flywheel, friction, the output rocker's dwell, the cyclogram
    among them) compiles nothing, neither of its mechanism's nor of the
    library's.  Before, a scene with friction compiled its kernel for 6 s and
    one with crank dynamics the flywheel's and the dwell's for 1.5 s."""
    env = child_env(PIPELINE_CACHE_DIR=str(tmp_path / "modules"),
                    NUMBA_CACHE_DIR=str(tmp_path / "numba"), PIPELINE_COMPILE_BESIDE="0")
    r = subprocess.run([sys.executable, "-m", "pipeline.compiler.plan_path"], env=env,
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    out = tmp_path / "out"
    out.mkdir()
    r = subprocess.run([sys.executable, "-c", _SCENES, str(STUDIES), str(out)], env=env,
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    compiled = json.loads(r.stdout.strip().splitlines()[-1])
    assert len(compiled) >= 12 and "takeup_dynamics" in compiled and "ov7_friction" in compiled
    assert {name: c for name, c in compiled.items() if c} == {}
