"""Session set-up shared by every test.

* Compile caches in pytest's temporary folder: the generated kernel modules
  (``PIPELINE_CACHE_DIR``, default ``~/.cache/pipeline``) and numba's compiled
  code (``NUMBA_CACHE_DIR``, default the package's ``__pycache__``) go to one
  folder (``compile_cache`` below), set in ``os.environ`` before ``pipeline`` or
  numba is imported, so every test and every subprocess a test starts (the CLI,
  Dask worker processes, the GPU simulator) shares one warm cache and nothing is
  written into the checkout or the home folder but the package's bytecode
  (``package_bytecode`` below, where Python writes none itself; the libraries'
  goes beside them: ``library_bytecode``).
* Hypothesis runs the registered profile ``ci`` (derandomized, no deadline, no
  example database): the same examples on every run and machine, no
  wall-clock limit on a loaded machine.  ``HYPOTHESIS_PROFILE=dev`` draws
  fresh examples.
* ``tests/`` is on ``sys.path`` for the helpers package ``support``.
"""

import os
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))

STUDIES = ROOT / "studies"
REFERENCE = ROOT.parent / "shared" / "reference"

# registered and loaded at import, before any test module is collected: a test's
# own @settings(...) inherits every field it does not set from this profile
settings.register_profile(
    "ci", derandomize=True, deadline=None, database=None, print_blob=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.register_profile("dev", deadline=None, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


@pytest.hookimpl(trylast=True)   # after pytest's tmpdir plugin has set up its factory
def pytest_configure(config):
    """Hypothesis's home (its constants cache) and the compile caches in
    pytest's temporary folder (the factory of the fixture tmp_path_factory)."""
    from hypothesis import configuration
    base = config._tmp_path_factory.getbasetemp()
    configuration.set_hypothesis_home_dir(base / "hypothesis")
    if "pipeline" in sys.modules or "numba" in sys.modules:
        raise pytest.UsageError("pipeline or numba was imported before tests/conftest.py "
                                "could point their caches at pytest's temporary folder")
    if os.environ.get("PYTEST_XDIST_WORKER"):
        # a worker of pytest-xdist: the controller chose the cache (its environment
        # is the worker's), so every worker shares one
        cache = Path(os.environ["PIPELINE_TEST_COMPILE_CACHE"])
    else:
        cache = compile_cache(config, base)
        os.environ["PIPELINE_TEST_COMPILE_CACHE"] = str(cache)
        package_bytecode()
    os.environ["PIPELINE_CACHE_DIR"] = str(cache / "modules")
    os.environ["NUMBA_CACHE_DIR"] = str(cache / "numba")
    # no compile beside a run (pipeline.compiler.beside): the suite's two workers keep
    # both cores busy already; tests/compiler/test_compiler.py tests it on its own
    os.environ["PIPELINE_COMPILE_BESIDE"] = "0"
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        library_bytecode()


# What the suite's processes import, in two groups of about the same cost (a
# process each): the command line and the libraries its commands and the tests bring
IMPORTED = (("pipeline.cli", "pipeline.api", "pipeline.runs.sweep", "pipeline.runs.search",
             "numba", "scipy.stats", "scipy.optimize", "scipy.interpolate", "tqdm",
             "tqdm.contrib.logging", "pymoo.optimize", "pymoo.algorithms.moo.nsga2",
             "hypothesis.strategies", "xdist", "mpmath", "h5py._hl.dims"),
            ("pipeline.views.page", "matplotlib.pyplot", "matplotlib.animation",
             "matplotlib.backends.backend_agg", "PIL.features", "PIL.PngImagePlugin",
             "PIL.JpegImagePlugin", "PIL.GifImagePlugin", "PIL.BmpImagePlugin",
             "PIL.PpmImagePlugin", "plotly.graph_objects", "plotly.offline", "jinja2",
             "dask.distributed", "xarray", "h5netcdf", "nbclient", "nbformat",
             "ipykernel.kernelapp", "ezdxf", "pyarrow.parquet", "pyarrow.pandas_compat",
             "pandas", "sklearn.ensemble", "sklearn.inspection", "sklearn.model_selection",
             "sklearn.cluster"))


# (numba imports its typing and lowering registries at its first compile or cache load)
_IMPORT = """
import importlib, sys
for name in sys.argv[1:]:
    try:
        importlib.import_module(name)
    except ImportError:     # (a library the suite then skips or reports)
        pass
if "numba" in sys.modules:
    from numba.core.registry import cpu_target
    cpu_target.typing_context.refresh()
    cpu_target.target_context.refresh()
"""


def library_bytecode():
    """The bytecode of the modules the suite's processes import (``IMPORTED``, and
    what they import) written by importing them once, where Python writes none
    (PYTHONDONTWRITEBYTECODE, as in some sandboxes) and the libraries were
    installed without theirs (``pip install --no-compile``, as the README's test
    command installs them: pip's compiling of every file of every library took
    55-60 s of a two-minute install here, importing what the suite uses takes
    14-15 s on two cores): otherwise every worker and every process a test starts
    would compile the libraries' sources again.  Bytecode that is there already is
    only read, and where SciPy's and Plotly's are there this does nothing."""
    import subprocess
    if not sys.dont_write_bytecode or all(_has_bytecode(name) for name in ("scipy", "plotly")):
        return
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    runs = [subprocess.Popen([sys.executable, "-c", _IMPORT, *group],
                             env=env, cwd=ROOT, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)
            for group in IMPORTED]
    for r in runs:
        r.wait()


def _has_bytecode(package):
    """Whether the package's ``__init__`` has its bytecode (found, not imported)."""
    import importlib.util
    spec = importlib.util.find_spec(package)
    return spec is not None and bool(spec.cached) and os.path.exists(spec.cached)


def package_bytecode():
    """The package's modules byte-compiled into its ``__pycache__`` folders (ignored by
    git), as pip writes them for an installed copy; an editable install leaves that to
    Python's first import, which writes nothing where PYTHONDONTWRITEBYTECODE is set (as
    in some sandboxes): every worker and every child process a test starts (about 120)
    then compiled the package's source again, 0.2-0.3 s each.  A module changed later is
    compiled from its source as before (its bytecode records the source's time and
    size); compileall leaves bytecode that is up to date as it is."""
    if sys.dont_write_bytecode:
        import compileall
        compileall.compile_dir(ROOT / "pipeline", quiet=2)


def compile_cache(config, base):
    """The compile cache of this session.  By default one folder in pytest's
    temporary root (/tmp/pytest-of-USER/, beside the numbered session folders,
    which pytest prunes while this one stays): the session's tests and
    subprocesses share it, and the next session, of any checkout, starts warm (a
    cold start compiles every mechanism of the suite: about 20 minutes on two
    cores).  Generated modules are named by the hash of their source, numba keeps
    the code of each checkout's kernels under that checkout's own path and drops
    it when a kernel source changes, so a warm cache is never a stale one.  PIPELINE_TEST_CACHE=session: a fresh folder inside this session's
    temporary folder; PIPELINE_TEST_CACHE=DIR: that folder.  With --basetemp
    the session's folder is used."""
    choice = os.environ.get("PIPELINE_TEST_CACHE", "")
    if choice == "session" or (not choice and config.option.basetemp):
        return base / "compile-cache"
    if choice:
        return Path(choice)
    return base.parent / "pipeline-compile-cache"


def pytest_collection_modifyitems(config, items):
    """The test files that read the session's sweep (``synthesis_sweep``), but the
    first, out of the first half of the files (``support.suite_order``: a worker
    given one at the start waited on the sweep's lock, its core idle).  Every
    worker collects the same order (xdist checks)."""
    from support.suite_order import by_file, files_in_order, sweep_readers
    files = by_file(items)
    order = files_in_order(list(files), set(sweep_readers(files)))
    items[:] = [item for name in order for item in files[name]]


@pytest.fixture(scope="session")
def studies():
    return STUDIES


@pytest.fixture(scope="session")
def reference_dir():
    if not REFERENCE.exists():
        pytest.fail(f"the shared reference tables are missing: {REFERENCE}")
    return REFERENCE


# The main job's study (studies/ov7_synthesis.toml), swept once per session with
# fewer candidates (support.sweep_helpers.SYNTHESIS_N); tests read this file and
# copy it (support.sweep_helpers.copy_of) before changing it (analyze, resume, ...).
@pytest.fixture(scope="session")
def synthesis_sweep(tmp_path_factory):
    """Path of the session's sweep of the main job's study.  Read it; copy it to
    change it.  Under pytest-xdist the workers share one: the first to ask runs
    it in the session's common folder, the others wait on the lock and read it."""
    import fcntl

    import h5py

    from pipeline.study.reader import load_study
    from pipeline.runs.sweep import run_sweep
    from support.sweep_helpers import SYNTHESIS_CHUNK, SYNTHESIS_N
    common = session_folder(tmp_path_factory) / "synthesis_sweep"
    common.mkdir(exist_ok=True)
    out = common / "ov7_synthesis.h5"
    with open(common / "lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not out.exists():
            run_sweep(load_study(STUDIES / "ov7_synthesis.toml"), out, candidates=SYNTHESIS_N,
                      chunk_size=SYNTHESIS_CHUNK, progress=False)
    with h5py.File(out, "r") as f:
        assert f["candidates/feasible"][()].sum() >= 50, "the sweep needs feasible designs"
    return out


def session_folder(tmp_path_factory):
    """The folder of this test session that every pytest-xdist worker shares
    (each worker's own temporary root is a folder inside it)."""
    base = tmp_path_factory.getbasetemp()
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
