"""kernels.calls: a kernel called through its address (``first_class`` and
``function_at``) runs the same compiled code as a direct call, and the caller's
compile does not link the callee's code."""

import numpy as np
from numba import njit

from pipeline.kernels.calls import first_class, function_at, pick, unliteral


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


@njit(cache=False)
def _flagged(x, keep, n):
    return x + n if keep else x - n


@njit(cache=False)
def _literal_caller(x):
    return _flagged(x, True, 3) + _flagged(x, False, 3)


@njit(cache=False)
def _unliteral_caller(x):
    return (_flagged(x, unliteral(True), unliteral(3))
            + _flagged(x, unliteral(False), unliteral(3)))


def test_a_callee_called_with_two_literals_compiles_once_through_unliteral():
    """numba compiles a callee once per literal argument (``True`` here, ``False``
    there); through ``unliteral`` once, for a run-time bool and int, the signature
    a call from Python gives it, and with the same result."""
    assert _literal_caller(1.5) == 1.5 + 3 + 1.5 - 3
    literal = list(_flagged.signatures)
    assert len(literal) == 2 and all("Literal" in str(s) for s in literal), literal
    assert _unliteral_caller(1.5) == _literal_caller(1.5)
    new = [s for s in _flagged.signatures if s not in literal]
    assert [str(s) for s in new] == ["(float64, bool, int64)"], new
    _flagged(1.5, True, 3)                                  # from Python: the same one
    assert len(_flagged.signatures) == 3


@njit(cache=False)
def _picked(which, a, out):
    for i in range(a.shape[0]):
        out[i] = pick(which == 0, a[i, 0], pick(which == 1, a[i, 1], a[i, 2]))


def test_pick_is_the_conditional_expression_to_the_bit():
    """``pick(c, a, b)`` is ``a if c else b`` for every value a float takes,
    NaN (its payload and sign), infinities and signed zeros among them."""
    vals = np.array([0.0, -0.0, 1.5, -2.25, np.inf, -np.inf, np.nan, -np.nan, 5e-324,
                     np.frombuffer(np.uint64(0x7FF8_0000_DEAD_BEEF).tobytes())[0]])
    rng = np.random.default_rng(3)
    a = rng.choice(vals, (200, 3))
    for which in range(3):
        out = np.empty(200)
        _picked(which, a, out)
        want = np.array([x[0] if which == 0 else (x[1] if which == 1 else x[2]) for x in a])
        assert out.tobytes() == want.tobytes()


def test_the_friction_integrator_passes_its_callees_no_literal():
    """The friction integrator's evaluation, the secant on eps1 and the forces are
    called with run-time flags and counts (``unliteral``), so each compiles once
    (a literal True and False compiled the chain twice: 46.6 s against 34.4 s)."""
    import ast
    import inspect

    from pipeline.kernels import dynamics_friction, friction
    callees = {"_eval", "friction_eps", "_m_bal", "friction_forces"}
    for module in (dynamics_friction, friction):
        tree = ast.parse(inspect.getsource(module))
        constants = {t.id for node in tree.body if isinstance(node, ast.Assign)
                     for t in node.targets if isinstance(t, ast.Name)
                     and isinstance(node.value, ast.Constant)
                     and type(node.value.value) in (bool, int)}
        for call in ast.walk(tree):
            if isinstance(call, ast.Call) and getattr(call.func, "id", None) in callees:
                for a in call.args:
                    literal = (isinstance(a, ast.Constant) and type(a.value) in (bool, int)) \
                        or (isinstance(a, ast.Name) and a.id in constants)
                    assert not literal, (module.__name__, call.func.id, call.lineno,
                                         ast.unparse(a))
