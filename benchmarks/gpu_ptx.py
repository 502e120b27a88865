"""The sweep's CUDA kernels compiled here, without a GPU: PTX, then registers and spills.

    python benchmarks/gpu_ptx.py [--study NAME] [--cc 9.0] [--against DIR] [--smoke] [-o DIR]

numba-cuda (the ``[gpu]`` extra) compiles a kernel with NVVM, which needs no GPU.  It asks
the driver only for the device's compute capability (given here by ``--cc``: 9.0, an
H100) and finds libdevice beside NVRTC; where the toolkit has NVVM but no NVRTC (a CUDA
toolkit's compiler pieces alone, as on the machines without a GPU this project is built
on) libdevice is taken from the toolkit's ``nvvm/libdevice`` (CUDA_HOME, or
/usr/local/cuda*).  The toolkit's ``ptxas -v`` then says what ``bench_gpu.py`` reads on a
GPU: registers per thread, spill stores and loads and the stack frame of each kernel
(``pipeline.runs.gpu``: the whole careful path in one kernel, or split in two).

``--against DIR``: another checkout of the package (``git worktree add DIR REV``) compiled
the same way in a process of its own, and each kernel's PTX compared with this one's, line
for line but for the numbers numba gives its symbols: a change that should leave the GPU's
code alone is shown to, without a GPU.

--smoke (the suite): the default study's CUDA source written and its kernels' argument
types built; where numba-cuda, NVVM and ptxas are here, the smallest kernel
(``forces_kernel``) compiled and assembled too; elsewhere the table says what is missing.
Writes DIR/gpu_ptx.md.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import ROOT, STUDIES, write_table  # noqa: E402

KERNELS = ("sweep_kernel", "metrics_kernel", "forces_kernel")
SPLIT = {"metrics_kernel", "forces_kernel"}      # (forced, n_forced) after metrics


def toolkit() -> dict:
    """What compiling needs, found here: numba-cuda's version, NVVM's and
    libdevice's paths, ptxas; None for each missing."""
    from importlib.metadata import PackageNotFoundError, version
    try:
        found = {"numba-cuda": version("numba-cuda")}
    except PackageNotFoundError:
        found = {"numba-cuda": None}
    homes = [os.environ.get("CUDA_HOME") or "", *sorted(glob.glob("/usr/local/cuda*"))]
    pick = (lambda pattern: next((p for h in homes if h for p in sorted(glob.glob(
        os.path.join(h, pattern)))), None))
    found["libdevice"] = pick("nvvm/libdevice/libdevice*.bc")
    found["nvvm"] = pick("lib*/libnvvm.so*") or pick("nvvm/lib*/libnvvm.so*")
    found["ptxas"] = shutil.which("ptxas") or pick("bin/ptxas")
    return found


def _without_a_device(cc, found):
    """numba-cuda told what it would ask a GPU's driver and NVRTC for (a
    benchmark's means, not the package's: names inside numba-cuda)."""
    import collections

    from numba.cuda import cuda_paths
    from numba.cuda import dispatcher

    class Device:
        compute_capability = cc
    dispatcher.get_current_device = lambda: Device()
    os.environ.setdefault("NUMBA_FORCE_CUDA_CC", f"{cc[0]}.{cc[1]}")
    try:
        cuda_paths.get_cuda_paths()
    except Exception:           # (no NVRTC: libdevice's path given)
        path = collections.namedtuple("path", "by info")
        cuda_paths.get_cuda_paths._cached_result = {
            "nvrtc": path("none", None), "nvvm": path("found", found["nvvm"]),
            "libdevice": path("found", found["libdevice"]),
            "cudalib_dir": path("none", None), "static_cudalib_dir": path("none", None),
            "include_dir": path("none", None)}


