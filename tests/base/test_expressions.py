"""Tests for pipeline.expressions: whitelisted load expressions of phi and t.

The fuzz tests compare the NumPy implementation with ``_Ref``, an independent
point-wise evaluator written here over the ``ast`` tree with Python floats and
``math``.  ``_Ref`` also carries a running bound on how far an implementation
with a few ulps of libm error could drift, and declares a point *ambiguous*
when that drift could flip a discontinuity (a comparison, ``sign``, the
condition of ``where``, a pole, the domain edge of ``log``/``sqrt``/``**``,
overflow or underflow).  Ambiguous points are not compared; every other point
must agree to ``rtol=1e-12`` (plus the carried bound), and a non-finite
reference value must make ``evaluate`` raise ``ExpressionError``.
"""

from __future__ import annotations

import ast
import builtins
import dataclasses
import math
import pickle
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pipeline.base import expressions
from pipeline.base.expressions import (
         MAX_DEPTH,
         MAX_TERMS,
         MAX_LENGTH,
         Expression,
         ExpressionError,
         parse_expression,
     )

FIELD = "studies/foo.toml: loads[0].fy"
RTOL = 1e-12
DOMAIN_LOAD = "-150*(1 + 0.2*sin(2*phi))"


def _parse_error(text, field=FIELD) -> ExpressionError:
    with pytest.raises(ExpressionError) as info:
        parse_expression(text, field)
    return info.value


# ---------------------------------------------------------------------------
# known values
# ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("phi", "expected"),
    [
        (0.0, -150.0),
        (math.pi / 4, -180.0),
        (math.pi / 2, -150.0),
        (3 * math.pi / 4, -120.0),
        (1.0, -150.0 * (1 + 0.2 * math.sin(2.0))),
        (-2.5, -150.0 * (1 + 0.2 * math.sin(-5.0))),
    ],
)
def test_domain_load_known_values(phi, expected):
    expr = parse_expression(DOMAIN_LOAD, FIELD)
    got = expr.evaluate(phi)
    assert got.shape == ()
    assert got.dtype == np.float64
    np.testing.assert_allclose(got, expected, rtol=RTOL, atol=1e-12)


def test_domain_load_on_array_matches_formula():
    phi = np.linspace(0.0, 2 * np.pi, 361)
    got = parse_expression(DOMAIN_LOAD, FIELD).evaluate(phi)
    np.testing.assert_allclose(got, -150 * (1 + 0.2 * np.sin(2 * phi)), rtol=RTOL)


@pytest.mark.parametrize(
    ("text", "phi", "t", "expected"),
    [
        ("2**3", 0.0, 0.0, 8.0),
        ("-2**2", 0.0, 0.0, -4.0),  # ** binds tighter than unary minus, as in Python
        ("2**-1", 0.0, 0.0, 0.5),
        ("2**3**2", 0.0, 0.0, 512.0),  # right-associative
        ("7/2", 0.0, 0.0, 3.5),
        ("1 - 2 - 3", 0.0, 0.0, -4.0),
        ("+phi", 1.5, 0.0, 1.5),
        ("--phi", 1.5, 0.0, 1.5),
        ("2*pi", 0.0, 0.0, 2 * math.pi),
        ("phi*t", 3.0, 0.5, 1.5),
        ("1.5e2 + .5 + 2.", 0.0, 0.0, 152.5),
        ("phi < 1", 0.5, 0.0, 1.0),
        ("phi < 1", 1.0, 0.0, 0.0),
        ("phi <= 1", 1.0, 0.0, 1.0),
        ("phi > 1", 1.0, 0.0, 0.0),
        ("phi >= 1", 1.0, 0.0, 1.0),
        ("phi == 1", 1.0, 0.0, 1.0),
        ("phi != 1", 1.0, 0.0, 0.0),
        ("(phi > 1) * 5 + 1", 2.0, 0.0, 6.0),
        ("0 <= phi < pi", 1.0, 0.0, 1.0),  # chained comparison, Python semantics
        ("0 <= phi < pi", 4.0, 0.0, 0.0),
        ("0 <= phi < pi", -1.0, 0.0, 0.0),
        ("1 < 2 > 0", 0.0, 0.0, 1.0),
        ("where(phi < pi, 1, -1)", 1.0, 0.0, 1.0),
        ("where(phi < pi, 1, -1)", 4.0, 0.0, -1.0),
        ("where(phi, 10, 20)", 0.0, 0.0, 20.0),
        ("where(phi, 10, 20)", -0.1, 0.0, 10.0),
        ("min(phi, 1, t)", 3.0, 2.0, 1.0),
        ("max(phi, 1, t)", 3.0, 2.0, 3.0),
        ("min(phi, t)", -3.0, 2.0, -3.0),
        ("sign(phi - 1)", 0.5, 0.0, -1.0),
        ("sign(phi - 1)", 1.0, 0.0, 0.0),
        ("sign(phi - 1)", 7.0, 0.0, 1.0),
        ("abs(-phi)", 2.5, 0.0, 2.5),
        ("sqrt(4)", 0.0, 0.0, 2.0),
        ("exp(0)", 0.0, 0.0, 1.0),
        ("log(exp(2))", 0.0, 0.0, 2.0),
        ("tan(pi/4)", 0.0, 0.0, 1.0),
        ("cos(pi)", 0.0, 0.0, -1.0),
        ("sin(phi)**2 + cos(phi)**2", 0.7, 0.0, 1.0),
        ("( phi\n + 1 )", 1.0, 0.0, 2.0),  # newlines inside brackets (TOML multi-line strings)
        ("phi\n  + 1\r\n", 1.0, 0.0, 2.0),  # and at top level too
        ("  phi + 1  ", 1.0, 0.0, 2.0),  # surrounding blanks are ignored
        ("where(phi > 0, log(phi), 0)", -1.0, 0.0, 0.0),  # non-finite only in the unused branch
        ("1/(1/phi)", 0.0, 0.0, 0.0),  # intermediate inf is fine, only the result is checked
        ("exp(-1/abs(phi))", 0.0, 0.0, 0.0),
    ],
)
def test_known_values(text, phi, t, expected):
    got = parse_expression(text, FIELD).evaluate(phi, t)
    np.testing.assert_allclose(got, expected, rtol=RTOL, atol=1e-15)


