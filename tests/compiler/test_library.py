"""The library compiled once per installation (``pipeline.compiler.beside.
compile_library``; by hand ``pipeline compile --library``): a scene that comes
before it says that it compiles the installation's kernels, and after it a
scene of any mechanism compiles nothing (issue 53: a new mechanism's scene never
waits for a compile)."""

import json
import subprocess
import sys

import pytest
from conftest import STUDIES
from support.checkout import child_env
from support.terminal import longest_silence, run_on_terminal, said_live

SILENCE_S = 2.0         # tests/base/test_progress.py
CLI = [sys.executable, "-m", "pipeline.cli"]

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
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a pseudo-terminal")
def test_a_new_installation_compiles_its_library_once(tmp_path):
    """A new installation (every compile cache empty).  Its first scene compiles
    the kernels it needs, said live as the installation's kernels, once for all
    mechanisms, with its seconds (not only as the run's time).  Then the library
    compiled by hand (`pipeline compile --library`), and every shipped scene study run as `pipeline run` runs it
    (crank dynamics, the flywheel, friction, the output rocker's dwell and the
    cyclogram among them) compiles nothing, neither of its mechanism's nor of the
    library's.  Before, a scene with friction compiled its kernel for 6 s after
    the library, and one with crank dynamics the flywheel's and the dwell's."""
    env = child_env(PIPELINE_CACHE_DIR=str(tmp_path / "modules"),
                    NUMBA_CACHE_DIR=str(tmp_path / "numba"), PIPELINE_COMPILE_BESIDE="0")
    code, times, end, text = run_on_terminal(
        CLI + ["run", str(STUDIES / "warp_feed_fourbar.toml"), "-o", str(tmp_path / "w.h5"),
               "--no-pictures"], env=env)
    assert code == 0, text
    assert longest_silence(times, end) <= SILENCE_S, (times, end, text)
    said_live(text, "compiling this installation's kernels (once for all mechanisms")
    assert "kernels ready after" in text
    r = subprocess.run(CLI + ["compile", "--library"], env=env, capture_output=True,
                       text=True, timeout=900)
    assert r.returncode == 0 and r.stdout.startswith("library: "), r.stdout + r.stderr[-3000:]
    assert "Warning" not in r.stderr, r.stderr[-3000:]
    out = tmp_path / "out"
    out.mkdir()
    r = subprocess.run([sys.executable, "-c", _SCENES, str(STUDIES), str(out)], env=env,
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    compiled = json.loads(r.stdout.strip().splitlines()[-1])
    assert len(compiled) >= 12 and "takeup_dynamics" in compiled and "ov7_friction" in compiled
    assert {name: c for name, c in compiled.items() if c} == {}


def test_compile_library_takes_no_study(capsys):
    """`pipeline compile --library` compiles the installation's kernels, no
    study's: a study or --show with it is refused in one line."""
    from pipeline.cli import main
    for extra in ([str(STUDIES / "ov7_base.toml")], ["--show"]):
        assert main(["compile", "--library", *extra]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and "--library compiles the installation's kernels" in err