def argument_types(problem, mod, split):
    """The numba types of a kernel's arguments as ``GpuSweep`` launches it
    (``pipeline.runs.gpu``: rows, the shared inputs, status, metrics, the split
    kernels' list of forced candidates, then each thread's work arrays)."""
    from numba import typeof, types

    from pipeline.kernels import sweep as ks
    try:
        from pipeline.runs.gpu import thread_work
    except ImportError:     # (a checkout from before it: GpuSweep._work_arrays's own list)
        def thread_work(p):
            from pipeline.kernels.continuation import work
            from pipeline.kernels.forces import force_work
            m, n, w = p.kernels, len(p.phis), p.dwell_w
            return [np.empty(n), np.empty(n + w + 1, np.int64), np.empty(n + w + 1, np.int64),
                    np.empty(n), *work(m.N_POINTS, m.N_GROUPS, m.N_TRIADS),
                    *force_work(m.N_BODIES, m.N_JOINTS, m.N_SLIDES + m.N_INPUTS),
                    *m.watch_work(m.N_WATCH, m.N_TRIADS)]
    rows = 4
    like = thread_work(problem)
    assert len(like) == len(mod.WORK_NAMES), (len(like), mod.WORK_NAMES)
    args = [np.empty((rows, problem.plan.par.shape[0])), problem.phis, 0.0, problem.tols,
            problem.settings(), problem.loads, np.zeros((1, 1)), np.empty(rows, np.int8),
            np.empty((rows, ks.N_METRICS))]
    if split:
        args += [np.empty(rows, np.int64), np.empty(1, np.int32)]
    args += [np.empty((rows,) + a.shape, a.dtype) for a in like]
    return tuple(types.float64 if isinstance(a, float) else typeof(np.ascontiguousarray(a))
                 for a in args)


def compile_kernels(study, kernels, cc, folder):
    """Each kernel of ``study``'s sweep compiled to PTX into ``folder`` (this
    process's package): {kernel: seconds}."""
    found = toolkit()
    _without_a_device(cc, found)
    from numba import cuda

    from pipeline.compiler import gpu_kernels_for
    from pipeline.runs.sweep import build_problem
    from pipeline.study.reader import load_study
    s = load_study(STUDIES / f"{study}.toml")
    problem = build_problem(s, s.sweep)
    mod = gpu_kernels_for(problem.plan, problem.rocker)
    seconds = {}
    for name in kernels:
        sig = argument_types(problem, mod, name in SPLIT)
        t = time.perf_counter()
        ptx, _ = cuda.compile_ptx(getattr(mod, name).py_func, sig, device=False, cc=cc)
        seconds[name] = time.perf_counter() - t
        (Path(folder) / f"{name}.ptx").write_text(ptx)
    return seconds


def assembled(ptx_file, ptxas, cc):
    """``ptxas -v`` of one kernel: registers, spill stores and loads, stack (bytes)."""
    r = subprocess.run([ptxas, f"-arch=sm_{cc[0]}{cc[1]}", "-v", "-o", os.devnull,
                        str(ptx_file)], capture_output=True, text=True, check=True)
    text = r.stderr + r.stdout
    num = (lambda pattern: max((int(m) for m in re.findall(pattern, text)), default=0))
    return {"registers": num(r"Used (\d+) registers"),
            "spill_stores": num(r"(\d+) bytes spill stores"),
            "spill_loads": num(r"(\d+) bytes spill loads"),
            "stack": num(r"(\d+) bytes stack frame")}


def same_code(a: str, b: str) -> bool:
    """Two kernels' PTX the same but for the numbers numba gives its modules,
    functions, constant-memory symbols and environments, and its order of the
    environments' declarations."""
    def norm(t):
        t = re.sub(r"pipeline_(mech|gpu)_[0-9a-f]{20}", "MOD", t)
        t = re.sub(r"B\d+v\d+B", "BvB", t)
        t = re.sub(r"(_cudapy_cmem\S*?)\$\d+", r"\1$N", t)
        lines = t.splitlines()
        return (sorted(x for x in lines if x.startswith(".common .global")),
                [x for x in lines if not x.startswith(".common .global")])
    return norm(a) == norm(b)