def test_broadcasting_phi_and_t():
    expr = parse_expression("phi + 10*t", FIELD)
    phi = np.linspace(0.0, 1.0, 5)
    t = np.array([[0.0], [1.0], [2.0]])
    got = expr.evaluate(phi, t)
    assert got.shape == np.broadcast(phi, t).shape == (3, 5)
    assert got.dtype == np.float64
    np.testing.assert_allclose(got, phi + 10 * t, rtol=RTOL)


@pytest.mark.parametrize("text", ["3", "pi", "t", "phi", "2*t + 1", "where(t > 0, phi, 1)"])
@pytest.mark.parametrize(
    ("phi", "t", "shape"),
    [
        (0.5, 0.0, ()),
        (np.zeros(4), 0.0, (4,)),
        (0.5, np.ones(3), (3,)),
        (np.zeros((2, 1)), np.ones(3), (2, 3)),
        ([0.0, 1.0], 2.0, (2,)),  # lists are accepted like arrays
        (np.arange(3, dtype=np.int64), 0.0, (3,)),  # integer input is promoted
    ],
)
def test_result_shape_is_broadcast_shape(text, phi, t, shape):
    got = parse_expression(text, FIELD).evaluate(phi, t)
    assert isinstance(got, np.ndarray)
    assert got.shape == shape
    assert got.dtype == np.float64


def test_result_is_a_fresh_writable_array():
    expr = parse_expression("2", FIELD)
    first = expr.evaluate(np.zeros(3))
    first[:] = 99.0
    np.testing.assert_array_equal(expr.evaluate(np.zeros(3)), [2.0, 2.0, 2.0])
    phi = np.zeros(3)
    out = parse_expression("phi", FIELD).evaluate(phi)
    out[0] = 5.0
    assert phi[0] == 0.0


def test_default_time_is_zero():
    expr = parse_expression("t + 1", FIELD)
    np.testing.assert_array_equal(expr.evaluate(np.arange(3.0)), [1.0, 1.0, 1.0])


@pytest.mark.parametrize(
    ("text", "depends_on_time", "is_constant"),
    [
        (DOMAIN_LOAD, False, False),
        ("sin(phi)", False, False),
        ("t*2", True, False),
        ("phi + t", True, False),
        ("where(t > 1, 0, phi)", True, False),
        ("3", False, True),
        ("-2.5e3", False, True),
        ("pi/2 + sqrt(2)", False, True),
        ("0*t", True, False),  # the flags are syntactic: t is mentioned
        ("0*phi", False, False),
    ],
)
def test_dependency_flags(text, depends_on_time, is_constant):
    expr = parse_expression(text, FIELD)
    assert expr.depends_on_time is depends_on_time
    assert expr.is_constant is is_constant


@pytest.mark.parametrize(("value", "expected"), [(-150, -150.0), (0, 0.0), (2.5, 2.5), (1e-3, 1e-3)])
def test_numbers_from_toml_are_constant_expressions(value, expected):
    expr = parse_expression(value, FIELD)
    assert expr.is_constant and not expr.depends_on_time
    assert expr.field == FIELD
    got = expr.evaluate(np.linspace(0, 1, 4), 2.0)
    np.testing.assert_array_equal(got, np.full(4, expected))


def test_numpy_numbers_are_accepted():
    assert float(parse_expression(np.float64(2.0), FIELD).evaluate(0.0)) == 2.0
    assert float(parse_expression(np.int64(-3), FIELD).evaluate(0.0)) == -3.0


@pytest.mark.parametrize(
    ("value", "token"),
    [
        (True, "bool"),
        (False, "bool"),
        (np.bool_(True), "bool"),
        (None, "NoneType"),
        ([1, 2], "list"),
        ({"a": 1}, "dict"),
        (b"phi", "bytes"),
        (1 + 2j, "complex"),
    ],
)
def test_wrong_types_are_rejected(value, token):
    err = _parse_error(value)
    message = str(err)
    assert message.startswith(FIELD + ": ")
    assert "expected a string expression or a number" in message
    assert token in message
    assert err.token == token


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, 10**400])
def test_non_finite_numbers_are_rejected(value):
    err = _parse_error(value)
    assert str(err).startswith(FIELD + ": ")
    assert err.token in str(err)


# ---------------------------------------------------------------------------
# non-finite results
# ---------------------------------------------------------------------------


def test_non_finite_result_names_field_and_point():
    expr = parse_expression("1/phi", FIELD)
    with pytest.raises(ExpressionError) as info:
        expr.evaluate(np.array([1.0, 0.0, 2.0]), 0.25)
    message = str(info.value)
    assert message.startswith(FIELD + ": ")
    assert "non-finite value at phi=0.0, t=0.25" in message
    assert info.value.field == FIELD


