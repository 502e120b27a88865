"""kernels.calls: a kernel called through its address (``first_class`` and
``function_at``) runs the same compiled code as a direct call, and the caller's
compile does not link the callee's code."""

import numpy as np
from numba import njit

from pipeline.kernels.calls import first_class, function_at


@njit(cache=False)
def _callee(a, work, k):
    s = 0.0
    for i in range(a.shape[0]):
        s += a[i] * work[0][i] / (k + 1.0) + work[1][i % 2, 1]
    return s


_FN = None      # (set below, before _caller compiles: numba reads it then)


@njit(cache=False)
def _caller(called, a, work):
    f = function_at(called[0], _FN)
    t = 0.0
    for k in range(3):
        t += f(a, work, np.int64(k))
    return t


def test_a_kernel_called_through_its_address_gives_the_direct_call_s_bits():
    global _FN
    rng = np.random.default_rng(3)
    a = rng.standard_normal(7)
    work = (rng.standard_normal(7), rng.standard_normal((2, 2)))
    _FN, address = first_class(_callee, (a, work, np.int64(0)))
    assert isinstance(address, int) and address > 0
    assert str(_FN).startswith("FunctionType[float64(array(float64, 1d, C), Tuple(")
    got = _caller(np.array([address], np.int64), a, work)
    want = 0.0
    for k in range(3):
        want += _callee(a, work, np.int64(k))
    assert got == want                                  # the same compiled code: the bits
    # the caller's own module holds no copy of the callee's code
    ir = next(iter(_caller.inspect_llvm().values()))
    defined = [ln for ln in ir.splitlines() if ln.startswith("define") and "_callee" in ln]
    assert defined == [], defined
    called = next(iter(_callee.inspect_llvm().values()))
    assert any(ln.startswith("define") and "_callee" in ln for ln in called.splitlines())
