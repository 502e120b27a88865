"""Sweeps on an NVIDIA GPU: the mechanism's generated kernels compiled by
numba.cuda (``pipeline.compiler.cuda_source``), fed in batches from the host.

* ``probe()`` says what this machine has: the package (numba-cuda, from the
  ``[gpu]`` extra), the driver, the toolkit (NVVM) and the devices;
  ``require()`` turns a missing piece into a ``GpuUnavailable`` naming it, and
  ``choose(device)`` resolves ``--device cpu|gpu|auto``.
* ``GpuSweep(problem).evaluate_rows(pars)``: status and metric rows of every
  parameter row, in batches of ``batch`` threads on two CUDA streams, so that
  one batch's transfers overlap the other's kernel.  Device memory is bounded
  by the batch size (two sets of per-thread work arrays); the host's by the
  sweep's chunk.

The numbers: every thread runs the careful path (``settle``) of the CPU
module, in one kernel or (``stages="split"``) in two: every candidate's
positions and metrics, then the force stage of the candidates that reach it,
listed by the first kernel, one thread each (the same functions on the same
inputs: the same numbers, tested).  On the CPU most candidates take the
lock-step lanes, which vouch for a candidate only where they agree with the
careful path; statuses are the same, and metrics agree to rounding except two,
by construction:
``newton_mean`` (the lanes take a fixed number of Newton steps per position,
the careful path counts the steps it took) and the class III ``margin``,
which is det J at each path's own Newton iterate (the careful path stops at
a residual of tols[T_NEWTON_TOL] = 1e-12, the lanes after two steps), a
difference bounded by the closure tolerance over the margin.  A lane that
flagged itself and met no failure is spliced: its careful window solved to
near rounding, so its metrics differ from the careful path's by that path's
own closure error (no further from the exact numbers).  On a real GPU,
NVVM contracts a*b + c into FMA and uses its own libm (sin, cos, atan2 to
1-2 ulp): last-digit differences, magnified near singular positions as on
any two CPUs.  ``tests/runs/test_gpu.py`` checks all of this under numba's CUDA
simulator, which runs the same kernel on the CPU.
"""

from __future__ import annotations

import logging
import math
import os

import numpy as np

log = logging.getLogger("pipeline")

# first: cuda_device's numpy fix precedes numba.cuda's import
from ..compiler.cuda_device import SIMULATOR, launching  # noqa: E402
from numba import cuda                  # noqa: E402

THREADS = 128            # threads per CUDA block
BATCH = 1 << 16          # threads per launch (device memory: two sets of work arrays)
STREAMS = 2
# the careful path in one kernel ("whole"), or in two ("split": every candidate's
# positions and metrics, then the force stage of those that reach it alone,
# gathered); the same numbers (tested).  "whole" is the one measured on a GPU so
# far (benchmarks/bench_gpu.py measures both and says which is faster)
STAGES = ("whole", "split")
DEFAULT_STAGES = "whole"


class GpuUnavailable(ValueError):
    """A GPU was asked for and cannot be used; the message says what is missing."""


# ----------------------------------------------------------------- what is here
def probe() -> dict:
    """What this machine offers numba.cuda: {"package", "simulator", "driver",
    "toolkit", "devices" [(index, name, compute capability, memory GiB)],
    "missing" (None or what to install / fix)}."""
    out = {"package": _package(), "simulator": SIMULATOR, "driver": None, "toolkit": None,
           "devices": [], "missing": None}
    if SIMULATOR:
        out.update(driver="simulated (NUMBA_ENABLE_CUDASIM=1)", toolkit="simulated",
                   devices=[(0, "CUDA simulator (runs on the CPU)", (0, 0), 0.0)])
        return out
    try:
        ok = cuda.is_available()
    except Exception as e:     # pragma: no cover - depends on the installation
        ok = False
        out["driver"] = f"error: {e}"
    if not ok:
        reason = _driver_error()
        out["driver"] = out["driver"] or f"not usable: {reason}"
        out["missing"] = f"an NVIDIA driver and GPU (numba.cuda says: {reason})"
        return out
    out["driver"] = _driver_version()
    for i, dev in enumerate(cuda.list_devices()):
        with dev:
            d = cuda.get_current_device()
            free, total = cuda.current_context().get_memory_info()
            out["devices"].append((i, _text(d.name), tuple(d.compute_capability),
                                   round(total / 2**30, 1)))
    out["toolkit"] = _toolkit()
    if out["toolkit"].startswith("missing"):
        out["missing"] = ("the CUDA toolkit's NVVM compiler: pip install -e '.[gpu]' "
                          "(nvidia-cuda-nvcc) or a CUDA toolkit on CUDA_HOME")
    return out