@pytest.mark.parametrize(
    ("text", "phi", "t", "where_"),
    [
        ("log(phi - 1)", [2.0, 0.5, 3.0], 0.0, "phi=0.5, t=0.0"),
        ("sqrt(phi)", [1.0, 4.0, -1.0], 0.0, "phi=-1.0, t=0.0"),
        ("1/(t - 1)", 0.0, [0.0, 1.0], "phi=0.0, t=1.0"),
        ("exp(1000*phi)", [0.0, 1.0], 0.0, "phi=1.0, t=0.0"),
        ("sqrt(-1)", 0.0, 0.0, "phi=0.0, t=0.0"),
        ("0/0", 0.0, 3.0, "phi=0.0, t=3.0"),
        ("where(sqrt(phi), 1, 2)", -1.0, 0.0, "phi=-1.0, t=0.0"),  # NaN condition -> NaN
        ("min(phi, sqrt(phi))", -1.0, 0.0, "phi=-1.0, t=0.0"),  # min/max propagate NaN
        ("phi", np.nan, 0.0, "phi=nan, t=0.0"),
    ],
)
def test_non_finite_results_raise(text, phi, t, where_):
    expr = parse_expression(text, FIELD)
    with pytest.raises(ExpressionError) as info:
        expr.evaluate(phi, t)
    assert f"non-finite value at {where_}" in str(info.value)
    assert FIELD in str(info.value)


def test_no_numpy_warnings_escape(recwarn):
    parse_expression("log(phi) + 1/phi", FIELD)
    with pytest.raises(ExpressionError):
        parse_expression("log(phi) + 1/phi", FIELD).evaluate(np.array([0.0, -1.0]))
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_power_follows_c_pow_for_scalar_and_array_exponents():
    # NumPy turns x**0.5 into sqrt(x) for scalar exponents, which differs from
    # pow() at -inf (nan instead of inf); the result must not depend on that.
    a = parse_expression("1/(log(phi)**0.5)", FIELD).evaluate(np.array([0.0]))
    b = parse_expression("1/(log(phi)**(0.5 + 0*t))", FIELD).evaluate(np.array([0.0]), np.zeros(1))
    np.testing.assert_array_equal(a, [0.0])
    np.testing.assert_array_equal(b, [0.0])


# ---------------------------------------------------------------------------
# rejections
# ---------------------------------------------------------------------------


def test_message_format_matches_the_documented_examples():
    assert str(_parse_error("-150*x")).startswith(f"{FIELD}: unknown name 'x'")
    assert str(_parse_error("-150*x")).endswith(' in "-150*x"')
    assert f"{FIELD}: function 'open' is not allowed" in str(_parse_error("open('f')"))
    assert f"{FIELD}: attribute access '.__class__' is not allowed" in str(_parse_error("phi.__class__"))


REJECTED = [
    # (text, offending token that the message must contain)
    ("-150*x", "x"),
    ("e", "e"),
    ("PHI", "PHI"),
    ("__builtins__", "__builtins__"),
    ("open('f')", "open"),
    ("__import__('os').system('ls')", "__import__"),
    ("eval('1')", "eval"),
    ("exec('1')", "exec"),
    ("getattr(phi, 'x')", "getattr"),
    ("asin(phi)", "asin"),
    ("phi.__class__", ".__class__"),
    ("().__class__.__bases__", ".__bases__"),
    ("np.sin(phi)", ".sin"),
    ("phi.real", ".real"),
    ("phi[0]", "phi[0]"),
    ("(1, 2)[0]", "(1, 2)[0]"),
    ("lambda: 1", "lambda"),
    ("(lambda x: x)(1)", "lambda"),
    ("'abc'", "'abc'"),
    ('"phi"', '"phi"'),
    ("b'x'", "b'x'"),
    ("f'{phi}'", "f'{phi}'"),
    ("import os", "import"),
    ("for", "for"),
    ("yield phi", "yield"),
    ("phi if t else 1", "if"),
    ("phi and t", "and"),
    ("phi or t", "or"),
    ("not phi", "not"),
    ("sin(phi, t)", "sin"),
    ("sin()", "sin"),
    ("min(phi)", "min"),
    ("max()", "max"),
    ("where(phi, 1)", "where"),
    ("where(phi, 1, 2, 3)", "where"),
    ("min(phi, key=abs)", "key"),
    ("sin(x=phi)", "x"),
    ("max(**d)", "**d"),
    ("max(*phi)", "*phi"),
    ("sin", "sin"),
    ("phi(1)", "phi"),
    ("sin(phi)(1)", "sin(phi)"),
    ("phi % 2", "%"),
    ("phi // 2", "//"),
    ("phi @ t", "@"),
    ("phi & 1", "&"),
    ("phi | 1", "|"),
    ("phi ^ 1", "^"),
    ("phi << 1", "<<"),
    ("~phi", "~"),
    ("phi is t", "is"),
    ("phi is not t", "is not"),
    ("phi in t", "in"),
    ("phi not in t", "not in"),
    ("[phi]", "[phi]"),
    ("{phi}", "{phi}"),
    ("{1: 2}", "{1: 2}"),
    ("phi, t", "phi, t"),
    ("[x for x in phi]", "[x for x in phi]"),
    ("(x := 1)", ":="),
    ("True", "True"),
    ("None", "None"),
    ("...", "..."),
    ("1j", "1j"),
    ("1e999", "1e999"),
    ("9" * 400, "9" * 20),
    ("1 # comment", "#"),
    ("phi + \\\n 1", "\\"),
    ("φ", "φ"),
    ("ｐｈｉ", "ｐ"),  # full-width letters would NFKC-normalise to 'phi'
    ("phi\x00", "\\x00"),
    ("sin(phi", "("),
    ("phi +", "end of expression"),
    ("phi phi", "phi"),
    ("phi;t", ";"),
    ("", ""),
    ("   ", ""),
    ("x" * (MAX_LENGTH + 1), f"{MAX_LENGTH + 1} characters"),
    ("(" * (MAX_DEPTH + 1) + "phi" + ")" * (MAX_DEPTH + 1), "("),
    ("-" * (MAX_DEPTH + 5) + "phi", "-" * 10),
    ("+".join(["1"] * (MAX_TERMS + 1)), f"more than {MAX_TERMS} terms"),
    ("sin(" * (MAX_DEPTH + 1) + "phi" + ")" * (MAX_DEPTH + 1), "("),
]


