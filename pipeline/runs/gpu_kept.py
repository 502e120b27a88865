"""Only what is kept crosses back (issue 54): a store-feasible sweep's rows
judged on the device, and only the feasible ones' metrics gathered and copied
to the host, with every row's status (the chunk's counts stay exact).  The
judgement is ``study.objectives.feasibility``'s, from its tables
(``feasibility_rules``): the same products and sums, their roundings kept
apart on a GPU as in ``gpu_draws``; the host judges the rows it receives
again, and a row the two judge differently stops the run."""

from __future__ import annotations

import math

import numpy as np

# first: cuda_device's numpy fix precedes numba.cuda's import
from ..compiler.cuda_device import add_rn, launching, mul_rn
from numba import cuda
from .gpu_draws import THREADS


@cuda.jit
def _judge(status, metrics, ok, limits, finite, flags):
    """flags[i] = 1 where row i is feasible: status OK, no constraint's g above 0,
    every objective and bounded metric finite; else 0."""
    i = cuda.threadIdx.x + cuda.blockIdx.x * cuda.blockDim.x
    if i < status.shape[0]:
        good = status[i] == ok
        for r in range(limits.shape[0]):
            v = mul_rn(metrics[i, int(limits[r, 0])], limits[r, 1])
            if limits[r, 2] != 0.0:
                v = add_rn(v, limits[r, 2])
            if limits[r, 3] * (v - limits[r, 4]) > 0.0:
                good = False
        for r in range(finite.shape[0]):
            v = mul_rn(metrics[i, int(finite[r, 0])], finite[r, 1])
            if finite[r, 2] != 0.0:
                v = add_rn(v, finite[r, 2])
            if not math.isfinite(v):
                good = False
        flags[i] = 1 if good else 0


@cuda.jit
def _gather(metrics, rows, out):
    """out[r] = metrics[rows[r]]."""
    r = cuda.threadIdx.x + cuda.blockIdx.x * cuda.blockDim.x
    if r < rows.shape[0]:
        for j in range(metrics.shape[1]):
            out[r, j] = metrics[rows[r], j]


class KeptRows:
    """The judging and gathering of one ``GpuSweep``: its rules on the device."""

    def __init__(self, spec, has_margin, ok):
        from ..study.objectives import feasibility_rules
        limits, finite = feasibility_rules(spec, has_margin)
        self.ok = ok
        self.limits, self.finite = cuda.to_device(limits), cuda.to_device(finite)

    def judge(self, d_status, d_metrics, d_flags, stream):
        """Launch the judgement of a batch's rows into ``d_flags`` (int8)."""
        k = d_status.shape[0]
        with launching():
            _judge[(k + THREADS - 1) // THREADS, THREADS, stream](
                d_status, d_metrics, self.ok, self.limits, self.finite, d_flags)

    def gather(self, d_metrics, rows, stream):
        """The metric rows ``rows`` (host indices into the batch) of ``d_metrics``,
        copied to the host."""
        k = len(rows)
        out = cuda.device_array((k, d_metrics.shape[1]), stream=stream)
        with launching():
            _gather[(k + THREADS - 1) // THREADS, THREADS, stream](
                d_metrics, cuda.to_device(np.ascontiguousarray(rows, np.int64), stream=stream),
                out)
        host = out.copy_to_host(stream=stream)
        stream.synchronize()
        return host