def _package():
    try:
        from importlib.metadata import version
        return f"numba-cuda {version('numba-cuda')}"
    except Exception:
        return "numba's built-in numba.cuda (deprecated; pip install -e '.[gpu]' for numba-cuda)"


def _driver_error() -> str:
    try:
        from numba.cuda.cudadrv.driver import driver
        driver.get_device_count()
    except Exception as e:
        return " ".join(str(e).split()).rstrip(" :")
    return "found no CUDA device"


def _driver_version():
    try:
        from numba.cuda.cudadrv.driver import driver
        v = driver.get_version()
        return f"CUDA driver {v[0]}.{v[1]}"
    except Exception:    # pragma: no cover - depends on the installation
        return "CUDA driver (version unknown)"


def _toolkit():
    try:
        from numba.cuda.cudadrv import nvvm
        v = nvvm.NVVM().get_version()
        return f"NVVM {v[0]}.{v[1]}"
    except Exception as e:
        return f"missing ({' '.join(str(e).split())[:200]})"


def _text(x):
    return x.decode() if isinstance(x, bytes) else str(x)


def describe(p: dict | None = None) -> str:
    """One line: the device a sweep would run on."""
    p = p or probe()
    if p["devices"]:
        i, name, cc, mem = p["devices"][0]
        return (f"GPU 0: {name}" + (f" (compute capability {cc[0]}.{cc[1]}, {mem} GiB)"
                                    if not p["simulator"] else ""))
    return "no GPU"


def require() -> dict:
    """The probe, or GpuUnavailable naming what is missing."""
    p = probe()
    if p["missing"]:
        raise GpuUnavailable(f"--device gpu: no usable GPU; missing {p['missing']} "
                             "(`pipeline doctor` says more)")
    return p


def choose(device: str) -> str:
    """'cpu' or 'gpu' for ``--device cpu|gpu|auto``; 'auto' says which it took."""
    if device == "cpu":
        return "cpu"
    if device == "gpu":
        log.info("device: %s", describe(require()))
        return "gpu"
    p = probe()
    if p["missing"]:
        log.info("device auto: the CPU (no usable GPU: missing %s)", p["missing"])
        return "cpu"
    log.info("device auto: %s", describe(p))
    return "gpu"


# ----------------------------------------------------------------- the sweep on a GPU
def thread_work(problem) -> list:
    """One thread's work arrays of the CUDA kernels of ``problem``'s sweep, as the
    CPU path allocates them: ``evaluate``'s own four, then continuation.work,
    forces.force_work and the module's watch_work (the kernels' WORK_NAMES)."""
    from ..kernels.continuation import work
    from ..kernels.forces import force_work
    m, n, w = problem.kernels, len(problem.phis), problem.dwell_w
    return [np.empty(n), np.empty(n + w + 1, np.int64), np.empty(n + w + 1, np.int64),
            np.empty(n), *work(m.N_POINTS, m.N_GROUPS, m.N_TRIADS),
            *force_work(m.N_BODIES, m.N_JOINTS, m.N_SLIDES + m.N_INPUTS),
            *m.watch_work(m.N_WATCH, m.N_TRIADS)]