@pytest.mark.parametrize(("text", "token"), REJECTED)
def test_rejections_name_field_and_token(text, token):
    err = _parse_error(text)
    message = str(err)
    assert message.startswith(FIELD + ": "), message
    assert token in message, message
    assert err.field == FIELD
    assert err.token in message
    assert isinstance(err, ValueError)


def test_tan_at_its_pole_is_reported_not_1e16():
    expr = parse_expression("100 * tan(phi)", FIELD)
    with pytest.raises(ExpressionError, match="non-finite value at phi="):
        expr.evaluate(np.array([0.0, math.pi / 2]))
    phi = np.array([0.3, math.pi / 2 - 1e-9, -1.2])
    np.testing.assert_array_equal(expr.evaluate(phi), 100 * np.tan(phi))


def test_long_flat_sums_are_accepted():
    """A sum of many terms is not nesting (it was refused as "nested too deeply")."""
    text = "+".join(f"{k}*phi" for k in range(1, MAX_DEPTH + 30))
    phi = np.array([0.3, 1.1])
    want = sum(k * phi for k in range(1, MAX_DEPTH + 30))
    np.testing.assert_allclose(parse_expression(text, FIELD).evaluate(phi), want, rtol=1e-13)


def test_rejections_are_short_for_long_inputs():
    err = _parse_error("phi+" * 200)
    assert len(str(err)) < 400


def test_first_offending_token_is_reported():
    # the function name is checked before its arguments
    assert "'open'" in str(_parse_error("open(x)"))
    assert "'x'" in str(_parse_error("sin(x) + open(1)"))


def test_max_length_is_inclusive():
    text = "phi" + " " * (MAX_LENGTH - 3)
    assert len(text) == MAX_LENGTH
    np.testing.assert_array_equal(parse_expression(text, FIELD).evaluate([1.0]), [1.0])


def test_expression_constructor_validates():
    with pytest.raises(ExpressionError, match="unknown name 'x'"):
        Expression(FIELD, "x")
    with pytest.raises(ExpressionError, match="expected a string expression"):
        Expression(FIELD, 3)  # type: ignore[arg-type]


def test_expression_is_frozen_comparable_and_picklable():
    expr = parse_expression(DOMAIN_LOAD, FIELD)
    assert expr == Expression(FIELD, DOMAIN_LOAD)
    assert hash(expr) == hash(Expression(FIELD, DOMAIN_LOAD))
    assert "text=" in repr(expr) and "_fn" not in repr(expr)
    with pytest.raises(dataclasses.FrozenInstanceError):
        expr.text = "phi"  # type: ignore[misc]
    clone = pickle.loads(pickle.dumps(expr))
    assert clone == expr
    phi = np.linspace(0, 6, 7)
    np.testing.assert_array_equal(clone.evaluate(phi), expr.evaluate(phi))


def test_error_is_picklable():
    err = _parse_error("-150*x")
    clone = pickle.loads(pickle.dumps(err))
    assert type(clone) is ExpressionError
    assert str(clone) == str(err)
    assert (clone.field, clone.token, clone.reason, clone.source) == (err.field, err.token, err.reason, err.source)


def test_error_without_source():
    err = ExpressionError("f", "tok", "reason about 'tok'")
    assert str(err) == "f: reason about 'tok'"


def test_no_eval_exec_or_code_compilation(monkeypatch):
    """Only ast.parse may call compile(), and only to build a syntax tree."""

    def forbidden(*args, **kwargs):
        raise AssertionError("eval/exec must never be called")

    real_compile = builtins.compile

    def ast_only_compile(source, filename, mode, flags=0, *args, **kwargs):
        assert flags & ast.PyCF_ONLY_AST, "compile() used to build code, not a syntax tree"
        return real_compile(source, filename, mode, flags, *args, **kwargs)

    monkeypatch.setattr(builtins, "eval", forbidden)
    monkeypatch.setattr(builtins, "exec", forbidden)
    monkeypatch.setattr(builtins, "compile", ast_only_compile)
    expr = parse_expression(DOMAIN_LOAD + " + where(t > 1, max(phi, 2), 0)**2", FIELD)
    expr.evaluate(np.linspace(0, 1, 3), np.array([[0.0], [2.0]]))
    with pytest.raises(ExpressionError):
        parse_expression("__import__('os').system('true')", FIELD)


def test_module_source_never_calls_eval_exec_compile():
    tree = ast.parse(Path(expressions.__file__).read_text())
    called = {
        node.func.id
        for node in ast.walk(tree)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
    }
    assert not called & {"eval", "exec", "compile", "__import__"}


# ---------------------------------------------------------------------------
# independent reference evaluator for the fuzz tests
# ---------------------------------------------------------------------------

U = 1e-15  # relative error allowed per libm call or propagated rounding (~4.5 ulp)
HUGE = 1e290  # finite values above this are too close to overflow to judge
TINY = 1e-290  # non-zero values below this are too close to underflow to judge
FUZZY_ZERO = 1e-300  # error bound given to a zero whose sign or exactness is uncertain
LN_MAX = 709.8  # slightly above ln(DBL_MAX) = 709.78


class Ambiguous(Exception):
    """Rounding differences could change this point's outcome; do not compare."""