def in_process(root, study, kernels, cc, folder):
    """``compile_kernels`` in a fresh process of the package at ``root``."""
    # (this file by its path: the other checkout may have none; its package first)
    code = (f"import sys, json, runpy\n"
            f"g = runpy.run_path({__file__!r}, run_name='gpu_ptx')\n"
            f"assert 'pipeline' not in sys.modules\n"
            f"sys.path.insert(0, {str(root)!r})\n"
            f"print(json.dumps(g['compile_kernels']({study!r}, {list(kernels)!r}, "
            f"{tuple(cc)!r}, {str(folder)!r})))")
    env = dict(os.environ, PYTHONPATH=str(root))
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                       cwd=root)
    if r.returncode:
        raise RuntimeError(f"compiling in {root} failed:\n{r.stderr[-3000:]}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", default="ov7_synthesis", help="a sweep study of studies/")
    ap.add_argument("--cc", default="9.0", help="the GPU's compute capability (9.0: H100)")
    ap.add_argument("--against", help="another checkout: its kernels' PTX compared")
    ap.add_argument("--smoke", action="store_true", help="the smallest kernel only")
    ap.add_argument("-o", "--out", default=str(ROOT / "results" / "bench"))
    a = ap.parse_args(argv)
    cc = tuple(int(x) for x in a.cc.split("."))
    kernels = ("forces_kernel",) if a.smoke else KERNELS
    found = toolkit()
    lines = ["# The sweep's CUDA kernels compiled without a GPU", "",
             f"study `{a.study}`, compute capability {cc[0]}.{cc[1]}; found: "
             + ", ".join(f"{k} {v or 'missing'}" for k, v in found.items()), ""]
    missing = [k for k, v in found.items() if not v]
    if missing:
        # the argument types still built, so that the script cannot rot where it cannot compile
        from pipeline.compiler import kernels_for
        from pipeline.compiler.cuda_source import gpu_source
        from pipeline.runs.sweep import build_problem
        from pipeline.study.reader import load_study
        s = load_study(STUDIES / f"{a.study}.toml")
        problem = build_problem(s, s.sweep)
        src = gpu_source(kernels_for(problem.plan, problem.rocker).__name__)
        assert all(f"def {k}(" in src for k in KERNELS)
        lines.append(f"Not compiled: {', '.join(missing)} missing (`pip install -e "
                     "\".[gpu]\"`; NVVM, libdevice and ptxas come with a CUDA toolkit).")
        write_table(a.out, "gpu_ptx.md", "\n".join(lines) + "\n")
        return 0
    with tempfile.TemporaryDirectory() as d:
        here, there = Path(d) / "here", Path(d) / "against"
        here.mkdir()
        secs = in_process(ROOT, a.study, kernels, cc, here)
        other = {}
        if a.against:
            there.mkdir()
            other = in_process(Path(a.against).resolve(), a.study, kernels, cc, there)
        lines += ["| kernel | PTX compile | registers | spill stores | spill loads | stack |"
                  + (" PTX against `" + a.against + "` |" if a.against else ""),
                  "|---|---|---|---|---|---|" + ("---|" if a.against else "")]
        for k in kernels:
            r = assembled(here / f"{k}.ptx", found["ptxas"], cc)
            row = (f"| {k} | {secs[k]:.1f} s | {r['registers']} | {r['spill_stores']} B | "
                   f"{r['spill_loads']} B | {r['stack']} B |")
            if a.against:
                same = same_code((here / f"{k}.ptx").read_text(), (there / f"{k}.ptx").read_text())
                row += (" the same" if same else " differs") + f" ({other[k]:.1f} s) |"
            lines.append(row)
    write_table(a.out, "gpu_ptx.md", "\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
