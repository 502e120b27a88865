"""Shared pieces of the benchmarks: the hardware line, timing with warm-up,
and batch inputs built from the studies."""

from __future__ import annotations

import math
import os
import platform
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
STUDIES = ROOT / "studies"


def hardware():
    """The machine in words: the CPU with the core LLVM compiles for and its widest
    vectors (the ratios to the C yardstick differ with them: on one 2-core AMD EPYC
    with AVX-512 the main job ran at 0.70x of triad_full per core, on another
    without it at 0.54x, the same code), the cores, numba's threads, Python."""
    cpu, flags = "unknown CPU", set()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name") and cpu == "unknown CPU":
                cpu = line.split(":", 1)[1].strip()
            elif line.startswith("flags") and not flags:
                flags = set(line.split(":", 1)[1].split())
    except OSError:
        pass
    import numba
    from llvmlite import binding as llvm
    isa = ("AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags
           else "AVX" if "avx" in flags else None)
    core = ", ".join(x for x in (llvm.get_host_cpu_name(), isa) if x)
    return (f"{cpu} ({core}), {os.cpu_count()} cores, numba {numba.__version__} "
            f"({numba.get_num_threads()} threads), Python {platform.python_version()}")


def best_of(fn, repeat=3):
    """Steady-state seconds: the best of ``repeat`` calls (call once before to compile)."""
    best = math.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def first_call(fn):
    """Seconds of the first call (compile or cache load + one run)."""
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def perturbed_rows(plan, names, n, spread=0.05, seed=0):
    """n parameter rows: the reference row with ``names`` scaled by 1 +- spread."""
    rng = np.random.default_rng(seed)
    pars = np.repeat(plan.par[None, :], n, axis=0)
    for name in names:
        k = plan.param(name)
        pars[:, k] *= 1.0 + rng.uniform(-spread, spread, n)
    return np.ascontiguousarray(pars)


def batch_runner(study, pars, positions, order, with_forces):
    """A zero-argument function running one revolution of every row of ``pars``."""
    from pipeline.solve.scene import batch_revolutions

    def run():
        return batch_revolutions(study, pars, positions, order, with_forces)
    return run


def smoke_main(run, doc, written):
    """The command line of a benchmark with a smoke mode: ``run(smoke, out)``
    (``doc``: the module's text; ``written``: what it writes into -o DIR)."""
    import argparse
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--smoke", action="store_true", help="tiny sizes (seconds), for the suite")
    ap.add_argument("-o", "--output", help=f"folder for {written} (default results/bench/)")
    a = ap.parse_args()
    run(a.smoke, a.output)


def write_table(folder, name, text):
    """A benchmark's table printed, and written to ``folder``/``name`` (made if new)."""
    from pipeline.base.files import write_text
    print(text)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    write_text(folder / name, text)


def forget_mechanisms(cache: Path) -> None:
    """Every generated module and its compiled code gone (numba's cache beside
    the module, or under NUMBA_CACHE_DIR by the module's folder); the plan
    path's stay."""
    places = [cache, cache / "__pycache__"]
    if os.environ.get("NUMBA_CACHE_DIR"):       # (numba: a folder per source folder)
        places += Path(os.environ["NUMBA_CACHE_DIR"]).glob(f"{cache.name}_*")
    for place in places:
        for f in place.glob("pipeline_mech_*"):
            f.unlink()


def fresh_mechanism_env(**settings):
    """The runs' environment: this one with ``settings``, bytecode written."""
    env = dict(os.environ, **settings)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def beside_done(limit=120.0):
    """Wait until no process compiles beside a run (pipeline.compiler.beside,
    which a first sweep starts and which may outlive it by a moment): the next
    study's compile then has the machine to itself, as it has after a run.
    (Linux: /proc; elsewhere no wait.)"""
    end = time.perf_counter() + limit
    while time.perf_counter() < end:
        busy = False
        for cmd in Path("/proc").glob("[0-9]*/cmdline"):
            try:
                busy = busy or b"pipeline.compiler.beside" in cmd.read_bytes()
            except OSError:
                pass
        if not busy:
            return
        time.sleep(0.2)