def _check(v: float, e: float) -> tuple[float, float]:
    if math.isnan(e) or math.isinf(e):
        raise Ambiguous
    if not math.isfinite(v):
        return v, 0.0
    if abs(v) + e > HUGE or 0.0 < abs(v) < TINY:
        raise Ambiguous
    return v, e


def _rel(x: float, ex: float) -> float:
    """Relative error bound of x, requiring x to be clearly away from zero."""
    if ex == 0.0:
        return 0.0
    if abs(x) <= ex:
        raise Ambiguous
    return ex / (abs(x) - ex)


def _overflow_is_clear(log_magnitude: float, log_err: float) -> None:
    if log_magnitude - log_err <= LN_MAX:
        raise Ambiguous


def _c_pow(a: float, b: float) -> float:
    """C99 pow() on Python floats (math.pow raises where C returns inf/nan)."""
    odd_int = math.isfinite(b) and b.is_integer() and int(b) % 2 == 1
    try:
        return math.pow(a, b)
    except OverflowError:
        return -math.inf if (a < 0 and odd_int) else math.inf
    except ValueError:
        if a == 0.0 and b < 0:
            return math.copysign(math.inf, a) if odd_int else math.inf
        return math.nan


def _cmp(op: ast.cmpop, a: float, b: float) -> bool:
    if isinstance(op, ast.Lt):
        return a < b
    if isinstance(op, ast.LtE):
        return a <= b
    if isinstance(op, ast.Gt):
        return a > b
    if isinstance(op, ast.GtE):
        return a >= b
    if isinstance(op, ast.Eq):
        return a == b
    if isinstance(op, ast.NotEq):
        return a != b
    raise AssertionError(op)


