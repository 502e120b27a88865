"""The device side a generated CUDA module imports besides the CPU module's
``settle``: ``own(a)``, a kernel's array argument as the CPU-compiled device
functions take it.  Part of the compiler (the layer whose source it is), so
that generated code imports nothing from the layers above.  Importing this
imports numba.cuda (the ``[gpu]`` extra); the CPU path never does."""

from __future__ import annotations

import contextlib
import threading

import numpy as np

# numba-cuda's import still names np.row_stack, which numpy 2.5 removed: the same
# function under its old name, before numba.cuda is imported (nothing else here uses it)
if not hasattr(np, "row_stack"):    # pragma: no cover - numpy >= 2.5
    np.row_stack = np.vstack

from numba import config as _config     # noqa: E402
from numba import cuda                  # noqa: E402

SIMULATOR = bool(_config.ENABLE_CUDASIM)
# the simulator runs one kernel at a time in a process (a kernel launched from a second
# thread meanwhile fails): launches from the thread drawing the next chunk
# (pipeline.runs.gpu_draws) and the one evaluating this chunk take turns there; a GPU runs
# them side by side
_ONE_AT_A_TIME = threading.Lock()


def launching():
    """Around a kernel's launch: the simulator's turn, nothing on a GPU."""
    return _ONE_AT_A_TIME if SIMULATOR else contextlib.nullcontext()

if SIMULATOR:
    def mul_rn(a, b):
        """a * b, rounded once (the simulator's arithmetic is the CPU's)."""
        return a * b

    def add_rn(a, b):
        """a + b, rounded once."""
        return a + b

    def own(a):
        """The numpy array inside the simulator's wrapper of a kernel argument
        (the CPU-compiled functions the kernel calls take only numpy arrays)."""
        inner = getattr(a, "_item", a)
        return getattr(inner, "_ary", inner)
else:
    from numba.cuda import libdevice

    @cuda.jit(device=True, inline=True)
    def mul_rn(a, b):
        """a * b rounded on its own: NVVM would contract a product and a sum into one
        FMA (one rounding), which the CPU's numbers do not have."""
        return libdevice.dmul_rn(a, b)

    @cuda.jit(device=True, inline=True)
    def add_rn(a, b):
        """a + b rounded on its own (``mul_rn``)."""
        return libdevice.dadd_rn(a, b)

    @cuda.jit(device=True, inline=True)
    def own(a):
        """On a GPU a kernel's array argument is already what the device
        functions take."""
        return a
