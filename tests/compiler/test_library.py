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
from support.terminal import SILENCE_S, longest_silence, run_on_terminal, said_live

CLI = [sys.executable, "-m", "pipeline.cli"]

# after the library, every shipped scene as `pipeline run` runs it; printed: every
# compiled kernel of the package that gained a compiled version meanwhile, compiled
# or loaded from numba's cache (a load is a kernel the library left out, which an
# installation without this suite's cache would compile there)
_SCENES = """
import json, sys
from pathlib import Path
from numba.core.registry import CPUDispatcher
from pipeline.compiler.beside import compile_library
from pipeline.runner import run_study
from pipeline.study.reader import load_study


def versions():
    # each kernel once (a module that imports it names it too): its name and versions
    out = {}
    for name, mod in list(sys.modules.items()):
        if name.startswith("pipeline") and not name.startswith(("pipeline_mech_",
                                                                "pipeline_gpu_")):
            for value in list(vars(mod).values()):
                if isinstance(value, CPUDispatcher):
                    f = value.py_func
                    out[id(value)] = (f"{f.__module__}.{f.__qualname__}", len(value.overloads))
    return out


compile_library()
before = versions()
scenes = []
for path in sorted(Path(sys.argv[1]).glob("*.toml")):
    study = load_study(path)
    if study.kind == "scene":
        run_study(study, Path(sys.argv[2]) / (path.stem + ".h5"), pictures=False,
                  progress=False)
        scenes.append(path.stem)
gained = {name: n for k, (name, n) in versions().items() if n > before.get(k, ("", 0))[1]}
print(json.dumps({"scenes": scenes, "gained": gained, "kernels": len(before)}))
"""


@pytest.mark.slow
def test_after_the_library_no_scene_compiles(tmp_path):
    """The library compiled (``compile_library``, as `pipeline compile --library`
    and the process beside the first sweep call it), then every shipped scene
    study run as `pipeline run` runs it (crank dynamics, the flywheel, friction,
    the output rocker's dwell and the cyclogram among them): no kernel of the
    package gains a compiled version, neither compiled nor loaded from numba's
    cache.  Before, a scene with friction compiled its kernel for 6 s after the
    library, and one with crank dynamics the flywheel's and the dwell's."""
    out = tmp_path / "out"
    out.mkdir()
    r = subprocess.run([sys.executable, "-c", _SCENES, str(STUDIES), str(out)],
                       env=child_env(PIPELINE_COMPILE_BESIDE="0"), capture_output=True,
                       text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    res = json.loads(r.stdout.strip().splitlines()[-1])
    assert len(res["scenes"]) >= 12 and {"takeup_dynamics", "ov7_friction"} <= set(res["scenes"])
    assert res["kernels"] > 50      # (the package's kernels were seen)
    assert res["gained"] == {}


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a pseudo-terminal")
def test_a_scene_on_a_new_installation_says_it_compiles_the_installation_s_kernels(tmp_path):
    """Every compile cache empty: the first scene compiles the kernels it needs,
    said live as the installation's kernels, once for all mechanisms, with its
    seconds (not only as the run's time), never silent over 2 s."""
    env = child_env(PIPELINE_CACHE_DIR=str(tmp_path / "modules"),
                    NUMBA_CACHE_DIR=str(tmp_path / "numba"), PIPELINE_COMPILE_BESIDE="0")
    code, times, end, text = run_on_terminal(
        CLI + ["run", str(STUDIES / "warp_feed_fourbar.toml"), "-o", str(tmp_path / "w.h5"),
               "--no-pictures"], env=env)
    assert code == 0, text
    assert longest_silence(times, end) <= SILENCE_S, (times, end, text)
    said_live(text, "compiling this installation's kernels (once for all mechanisms")
    assert "kernels ready after" in text


def test_compile_library_takes_no_study(capsys):
    """`pipeline compile --library` compiles the installation's kernels (here
    loaded from the cache, or compiled), no study's: a study or --show with it is
    refused in one line."""
    from pipeline.cli import main
    assert main(["compile", "--library", "-q"]) == 0
    for extra in ([str(STUDIES / "ov7_base.toml")], ["--show"]):
        assert main(["compile", "--library", *extra]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and "--library compiles the installation's kernels" in err