class _Ref:
    """Point-wise evaluation of an accepted expression; returns (value, error bound)."""

    def __init__(self, phi: float, t: float):
        self.phi = float(phi)
        self.t = float(t)

    def __call__(self, node: ast.AST) -> tuple[float, float]:
        v, e = self.eval(node)
        return _check(v, e)

    def eval(self, node: ast.AST) -> tuple[float, float]:
        if isinstance(node, ast.Expression):
            return self(node.body)
        if isinstance(node, ast.Constant):
            assert type(node.value) in (int, float)
            return float(node.value), 0.0
        if isinstance(node, ast.Name):
            return {"phi": self.phi, "t": self.t, "pi": math.pi}[node.id], 0.0
        if isinstance(node, ast.UnaryOp):
            v, e = self(node.operand)
            if isinstance(node.op, ast.USub):
                return -v, e
            assert isinstance(node.op, ast.UAdd)
            return v, e
        if isinstance(node, ast.BinOp):
            return self.binop(node.op, self(node.left), self(node.right))
        if isinstance(node, ast.Compare):
            return self.compare(node)
        if isinstance(node, ast.Call):
            return self.call(node.func.id, node.args)
        raise AssertionError(f"generator produced {ast.dump(node)}")

    # -- arithmetic ----------------------------------------------------------
    def binop(self, op, x, y) -> tuple[float, float]:
        (a, ea), (b, eb) = x, y
        if isinstance(op, ast.Pow):
            return self.pow(a, ea, b, eb)
        if not (math.isfinite(a) and math.isfinite(b)):
            return self.binop_nonfinite(op, a, ea, b, eb)
        exact = ea == 0.0 and eb == 0.0
        if isinstance(op, (ast.Add, ast.Sub)):
            r = a + b if isinstance(op, ast.Add) else a - b
            e = 0.0 if exact else ea + eb + U * abs(r)
        elif isinstance(op, ast.Mult):
            r = a * b
            if math.isinf(r):
                if not exact:
                    _overflow_is_clear(math.log(abs(a)) + math.log(abs(b)), _rel(a, ea) + _rel(b, eb))
                return r, 0.0
            e = 0.0 if exact else abs(a) * eb + abs(b) * ea + ea * eb + U * abs(r)
        else:
            assert isinstance(op, ast.Div)
            if eb > 0.0 and abs(b) <= eb:
                raise Ambiguous  # divisor might be zero (or of either sign)
            if b == 0.0:  # exactly zero divisor
                if a == 0.0 and ea == 0.0:
                    return math.nan, 0.0
                if abs(a) <= ea:
                    raise Ambiguous
                return math.copysign(math.inf, a) * math.copysign(1.0, b), 0.0
            r = a / b
            if math.isinf(r):
                if not exact:
                    _overflow_is_clear(math.log(abs(a)) - math.log(abs(b)), _rel(a, ea) + _rel(b, eb))
                return r, 0.0
            e = 0.0 if exact else (ea + abs(r) * eb) / (abs(b) - eb) + U * abs(r)
        if r == 0.0 and not exact:
            e = max(e, FUZZY_ZERO)
        return r, e

    def binop_nonfinite(self, op, a, ea, b, eb) -> tuple[float, float]:
        if math.isnan(a) or math.isnan(b):
            return math.nan, 0.0
        if isinstance(op, ast.Add):
            return a + b, 0.0
        if isinstance(op, ast.Sub):
            return a - b, 0.0
        if isinstance(op, ast.Mult):
            x, ex = (b, eb) if math.isinf(a) else (a, ea)
            if math.isfinite(x):
                if x == 0.0 and ex == 0.0:
                    return math.nan, 0.0
                if abs(x) <= ex:
                    raise Ambiguous
            return a * b, 0.0
        assert isinstance(op, ast.Div)
        if math.isinf(a) and math.isinf(b):
            return math.nan, 0.0
        if math.isinf(a):  # inf / finite
            if b == 0.0 and eb == 0.0:
                return a * math.copysign(1.0, b), 0.0
            if abs(b) <= eb:
                raise Ambiguous
            return a / b, 0.0
        # finite / inf -> signed zero
        if abs(a) <= ea and ea > 0.0:
            return 0.0, FUZZY_ZERO
        return a / b, 0.0

    def pow(self, a, ea, b, eb) -> tuple[float, float]:
        if not (math.isfinite(a) and math.isfinite(b)):
            if ea > 0.0 or eb > 0.0:
                raise Ambiguous
            return _c_pow(a, b), 0.0
        r = _c_pow(a, b)
        if ea == 0.0 and eb == 0.0:
            if math.isinf(r) and a != 0.0:
                _overflow_is_clear(b * math.log(abs(a)), 0.0)
            return (r, 0.0) if not math.isfinite(r) else (r, U * abs(r))
        if abs(a) <= ea:
            raise Ambiguous  # base near zero: pole, sign or domain could change
        if a < 0.0:
            if eb > 0.0:
                raise Ambiguous  # integrality of an inexact exponent is unknowable
            if not b.is_integer():
                return math.nan, 0.0
        log_a = math.log(abs(a))
        log_err = abs(b) * ea / (abs(a) - ea) + abs(log_a) * eb
        if math.isinf(r):
            _overflow_is_clear(b * log_a, log_err)
            return r, 0.0
        e = abs(r) * math.expm1(min(log_err, 700.0)) + U * abs(r)
        if r == 0.0:
            e = max(e, FUZZY_ZERO)
        return r, e

    # -- comparisons ---------------------------------------------------------
    def compare(self, node: ast.Compare) -> tuple[float, float]:
        values = [self(n) for n in [node.left, *node.comparators]]
        truths = []
        for i, op in enumerate(node.ops):
            (a, ea), (b, eb) = values[i], values[i + 1]
            if math.isnan(a) or math.isnan(b):
                truths.append(isinstance(op, ast.NotEq))
            elif math.isinf(a) or math.isinf(b):
                truths.append(_cmp(op, a, b))
            elif ea + eb > 0.0 and abs(a - b) <= ea + eb:
                truths.append(None)
            else:
                truths.append(_cmp(op, a, b))
        if False in truths:
            return 0.0, 0.0
        if None in truths:
            raise Ambiguous
        return 1.0, 0.0

    # -- functions -----------------------------------------------------------
    def call(self, name: str, args: list[ast.AST]) -> tuple[float, float]:
        if name == "where":
            c, ec = self(args[0])
            if math.isnan(c):
                return math.nan, 0.0
            if ec > 0.0 and abs(c) <= ec:
                raise Ambiguous
            return self(args[1]) if c != 0.0 else self(args[2])
        if name in ("min", "max"):
            acc = self(args[0])
            for arg in args[1:]:
                acc = self.minmax(name, acc, self(arg))
            return acc
        a, ea = self(args[0])
        return getattr(self, "f_" + name)(a, ea)

    @staticmethod
    def minmax(name, x, y) -> tuple[float, float]:
        (a, ea), (b, eb) = x, y
        if math.isnan(a) or math.isnan(b):
            return math.nan, 0.0
        if a == b == 0.0 and math.copysign(1.0, a) != math.copysign(1.0, b):
            raise Ambiguous  # which signed zero is returned is NumPy's business
        r = min(a, b) if name == "min" else max(a, b)
        return r, max(ea, eb)

    @staticmethod
    def f_sin(a, ea):
        if not math.isfinite(a):
            return math.nan, 0.0
        r = math.sin(a)
        return r, min(ea, 2.0) + U * abs(r)

    @staticmethod
    def f_cos(a, ea):
        if not math.isfinite(a):
            return math.nan, 0.0
        r = math.cos(a)
        return r, min(ea, 2.0) + U * abs(r)

    @staticmethod
    def f_tan(a, ea):
        if not math.isfinite(a):
            return math.nan, 0.0
        if abs(math.cos(a)) <= 4.0 * 2.0 ** -52 * max(1.0, abs(a)):
            raise Ambiguous  # within the argument's rounding of a pole: the product says inf
        r = math.tan(a)
        if ea == 0.0:
            return r, U * abs(r)
        c = abs(math.cos(a))
        if ea >= 0.5 * c:
            raise Ambiguous  # a pole may lie within the error interval
        return r, ea / (c - ea) ** 2 + U * abs(r)

    @staticmethod
    def f_exp(a, ea):
        if not math.isfinite(a):
            return (math.nan if math.isnan(a) else math.exp(a)), 0.0
        if a - ea > LN_MAX:
            return math.inf, 0.0
        if a + ea > 709.0:
            raise Ambiguous
        r = math.exp(a)
        e = abs(r) * math.expm1(ea) + U * abs(r)
        if r == 0.0 and ea > 0.0:
            e = max(e, FUZZY_ZERO)
        return r, e

    @staticmethod
    def f_log(a, ea):
        if math.isnan(a) or a == -math.inf:
            return math.nan, 0.0
        if a == math.inf:
            return math.inf, 0.0
        if a == 0.0 and ea == 0.0:
            return -math.inf, 0.0
        if abs(a) <= ea:
            raise Ambiguous
        if a < 0.0:
            return math.nan, 0.0
        r = math.log(a)
        e = (-math.log1p(-ea / a) if ea > 0.0 else 0.0) + U * abs(r)
        if r == 0.0 and ea > 0.0:
            e = max(e, FUZZY_ZERO)
        return r, e

    @staticmethod
    def f_sqrt(a, ea):
        if math.isnan(a) or a == -math.inf:
            return math.nan, 0.0
        if a == math.inf:
            return math.inf, 0.0
        if ea > 0.0 and abs(a) <= ea:
            raise Ambiguous
        if a == 0.0:
            return a, 0.0  # sqrt(-0.0) is -0.0 (IEEE 754)
        if a < 0.0:
            return math.nan, 0.0
        r = math.sqrt(a)
        return r, (0.0 if ea == 0.0 else ea / r + U * r)

    @staticmethod
    def f_abs(a, ea):
        return abs(a), ea

    @staticmethod
    def f_sign(a, ea):
        if math.isnan(a):
            return math.nan, 0.0
        if ea > 0.0 and abs(a) <= ea:
            raise Ambiguous
        return (1.0 if a > 0 else -1.0 if a < 0 else 0.0), 0.0


