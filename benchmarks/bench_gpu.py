"""The default study's full-metrics sweep on the GPU against the CPU path on all
cores of the same machine, same process, same drawn candidates.

* kernel only: candidates/s of the evaluation alone (GPU: one batch already on
  the device, results left there; CPU: ``SweepProblem.evaluate_rows`` on all
  cores), best of ``--repeat``; on the GPU for each of its stages
  (``pipeline.runs.gpu.STAGES``: the careful path in one kernel, or split in two,
  the force stage only for the candidates that reach it), with each kernel's
  registers and local memory per thread;
* end to end: ``run_sweep`` into an HDF5 file (drawing, transfers, journal,
  HDF5; ``--store feasible`` by default, as the README's 10^7 command), with
  --device gpu and --device cpu, for each ``--sizes`` (default 10^6 and 10^7
  candidates; the CPU end to end only up to --cpu-max, its throughput is flat
  in the size; a size that the last rate says would take over --max-seconds
  is left out, saying so), the GPU on the stages that were faster kernel only.

Compile time is reported apart (the first evaluation of each path).  Where the
host's time goes end to end: the GPU run at ``--profile-size`` (10^6) again under
cProfile, its functions by own time (the profiled run is not the timed one).  Exits
with a message, and status 0, where numba.cuda finds no usable GPU (see
``pipeline doctor``); under NUMBA_ENABLE_CUDASIM=1 it runs with tiny sizes as a
smoke test of this script (the simulator's speed means nothing).

    python benchmarks/bench_gpu.py [--sizes 1000000 10000000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import STUDIES, hardware  # noqa: E402
from pipeline.kernels import sweep as ks  # noqa: E402
from pipeline.study.reader import load_study  # noqa: E402
from pipeline.runs.sweep import build_problem, run_sweep  # noqa: E402
from pipeline.study.sampling import draw_checked  # noqa: E402
from pipeline.study.sweep_spec import parameter_rows  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1_000_000, 10_000_000])
    ap.add_argument("--cpu-max", type=int, default=1_000_000)
    ap.add_argument("--kernel-rows", type=int, default=65536)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--chunk-size", type=int, default=1_000_000)
    ap.add_argument("--store", choices=("all", "feasible"), default="feasible")
    ap.add_argument("--max-seconds", type=float, default=float("inf"))
    ap.add_argument("--profile-size", type=int, default=1_000_000,
                    help="end to end on the GPU again at this size under cProfile (0: not)")
    ap.add_argument("--smoke", action="store_true",
                    help="that it runs, at the simulator's tiny sizes (the test suite runs it "
                         "under NUMBA_ENABLE_CUDASIM=1)")
    a = ap.parse_args(argv)
    from pipeline.compiler.cuda_device import SIMULATOR
    from pipeline.runs import gpu
    p = gpu.probe()
    if p["missing"]:
        print(f"no usable GPU: missing {p['missing']}")
        return 0
    if SIMULATOR or a.smoke:
        a.sizes, a.cpu_max, a.kernel_rows, a.repeat, a.chunk_size = [200], 200, 64, 1, 100
        a.profile_size = min(a.profile_size, 200)
    print(hardware())
    print(f"device: {gpu.describe(p)}")
    study = load_study(STUDIES / "ov7_synthesis.toml")
    spec = study.sweep
    cpu = build_problem(study, spec)
    dev = build_problem(study, spec, device="gpu")
    x, _ = draw_checked(spec.with_candidates(a.kernel_rows), 0) if a.kernel_rows <= \
        spec.chunk_size else _draws(spec, a.kernel_rows)
    pars = np.ascontiguousarray(parameter_rows(cpu.plan, spec, x))

    t = time.perf_counter()
    cpu.evaluate_rows(pars[:64])
    print(f"compile, CPU kernels: {time.perf_counter() - t:.1f} s")
    kernels = {"whole": ("sweep_kernel",), "split": ("metrics_kernel", "forces_kernel")}
    on = {}
    for stages in gpu.STAGES:
        t = time.perf_counter()
        try:    # (a variant that fails on this device is said, the other still measured)
            g = gpu.GpuSweep(dev, batch=max(a.kernel_rows, 1), stages=stages)
            g.evaluate_rows(pars[:64])
        except Exception as e:
            print(f"compile, CUDA kernels ({stages}): failed ({type(e).__name__}: "
                  f"{' '.join(str(e).split())[:300]})", flush=True)
            continue
        on[stages] = g
        print(f"compile, CUDA kernels ({stages}): {time.perf_counter() - t:.1f} s")
        for name in kernels[stages]:
            print(_occupancy(name, getattr(g.mod, name)))

    best_c = min(_timed(lambda: cpu.evaluate_rows(pars)) for _ in range(a.repeat))
    status, metrics = cpu.evaluate_rows(pars)
    print(f"force stage: {int((metrics[:, ks.M_FORCES_DONE] == 1).sum()):,} of "
          f"{len(pars):,} candidates reach it, {int((status != 0).sum()):,} fail")
    best_g = {}
    for stages, g in on.items():
        best_g[stages] = g.kernel_only(pars, repeats=a.repeat)
        print(f"kernel only ({stages}), {len(pars):,} candidates: CPU "
              f"{len(pars) / best_c:,.0f}/s, GPU {len(pars) / best_g[stages]:,.0f}/s, ratio "
              f"{best_c / best_g[stages]:.1f}x", flush=True)
    gpu.DEFAULT_STAGES = min(best_g, key=best_g.get)
    print(f"stages end to end: {gpu.DEFAULT_STAGES} (the faster kernel only)")

    rate = {}
    with tempfile.TemporaryDirectory() as tmp:
        for n in a.sizes:
            row = [f"end to end, {n:,} candidates, store {a.store}:"]
            for device in ("gpu", "cpu"):
                if device == "cpu" and n > a.cpu_max:
                    continue
                if device in rate and n / rate[device] > a.max_seconds:
                    row.append(f"{device.upper()} left out (about {n / rate[device]:.0f} s "
                               f"expected, over --max-seconds {a.max_seconds:g})")
                    continue
                out = Path(tmp) / f"{device}{n}.h5"
                t = time.perf_counter()
                run_sweep(study, out, candidates=n, chunk_size=min(a.chunk_size, n),
                          device=device, progress=False, store=a.store)
                s = time.perf_counter() - t
                rate[device] = n / s
                row.append(f"{device.upper()} {s:.1f} s ({n / s:,.0f}/s)")
                out.unlink()
            print(" ".join(row), flush=True)
        if a.profile_size:
            _profiled(study, Path(tmp) / "profiled.h5", a.profile_size,
                      min(a.chunk_size, a.profile_size), a.store)
    return 0


def _profiled(study, out, n, chunk_size, store):
    """The GPU run end to end once more under cProfile: where the main thread's
    time goes (transfers, waiting for the kernel and the drawing thread, the
    journal, HDF5), the top functions by their own time."""
    import cProfile
    import pstats
    prof = cProfile.Profile()
    t = time.perf_counter()
    prof.runcall(run_sweep, study, out, candidates=n, chunk_size=chunk_size, device="gpu",
                 progress=False, store=store)
    print(f"profiled end to end, {n:,} candidates on the GPU: {time.perf_counter() - t:.1f} s "
          "(under cProfile; the main thread's functions, its waits for the drawing thread "
          "and the device as lock acquire), by own time:")
    stats = pstats.Stats(prof)
    rows = sorted(stats.stats.items(), key=lambda kv: -kv[1][2])[:15]
    for (file, line, name), (_, calls, own, total, _) in rows:
        where = f"{Path(file).name}:{line}" if line else file
        print(f"  own {own:7.2f} s  total {total:7.2f} s  calls {calls:8d}  {name} ({where})")


def _occupancy(name, kernel):
    """Registers and local memory per thread of the compiled kernel (what limits
    how many threads a multiprocessor holds), where numba.cuda says."""
    try:
        regs, local = kernel.get_regs_per_thread(), kernel.get_local_mem_per_thread()
        if isinstance(regs, dict):     # one entry per compiled signature
            regs, local = max(regs.values()), max(local.values())
        return (f"CUDA kernel {name}: {regs} registers per thread, "
                f"{local} bytes of local memory per thread")
    except Exception as e:      # the simulator, or an older numba.cuda
        return f"CUDA kernel {name}: registers per thread not known here ({type(e).__name__})"


def _draws(spec, n):
    """n drawn candidates, chunk by chunk (the sweep's own draws)."""
    parts = []
    for c in range(-(-n // spec.chunk_size)):
        parts.append(draw_checked(spec, c)[0])
    return np.concatenate(parts)[:n], None


def _timed(f):
    t = time.perf_counter()
    f()
    return time.perf_counter() - t


if __name__ == "__main__":
    sys.exit(main())
