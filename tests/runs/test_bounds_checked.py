"""Every shipped sweep and search runs a small sweep with every array index
checked (issue 27), so that an out-of-bounds read or write in a kernel fails
loudly instead of reading garbage or corrupting memory.

How the indices are checked: the run's process has ``NUMBA_DISABLE_JIT=1``, so
the generated kernels and the library kernels run as the Python they are
written in, on NumPy arrays, and NumPy checks every index (a negative one
wraps, as in numba with its bounds checking on).  numba's own
``NUMBA_BOUNDSCHECK=1`` would check the compiled code, but numba's cache key
ignores that flag: compiled checked code would need a cache of its own and a
cold compile of every mechanism (20-45 s each here), minutes the suite does not
have.  The same source runs either way; the runs below take 2-3 s each.

What is run: ``pipeline run`` of each sweep study at 16 candidates (two lane
blocks: the lock-step path, then the careful path where a lane needs it) and
each search study at a population of 16 for two generations (the robust
search with 8 builds per design).  The last test shows that the check bites:
a kernel handed a status array one row short fails the run, naming the
IndexError.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from support.checkout import child_env

pytestmark = pytest.mark.filterwarnings("ignore")

CANDIDATES = 16


def sweep_studies(studies):
    return sorted(p for p in studies.glob("*.toml")
                  if re.search(r'^kind = "sweep"', p.read_text(), re.M))


def small_search(text):
    """A search study's text at population 16, two generations, 8 builds."""
    text = re.sub(r"^population = \d+", "population = 16", text, flags=re.M)
    text = re.sub(r"^evaluations = \d+", "evaluations = 32", text, flags=re.M)
    return re.sub(r"^builds = \d+", "builds = 8", text, flags=re.M)


def checked_run(argv, cwd, prelude=""):
    """``pipeline *argv`` in a fresh process whose kernels run with every index
    checked (NUMBA_DISABLE_JIT: NumPy's checks)."""
    code = prelude + "import sys\nfrom pipeline.cli import main\nsys.exit(main(sys.argv[1:]))\n"
    return subprocess.run([sys.executable, "-c", code, *map(str, argv)], cwd=cwd,
                          env=child_env(NUMBA_DISABLE_JIT="1"), capture_output=True, text=True,
                          timeout=600)


SHIPPED = sorted(p.stem for p in sweep_studies(Path(__file__).resolve().parents[2] / "studies"))


def test_every_sweep_study_is_run_here(studies):
    """The runs below are every sweep study of studies/ (read when the tests
    are collected, so a new one is run too); these at least."""
    assert {p.stem for p in sweep_studies(studies)} == set(SHIPPED)
    assert {"ov7_synthesis", "ov7_synthesis_law", "ov7_search", "ov7_robust_search",
            "cam_rocker_input_sweep", "ov7_class3_slider_sweep", "slotted_rocker_prp_sweep",
            "ppr_cross_slide_sweep"} <= set(SHIPPED), SHIPPED


@pytest.mark.parametrize("name", SHIPPED)
def test_a_small_sweep_with_every_index_checked(name, studies, tmp_path):
    study = studies / f"{name}.toml"
    text = study.read_text()
    assert study in sweep_studies(studies)
    if re.search(r"^\[search\]", text, re.M):
        study = tmp_path / f"{name}.toml"
        study.write_text(small_search(text))
        argv, n = ["run", study, "-o", tmp_path / "r.h5", "-q"], 32
    else:
        argv, n = ["run", study, "-o", tmp_path / "r.h5", "-q", "--candidates", CANDIDATES], \
            CANDIDATES
    r = checked_run(argv, tmp_path)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "Traceback" not in r.stderr and "Error" not in r.stderr, r.stderr[-3000:]
    with h5py.File(tmp_path / "r.h5", "r") as f:
        status = f["candidates/status"][()]
        assert status.shape == (n,)
        assert (status == 0).any()           # the kernels ran whole candidates through
        feasible = f["candidates/feasible"][()].astype(bool)
        for objective in f.attrs["objectives"]:
            assert np.isfinite(f[f"metrics/{objective}"][()][feasible]).all(), objective
        assert feasible.any()                # and the force stage too


def test_an_index_past_an_array_fails_the_run_loudly(studies, tmp_path):
    """The check bites: the kernel gets a status array one row short (as a
    kernel that wrote one row too far would), and the run fails naming the
    IndexError instead of writing past the array."""
    prelude = ("import pipeline.compiler.parallel as par\n"
               "real = par.run_rows\n"
               "def short(kernel, pars, *args, **kw):\n"
               "    args = list(args)\n"
               "    args[-2] = args[-2][:-1]          # status: one row short\n"
               "    return real(kernel, pars, *args, **kw)\n"
               "par.run_rows = short\n")
    r = checked_run(["run", studies / "ov7_synthesis.toml", "-o", tmp_path / "r.h5", "-q",
                     "--candidates", CANDIDATES], tmp_path, prelude)
    assert r.returncode != 0
    assert "IndexError" in r.stderr and "out of bounds" in r.stderr, r.stderr[-3000:]