def reference(tree: ast.Expression, phi: float, t: float) -> tuple[str, float, float]:
    """('ambiguous', nan, nan) | ('nonfinite', v, 0) | ('value', v, error bound)."""
    try:
        v, e = _Ref(phi, t)(tree)
    except Ambiguous:
        return "ambiguous", math.nan, math.nan
    if not math.isfinite(v):
        return "nonfinite", v, 0.0
    return "value", v, e


def test_reference_evaluator_sanity():
    """The reference agrees with plain arithmetic and flags what it should."""

    def ref(text, phi=0.0, t=0.0):
        return reference(ast.parse(text, mode="eval"), phi, t)

    assert ref("-150*(1 + 0.2*sin(2*phi))", math.pi / 4)[0] == "value"
    assert ref("-150*(1 + 0.2*sin(2*phi))", math.pi / 4)[1] == pytest.approx(-180.0, rel=1e-15)
    assert ref("2**3")[1:] == (8.0, U * 8.0)
    assert ref("1/phi")[0] == "nonfinite"
    assert ref("log(phi)")[0] == "nonfinite"
    assert ref("log(phi - 1)", 0.5)[0] == "nonfinite"
    assert ref("where(phi > 0, log(phi), 0)", -1.0)[:2] == ("value", 0.0)
    assert ref("1/(1/phi)")[:2] == ("value", 0.0)
    assert ref("sin(phi) - sin(phi) > 0", 1.0)[0] == "ambiguous"
    assert ref("1/(sin(phi) - sin(phi))", 1.0)[0] == "ambiguous"
    assert ref("phi > 1", 1.0)[:2] == ("value", 0.0)  # exact inputs compare exactly
    assert ref("exp(1000)")[0] == "nonfinite"
    assert ref("exp(709.5)")[0] == "ambiguous"


# ---------------------------------------------------------------------------
# fuzzing (a): random accepted expressions vs. the reference evaluator
# ---------------------------------------------------------------------------

_ws = st.sampled_from(["", " "])
_numbers = st.one_of(
    st.integers(0, 1000).map(str),
    st.floats(0.0, 1000.0).filter(lambda x: x == 0.0 or x > 1e-6).map(repr),
    st.sampled_from(["0.5", ".25", "2.", "1e-3", "1E2", "2.5e1", "0", "1", "3"]),
)
_leaves = st.one_of(_numbers, st.sampled_from(["phi", "t", "pi"]))
_UNARY = ["sin", "cos", "tan", "exp", "log", "sqrt", "abs", "sign"]
_BINARY = ["+", "-", "*", "/", "**"]
_COMPARE = ["<", "<=", ">", ">=", "==", "!="]


def _maybe_paren(s: str, wrap: bool) -> str:
    return f"({s})" if wrap else s


def _extend(children):
    binary = st.tuples(children, st.sampled_from(_BINARY), children, st.booleans(), st.booleans(), _ws).map(
        lambda p: f"{_maybe_paren(p[0], p[3])}{p[5]}{p[1]}{p[5]}{_maybe_paren(p[2], p[4])}"
    )
    compare = st.tuples(children, st.sampled_from(_COMPARE), children, _ws).map(
        lambda p: f"({p[0]}{p[3]}{p[1]}{p[3]}{p[2]})"
    )
    chained = st.tuples(children, st.sampled_from(_COMPARE), children, st.sampled_from(_COMPARE), children).map(
        lambda p: f"({p[0]} {p[1]} {p[2]} {p[3]} {p[4]})"
    )
    unary_op = st.tuples(st.sampled_from(["-", "+"]), children, st.booleans()).map(
        lambda p: f"{p[0]}{_maybe_paren(p[1], p[2])}"
    )
    function = st.tuples(st.sampled_from(_UNARY), children).map(lambda p: f"{p[0]}({p[1]})")
    minmax = st.tuples(st.sampled_from(["min", "max"]), st.lists(children, min_size=2, max_size=4), _ws).map(
        lambda p: f"{p[0]}({(',' + p[2]).join(p[1])})"
    )
    where = st.tuples(children, children, children).map(lambda p: f"where({p[0]}, {p[1]}, {p[2]})")
    return st.one_of(binary, compare, chained, unary_op, function, minmax, where, children.map(lambda s: f"({s})"))


accepted_expressions = st.recursive(_leaves, _extend, max_leaves=10)

PHI_GRID = np.array([-7.0, -math.pi, -1.0, -0.5, 0.0, 0.5, 1.0, math.pi / 2, math.pi, 2.0, 6.5])
T_GRID = np.array([0.0, 0.25, 1.0, 3.0])


def _tree_depth(node: ast.AST) -> int:
    """Nesting depth as the parser counts it: a chain a + b + c is flat (the
    left operand of a binary operator that is itself one adds no level)."""
    children = [c for c in ast.iter_child_nodes(node) if isinstance(c, ast.expr)]
    return 1 + max((_tree_depth(c) - (isinstance(node, ast.BinOp) and c is node.left
                                      and isinstance(c, ast.BinOp)) for c in children),
                   default=0)


