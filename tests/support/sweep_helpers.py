"""Shared helpers for the sweep tests."""

import h5py
import numpy as np

# the session's sweep of the main job's study (tests/conftest.py: synthesis_sweep)
SYNTHESIS_N, SYNTHESIS_CHUNK = 3000, 1000

VOLATILE = {"created", "wall_time_s", "engine"}


def copy_of(src, folder, name=None):
    """A copy of the file ``src`` in ``folder`` (made if needed), named ``name``
    (default: src's name); returns its path."""
    import shutil
    from pathlib import Path
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    dst = folder / (name or Path(src).name)
    shutil.copy(src, dst)
    return dst
REFERENCES = {"DIMENSION_LIST", "REFERENCE_LIST"}   # dimension-scale object references


def assert_same_results(a, b):
    """Every dataset and attribute of two results files equal (bit for bit),
    except the run's date, duration and engine."""
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        names_a, names_b = [], []
        fa.visit(names_a.append)
        fb.visit(names_b.append)
        assert names_a == names_b
        for key in set(fa.attrs) | set(fb.attrs):
            if key not in VOLATILE:
                assert np.array_equal(np.asarray(fa.attrs[key]), np.asarray(fb.attrs[key])), key
        for n in names_a:
            oa, ob = fa[n], fb[n]
            for key in oa.attrs:
                if key in REFERENCES:   # object references: the names they point to
                    continue
                assert np.array_equal(np.asarray(oa.attrs[key]), np.asarray(ob.attrs[key])), (n, key)
            if isinstance(oa, h5py.Dataset):
                assert [[s.name for s in d.values()] for d in oa.dims] == \
                    [[s.name for s in d.values()] for d in ob.dims], n
            if isinstance(oa, h5py.Dataset):
                np.testing.assert_array_equal(oa[()], ob[()], err_msg=n)


def run_and_analyze(study_path, out, candidates):
    """`pipeline run` of a sweep study with ``candidates`` into ``out``, then
    `pipeline analyze`; returns the loaded study and ``out``."""
    from pipeline.cli import main
    from pipeline.study.reader import load_study
    assert main(["run", str(study_path), "-o", str(out), "--candidates", str(candidates),
                 "-q"]) == 0
    assert main(["analyze", str(out), "-q"]) == 0
    return load_study(study_path), out


def assert_fronts_are_the_brute_force_rank(path, min_feasible=20):
    """The fronts of a sweep's stored analysis are those of a brute-force
    dominance test over its feasible candidates, and the knee is on front 1."""
    from support.naive_pareto import brute_force_rank
    from pipeline.analysis.fronts import read_analysis, read_sweep
    from pipeline.results.storage import open_results
    data = read_sweep(path)
    with open_results(path, "sweep") as f:
        an = read_analysis(f)
    assert data.feasible.sum() >= min_feasible
    np.testing.assert_array_equal(an.rank, brute_force_rank(data.F, data.feasible))
    assert (an.rank[an.front1] == 1).all() and an.rank[an.knee] == 1


# A `pipeline` command in a child process that holds still (never finishes) once
# the run's journal has saved a given number of chunks: a kill -9 then always
# lands in a running run, however fast or loaded the machine.  Every journal
# entry is written to a temporary name and renamed (files.replacing), so the
# count is taken at os.replace.
_HOLD_AFTER = r"""
import os, re, sys, threading
from pipeline.cli import main
real, seen, k = os.replace, [0], int(sys.argv[1])
def replace(src, dst, *a, **kw):
    real(src, dst, *a, **kw)
    if re.search(r"(chunk|block)_[\d_]+\.npz$", str(dst)):
        seen[0] += 1
        if seen[0] >= k:
            threading.Event().wait()        # hold here, mid-run, until killed
os.replace = replace
sys.exit(main(sys.argv[2:]))
"""


def kill_9_after_chunks(argv, parts, chunks, hang_guard_s=900):
    """Run `pipeline *argv` in a child process, wait until its journal folder
    ``parts`` holds ``chunks`` entries, chunks or blocks (the child then holds), kill -9 it and
    return the number of entries left.  ``hang_guard_s`` only stops a child
    that never gets there from hanging the suite (no timing is asserted)."""
    import os
    import signal
    import subprocess
    import sys
    import time
    proc = subprocess.Popen([sys.executable, "-c", _HOLD_AFTER, str(chunks), *map(str, argv)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    guard = time.monotonic() + hang_guard_s
    try:
        while _entries(parts) < chunks:
            assert proc.poll() is None, proc.stderr.read().decode()[-3000:]
            assert time.monotonic() < guard, "the child run never saved its chunks"
            time.sleep(0.05)
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
    assert proc.returncode == -signal.SIGKILL
    return _entries(parts)


def _entries(parts):
    """Files of a journal: a sweep's chunks, a search's blocks of generations."""
    return len(list(parts.glob("chunk_*.npz"))) + len(list(parts.glob("block_*.npz")))