class GpuSweep:
    """The stages of a sweep problem (``pipeline.runs.sweep.SweepProblem``) on the GPU."""

    def __init__(self, problem, batch=BATCH, stages=None):
        from ..compiler import gpu_kernels_for
        from ..kernels import sweep as ks
        self.stages = DEFAULT_STAGES if stages is None else stages
        if self.stages not in STAGES:
            raise ValueError(f"stages must be one of {', '.join(STAGES)}, got {stages!r}")
        self.problem = problem
        self.cpu = problem.kernels
        self.mod = gpu_kernels_for(problem.plan, problem.rocker)
        self.batch = int(batch)
        self.n_metrics = ks.N_METRICS
        p = problem
        self.settings = p.settings()
        # shared inputs, on the device once
        self.d_in = [cuda.to_device(np.ascontiguousarray(a)) for a in
                     (p.phis, p.tols, self.settings, p.loads, np.zeros((1, 1)))]
        self.streams = [cuda.stream() for _ in range(STREAMS)]
        self.work = [self._work_arrays() for _ in range(STREAMS)]
        self.stage = [self._staging() for _ in range(STREAMS)]
        self.kept = None        # gpu_kept.KeptRows, made by the first evaluate_kept

    def _work_arrays(self):
        """One set of per-thread work arrays (rows: threads of a batch), each
        shaped like the one the CPU path allocates (``thread_work``)."""
        like = thread_work(self.problem)
        if len(like) != len(self.mod.WORK_NAMES):
            raise RuntimeError(f"{self.mod.SOURCE_PATH}: the kernel takes "
                               f"{len(self.mod.WORK_NAMES)} work arrays, the CPU path "
                               f"allocates {len(like)}")
        return [cuda.device_array((self.batch,) + a.shape, a.dtype) for a in like]

    def _staging(self):
        """Page-locked host buffers of one batch (asynchronous copies) and the
        device arrays of its rows."""
        nv = self.problem.plan.par.shape[0]
        return dict(pars=cuda.pinned_array((self.batch, nv)),
                    status=cuda.pinned_array(self.batch, np.int8),
                    metrics=cuda.pinned_array((self.batch, self.n_metrics)),
                    d_pars=cuda.device_array((self.batch, nv)),
                    d_status=cuda.device_array(self.batch, np.int8),
                    d_metrics=cuda.device_array((self.batch, self.n_metrics)),
                    flags=cuda.pinned_array(self.batch, np.int8),
                    d_flags=cuda.device_array(self.batch, np.int8),
                    # the split stages' list of the candidates that reach the force stage
                    d_forced=cuda.device_array(self.batch, np.int64),
                    d_n_forced=cuda.device_array(1, np.int32))

    def evaluate_rows(self, pars):
        """(status int8 (n,), metrics (n, N_METRICS)) of the rows ``pars``: a host
        array, or a device array (the device's own draws: ``gpu_draws``)."""
        return self._evaluate(pars, False)

    def evaluate_kept(self, pars):
        """(status int8 (n,), the feasible rows' metrics (k, N_METRICS), their row
        indices (k,)) of the rows ``pars`` (a store-feasible sweep): judged and
        gathered on the device (``gpu_kept``), only those rows' metrics cross back."""
        if self.kept is None:
            from ..kernels import config as kc
            from .gpu_kept import KeptRows
            self.kept = KeptRows(self.problem.spec, self.problem.has_margin, kc.OK)
        return self._evaluate(pars, True)

    def _evaluate(self, pars, keep):
        """The batches of ``pars`` on the streams in turn (``evaluate_rows``,
        ``evaluate_kept``)."""
        if not hasattr(pars, "copy_to_host"):
            pars = np.ascontiguousarray(pars, dtype=np.float64)
        n = pars.shape[0]
        status = np.empty(n, np.int8)
        metrics = [] if keep else np.empty((n, self.n_metrics))    # keep: (lo, rows, metrics)
        pending = [None] * STREAMS      # (lo, hi) of the batch in flight on each stream
        for b, lo in enumerate(range(0, n, self.batch)):
            s = b % STREAMS
            self._collect(s, pending, status, metrics)
            hi = min(lo + self.batch, n)
            self._launch(s, pars[lo:hi], keep)
            pending[s] = (lo, hi)
        for s in range(STREAMS):
            self._collect(s, pending, status, metrics)
        if not keep:
            return status, metrics
        metrics.sort(key=lambda part: part[0])
        rows = np.concatenate([r for _, r, _ in metrics]) if metrics else np.zeros(0, np.int64)
        kept = (np.concatenate([m for _, _, m in metrics]) if metrics
                else np.zeros((0, self.n_metrics)))
        return status, kept, rows

    def _launch(self, s, rows, keep=False):
        k = rows.shape[0]
        st, stream = self.stage[s], self.streams[s]
        if hasattr(rows, "copy_to_host"):      # already on the device
            d_rows = rows
        else:
            st["pars"][:k] = rows
            d_rows = st["d_pars"][:k]
            d_rows.copy_to_device(st["pars"][:k], stream=stream)
        self._kernels(s, d_rows, k, stream)
        st["d_status"][:k].copy_to_host(st["status"][:k], stream=stream)
        if keep:
            self.kept.judge(st["d_status"][:k], st["d_metrics"][:k], st["d_flags"][:k], stream)
            st["d_flags"][:k].copy_to_host(st["flags"][:k], stream=stream)
        else:
            st["d_metrics"][:k].copy_to_host(st["metrics"][:k], stream=stream)

    def _kernels(self, s, d_rows, k, stream=0):
        """Launch the stages of the ``k`` rows ``d_rows`` (on the device) with the
        arrays of stream ``s``: status and metrics into its d_status, d_metrics."""
        st = self.stage[s]
        phis, tols, settings, loads, trail = self.d_in
        args = (d_rows, phis, self.problem.phi_close, tols, settings, loads, trail,
                st["d_status"][:k], st["d_metrics"][:k])
        work = [a[:k] for a in self.work[s]]
        blocks = (k + THREADS - 1) // THREADS
        with launching():
            if self.stages == "whole":
                self.mod.sweep_kernel[blocks, THREADS, stream](*args, *work)
                return
            # the force stage's candidates, listed by the first kernel (a count on
            # the device: the second kernel's threads past it return at once)
            forced, n_forced = st["d_forced"][:k], st["d_n_forced"]
            _zero[1, 1, stream](n_forced)
            self.mod.metrics_kernel[blocks, THREADS, stream](*args, forced, n_forced, *work)
            self.mod.forces_kernel[blocks, THREADS, stream](*args, forced, n_forced, *work)

    def _collect(self, s, pending, status, metrics):
        if pending[s] is None:
            return
        lo, hi = pending[s]
        st, stream = self.stage[s], self.streams[s]
        stream.synchronize()
        status[lo:hi] = st["status"][:hi - lo]
        if isinstance(metrics, list):      # keep: the feasible rows' metrics only
            rows = np.flatnonzero(st["flags"][:hi - lo])
            if len(rows):
                metrics.append((lo, lo + rows,
                                self.kept.gather(st["d_metrics"][:hi - lo], rows, stream)))
        else:
            metrics[lo:hi] = st["metrics"][:hi - lo]
        pending[s] = None

    def kernel_only(self, pars, repeats=1):
        """Seconds per evaluation of ``pars`` already on the device, results left
        there (the benchmark's kernel throughput; no host transfers)."""
        import time
        n = pars.shape[0]
        if n > self.batch:
            raise ValueError(f"kernel_only takes at most one batch ({self.batch} rows)")
        st = self.stage[0]
        st["d_pars"][:n].copy_to_device(np.ascontiguousarray(pars))
        best = math.inf
        for _ in range(repeats):
            cuda.synchronize()
            t = time.perf_counter()
            self._kernels(0, st["d_pars"][:n], n)
            cuda.synchronize()
            best = min(best, time.perf_counter() - t)
        return best


@cuda.jit
def _zero(count):
    """count[0] = 0 (on the device, in its stream's order)."""
    if cuda.threadIdx.x == 0 and cuda.blockIdx.x == 0:
        count[0] = 0


def doctor() -> str:
    """The report of ``pipeline doctor``: what numba.cuda sees, what is missing."""
    p = probe()
    lines = [f"numba.cuda package : {p['package']}",
             f"CUDA driver        : {p['driver']}",
             f"toolkit (NVVM)     : {p['toolkit'] or '-'}"]
    if p["devices"]:
        for i, name, cc, mem in p["devices"]:
            lines.append(f"GPU {i}              : {name}"
                         + (f", compute capability {cc[0]}.{cc[1]}, {mem} GiB" if mem else ""))
    else:
        lines.append("GPU                : none found")
    if os.environ.get("CUDA_VISIBLE_DEVICES") is not None:
        lines.append(f"CUDA_VISIBLE_DEVICES = {os.environ['CUDA_VISIBLE_DEVICES']!r}")
    if p["missing"]:
        lines.append(f"--device gpu: not available; missing {p['missing']}")
    else:
        lines.append("--device gpu: ready")
    return "\n".join(lines)