def _assert_close(got: float, want: float, err: float, context: str) -> None:
    assert math.isfinite(got), context
    assert abs(got - want) <= RTOL * abs(want) + err + 1e-300, f"{context}: got {got!r}, want {want!r} +- {err:g}"


@settings(max_examples=250, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(text=accepted_expressions, extra_phi=st.lists(st.floats(-10.0, 10.0), max_size=2))
def test_fuzz_accepted_expressions_match_reference(text, extra_phi):
    tree = ast.parse(text.strip(), mode="eval")
    if len(text) > MAX_LENGTH or _tree_depth(tree) > MAX_DEPTH - 2:
        with pytest.raises(ExpressionError, match="too long|too deeply"):
            parse_expression(text, FIELD)
        return
    expr = parse_expression(text, FIELD)
    assert expr.depends_on_time == any(isinstance(n, ast.Name) and n.id == "t" for n in ast.walk(tree))

    phi = np.concatenate([PHI_GRID, np.array(extra_phi, dtype=np.float64)])
    expected = [[reference(tree, p, tt) for tt in T_GRID] for p in phi]
    kinds = {cell[0] for row in expected for cell in row}

    # the whole grid at once
    try:
        grid = expr.evaluate(phi[:, None], T_GRID[None, :])
    except ExpressionError as exc:
        assert str(exc).startswith(FIELD + ": ") and "non-finite value at phi=" in str(exc)
        assert kinds - {"value"}, f"{text!r} raised {exc} but the reference is finite everywhere"
        grid = None
    else:
        assert "nonfinite" not in kinds, f"{text!r} evaluated without error, reference has non-finite values"
        assert grid.shape == (len(phi), len(T_GRID)) and grid.dtype == np.float64

    # point by point (also covers the points of a grid that raised)
    for i, p in enumerate(phi):
        for j, tt in enumerate(T_GRID):
            kind, want, err = expected[i][j]
            context = f"{text!r} at phi={p!r}, t={tt!r}"
            if kind == "ambiguous":
                continue
            if kind == "nonfinite":
                with pytest.raises(ExpressionError, match="non-finite value"):
                    expr.evaluate(p, tt)
                continue
            got = float(expr.evaluate(p, tt))
            _assert_close(got, want, err, context)
            if grid is not None:
                _assert_close(float(grid[i, j]), want, err, context + " (grid)")


# ---------------------------------------------------------------------------
# fuzzing (b): random text either parses and evaluates, or raises ExpressionError
# ---------------------------------------------------------------------------

_ALLOWED_TOKENS = [
    "phi", "t", "pi", "0", "1", "2.5", "1e3", ".5", "+", "-", "*", "/", "**", "(", ")", ",",
    "<", "<=", ">", ">=", "==", "!=", " ", "sin", "cos", "tan", "exp", "log", "sqrt", "abs",
    "min", "max", "where", "sign",
]  # fmt: skip
_DISALLOWED_TOKENS = [
    "x", "e", "__import__", "open", "os", ".", "__class__", "[", "]", "{", "}", ":", "lambda",
    "'a'", '"b"', "and", "or", "not", "if", "else", "for", "in", "is", "//", "%", "@", "~", "&",
    "|", "^", "<<", ">>", "=", ":=", "1j", "1e999", "9" * 330, "None", "True", "...", "#", "\\",
    "\n", "\t", "\r", ";", "`", "$", "?", "!", "yield", "await", "import", "f'{x}'", "**kw", "*",
    "0x1F", "1_0", ".real", "getattr", "eval", "exec", "compile", "globals", "φ", "\x00", "\x0c",
    "ｐｈｉ", "'''", '"""', "\\N{DIGIT ONE}", "b'", "r'", "async", "def", "class", "return", "del",
]  # fmt: skip

_token_soup = st.lists(st.sampled_from(_ALLOWED_TOKENS + _DISALLOWED_TOKENS), max_size=40)

@st.composite
def _mutated_expressions(draw):
    """An accepted expression with one token inserted, or one stretch replaced."""
    text = draw(accepted_expressions)
    token = draw(st.sampled_from(_ALLOWED_TOKENS + _DISALLOWED_TOKENS))
    i = draw(st.integers(0, len(text)))
    j = draw(st.integers(i, min(len(text), i + 4)))
    return text[:i] + token + text[j:]


_random_text = st.one_of(
    _mutated_expressions(),
    st.text(max_size=60),
    st.text(alphabet=st.characters(min_codepoint=0, max_codepoint=127), max_size=60),
    st.text(alphabet="phisncoqrtexplgwmab()+-*/<>=!,. 0123456789_", max_size=60),
    _token_soup.map("".join),
    _token_soup.map(" ".join),
    st.lists(st.sampled_from(_ALLOWED_TOKENS), max_size=60).map("".join),
)

_PHI_SMALL = np.array([-1.0, 0.0, 0.5, 3.0])
_T_SMALL = np.array([0.0, 2.0])


@settings(max_examples=600, database=None)   # deadline: the profile's (none)
@given(text=_random_text)
def test_fuzz_random_text_parses_or_raises_expression_error(text):
    try:
        expr = parse_expression(text, FIELD)
    except ExpressionError as exc:
        message = str(exc)
        assert message.startswith(FIELD + ": ")
        assert exc.token in message
        return
    try:
        got = expr.evaluate(_PHI_SMALL[:, None], _T_SMALL[None, :])
    except ExpressionError as exc:
        assert "non-finite value at phi=" in str(exc)
        return
    assert got.shape == (4, 2)
    assert got.dtype == np.float64
    assert np.isfinite(got).all()
