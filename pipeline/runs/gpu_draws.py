"""A sweep's draws on the GPU (issue 54): only what is stored crosses the bus.

Point k of a scrambled Sobol sequence is its digital shift XOR the direction
numbers of the bits set in k's Gray code, k ^ (k >> 1): what scipy's engine
reaches by stepping through the points, here computed by each thread from its
candidate's index alone, from the engine's own direction numbers and shift
(``study.sampling.sobol_engine``, the host's draws' own).
The points are mapped into the bounds, the triangle inequalities checked and
the parameter rows written on the device.  The rows that break a triangle
(their indices) come to the host, which redraws them exactly as the CPU's
draws do (``study.sampling.redrawn``) and sends them back.  The chunk's design
variables come back for the results file; the parameter rows stay on the
device for the kernel.  The same bits as ``SweepProblem.draw_chunk`` (tested
under numba's CUDA simulator): the integers are exact, the scale a power of
two, and the two roundings of low + u (high - low) are kept apart on a GPU
(``cuda_device.mul_rn``, ``add_rn``: NVVM would contract them into one FMA).
"""

from __future__ import annotations

import numpy as np

# first: cuda_device's numpy fix precedes numba.cuda's import
from ..compiler.cuda_device import add_rn, launching, mul_rn, own
from numba import cuda
from ..kernels.candidates import parameter_row
from ..study.sampling import bounds, redrawn, sobol_engine

THREADS = 256


@cuda.jit
def _points(first, sv, shift, scale, low, span, x):
    """x[i] = low + u (high - low), u = point first + i of the sequence."""
    i = cuda.threadIdx.x + cuda.blockIdx.x * cuda.blockDim.x
    if i < x.shape[0]:
        k = first + i
        gray = k ^ (k >> 1)
        for j in range(x.shape[1]):
            q = shift[j]
            for b in range(sv.shape[1]):
                if (gray >> b) & 1:
                    q ^= sv[j, b]
            x[i, j] = add_rn(low[j], mul_rn(q * scale, span[j]))


@cuda.jit
def _first_broken(x, cols, fixed, first):
    """first[i]: the first triangle row i of x breaks (-1: none); a side is a
    design variable's column or, where the column is -1, a fixed value."""
    i = cuda.threadIdx.x + cuda.blockIdx.x * cuda.blockDim.x
    if i < x.shape[0]:
        first[i] = -1
        for t in range(cols.shape[0]):
            a = x[i, cols[t, 0]] if cols[t, 0] >= 0 else fixed[t, 0]
            b = x[i, cols[t, 1]] if cols[t, 1] >= 0 else fixed[t, 1]
            c = x[i, cols[t, 2]] if cols[t, 2] >= 0 else fixed[t, 2]
            if not (a < b + c and b < a + c and c < a + b):
                first[i] = t
                return


@cuda.jit
def _put_rows(rows, values, x):
    """x[rows[r]] = values[r] (the host's redraws)."""
    r = cuda.threadIdx.x + cuda.blockIdx.x * cuda.blockDim.x
    if r < rows.shape[0]:
        for j in range(x.shape[1]):
            x[rows[r], j] = values[r, j]


@cuda.jit
def _parameter_rows(base, x, var_cols, factors, mass_cols, out):
    """``kernels.candidates.parameter_row`` (the CPU's own function, compiled for
    the GPU), a thread a row."""
    i = cuda.threadIdx.x + cuda.blockIdx.x * cuda.blockDim.x
    if i < x.shape[0]:
        # own(): the array itself on a GPU; the numpy array inside the simulator's wrapper
        parameter_row(own(base), own(x)[i], own(var_cols), own(factors), own(mass_cols),
                      own(out)[i])


def applies(spec) -> bool:
    """Whether a sweep's draws can be made on the device: the Sobol sampler's."""
    return spec.sampler == "sobol"


class DeviceDraws:
    """The draws of a sweep problem's chunks on the GPU (``draw``)."""

    def __init__(self, problem):
        from ..study.sweep_spec import parameter_columns
        spec, plan = problem.spec, problem.plan
        self.spec = spec
        engine = sobol_engine(spec)
        low, span = bounds(spec)
        cols = np.array([t.columns for t in spec.triangles], np.int64).reshape(-1, 3)
        fixed = np.array([t.fixed for t in spec.triangles], np.float64).reshape(-1, 3)
        var_cols, factors, mass_cols = parameter_columns(plan, spec)
        self.scale = float(engine._scale)
        self.d = {name: cuda.to_device(np.ascontiguousarray(a)) for name, a in (
            ("sv", engine._sv.astype(np.int64)), ("shift", engine._shift.astype(np.int64)),
            ("low", low), ("span", span), ("cols", cols), ("fixed", fixed),
            ("base", np.asarray(plan.par, np.float64)), ("var_cols", var_cols),
            ("factors", factors), ("mass_cols", mass_cols))}
        self.n_par = plan.par.shape[0]

    def draw(self, chunk):
        """(x, rejected, pars) of chunk ``chunk``, as ``SweepProblem.draw_chunk``
        gives them, with ``pars`` a device array (the kernel's input, left there)."""
        d, spec = self.d, self.spec
        lo, hi = spec.chunk_bounds(chunk)
        n = hi - lo
        blocks = (n + THREADS - 1) // THREADS
        stream = cuda.stream()
        x = cuda.device_array((n, len(spec.variables)), stream=stream)
        with launching():
            _points[blocks, THREADS, stream](lo, d["sv"], d["shift"], self.scale, d["low"],
                                             d["span"], x)
        rejected = np.zeros(len(spec.triangles), np.int64)
        if len(spec.triangles):
            first = cuda.device_array(n, np.int64, stream=stream)
            with launching():
                _first_broken[blocks, THREADS, stream](x, d["cols"], d["fixed"], first)
            first = first.copy_to_host(stream=stream)
            stream.synchronize()
            rejected += np.bincount(first[first >= 0], minlength=len(spec.triangles))
            rows = np.flatnonzero(first >= 0)
            if len(rows):
                values = redrawn(spec, chunk, rows, rejected)
                with launching():
                    _put_rows[(len(rows) + THREADS - 1) // THREADS, THREADS, stream](
                        cuda.to_device(rows, stream=stream),
                        cuda.to_device(values, stream=stream), x)
        pars = cuda.device_array((n, self.n_par), stream=stream)
        with launching():
            _parameter_rows[blocks, THREADS, stream](d["base"], x, d["var_cols"], d["factors"],
                                                     d["mass_cols"], pars)
        x_host = x.copy_to_host(stream=stream)
        stream.synchronize()
        return x_host, rejected, pars
