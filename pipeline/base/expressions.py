"""Whitelisted load expressions of the crank angle ``phi`` and time ``t``.

Study files give external loads as short formulas, e.g.
``fy = "-150*(1 + 0.2*sin(2*phi))"`` (DOMAIN.md section 6).  This module turns
such a formula into an :class:`Expression` that can be evaluated on NumPy
arrays, and rejects everything outside a small whitelist:

* numbers (finite, real), the names ``phi`` (crank angle, rad), ``t`` (time,
  s) and ``pi``;
* ``+ - * / **`` and unary ``+``/``-``;
* comparisons ``< <= > >= == !=``, which give ``1.0`` or ``0.0``; chained
  comparisons follow Python, ``0 <= phi < pi`` means
  ``(0 <= phi) and (phi < pi)``;
* parentheses;
* the functions ``sin cos tan exp log sqrt abs sign`` (one argument),
  ``min max`` (two or more) and ``where(cond, a, b)`` (``a`` where ``cond`` is
  non-zero, else ``b``; a NaN condition gives NaN).

The text is parsed with :func:`ast.parse` in ``"eval"`` mode, only to obtain
the syntax tree; the tree is then walked here and compiled into a tree of
closures over NumPy ufuncs.  Nothing is ever passed to ``eval``, ``exec`` or
``compile``.  Every rejection is an :class:`ExpressionError` whose message
names the study field and the offending token, e.g.::

    studies/foo.toml: loads[0].fy: unknown name 'x' in "-150*x"

Evaluation follows IEEE arithmetic (``log(0) = -inf``, ``sqrt(-1) = nan``,
``1/0 = inf``); intermediate non-finite values are allowed (for instance in the
branch of ``where`` that is not selected), but a non-finite value anywhere in
the *result* raises :class:`ExpressionError`.
"""

from __future__ import annotations

import ast
import math
import re
import warnings
from dataclasses import dataclass
from dataclasses import field as _dc_field
from typing import Callable

import numpy as np

__all__ = [
    "MAX_DEPTH",
    "MAX_LENGTH",
    "Expression",
    "ExpressionError",
    "parse_expression",
]

#: Longest accepted expression text, in characters.
MAX_LENGTH = 500
#: Deepest accepted nesting, counted both in brackets and in syntax-tree levels.
MAX_DEPTH = 40
MAX_TERMS = 200     # operands of one chain a + b + c ... (evaluated by recursion)

_Fn = Callable[[np.ndarray, np.ndarray], np.ndarray]

def _power(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a ** b`` with C99 ``pow`` semantics for every element.

    NumPy replaces ``x ** 0.5`` by ``sqrt(x)`` when the exponent is a scalar
    (or a broadcast, stride-0 array), which differs from ``pow`` at ``-inf``
    and ``-0.0``.  Passing both operands as contiguous arrays of the full
    shape keeps the element-wise ``pow`` loop, so ``phi**0.5`` and
    ``phi**(0.5 + 0*t)`` agree.
    """
    a_b, b_b = np.broadcast_arrays(a, b)
    out = np.power(np.array(a_b, dtype=np.float64, ndmin=1), np.array(b_b, dtype=np.float64, ndmin=1))
    return out.reshape(a_b.shape)


_POLE = 4.0 * np.finfo(np.float64).eps


def _tan(x: np.ndarray) -> np.ndarray:
    """tan, infinite where the argument lies within its own rounding of a pole
    (there the library gives a large finite number that means nothing:
    tan(pi/2) = 1.6e16), so a load with a pole is reported, not used."""
    x = np.asarray(x, dtype=np.float64)
    r = np.tan(x)
    pole = np.abs(np.cos(x)) <= _POLE * np.maximum(1.0, np.abs(x))
    return np.where(pole, np.copysign(np.inf, r), r)


_UNARY_FUNCTIONS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "sin": np.sin,
    "cos": np.cos,
    "tan": _tan,
    "exp": np.exp,
    "log": np.log,
    "sqrt": np.sqrt,
    "abs": np.abs,
    "sign": np.sign,
}
_VARIADIC_FUNCTIONS: dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]] = {
    "min": np.minimum,  # NaN-propagating
    "max": np.maximum,
}
_FUNCTIONS = frozenset(_UNARY_FUNCTIONS) | frozenset(_VARIADIC_FUNCTIONS) | {"where"}
_ALLOWED_FUNCTIONS_TEXT = ", ".join(sorted(_FUNCTIONS))
_VARIABLES = ("phi", "t", "pi")

_BINARY_OPS: dict[type, Callable[[np.ndarray, np.ndarray], np.ndarray]] = {
    ast.Add: np.add,
    ast.Sub: np.subtract,
    ast.Mult: np.multiply,
    ast.Div: np.true_divide,
    ast.Pow: _power,
}
_REJECTED_BINARY_OPS: dict[type, str] = {
    ast.FloorDiv: "//",
    ast.Mod: "%",
    ast.MatMult: "@",
    ast.LShift: "<<",
    ast.RShift: ">>",
    ast.BitOr: "|",
    ast.BitXor: "^",
    ast.BitAnd: "&",
}
_COMPARE_OPS: dict[type, Callable[[np.ndarray, np.ndarray], np.ndarray]] = {
    ast.Lt: np.less,
    ast.LtE: np.less_equal,
    ast.Gt: np.greater,
    ast.GtE: np.greater_equal,
    ast.Eq: np.equal,
    ast.NotEq: np.not_equal,
}
_REJECTED_COMPARE_OPS: dict[type, str] = {
    ast.Is: "is",
    ast.IsNot: "is not",
    ast.In: "in",
    ast.NotIn: "not in",
}
_NODE_KINDS: dict[type, str] = {
    ast.List: "list",
    ast.Tuple: "tuple",
    ast.Set: "set",
    ast.Dict: "dict",
    ast.ListComp: "comprehension",
    ast.SetComp: "comprehension",
    ast.DictComp: "comprehension",
    ast.GeneratorExp: "generator expression",
    ast.JoinedStr: "f-string",
    ast.FormattedValue: "f-string",
    ast.Await: "await",
    ast.Yield: "yield",
    ast.YieldFrom: "yield",
    ast.Slice: "slice",
}

# Characters that may appear at all.  Non-ASCII is refused up front because
# Python NFKC-normalises identifiers (a full-width 'ｐｈｉ' would become 'phi');
# '#' would silently comment out the rest and '\\' continues lines.
_FORBIDDEN_CHARS = {"#": "comment '#'", "\\": "backslash '\\'"}
_SYNTAX_TOKEN = re.compile(r"\s*(\w+|\*\*|//|<=|>=|==|!=|:=|<<|>>|\S)")


def _display(source: str, limit: int = 120) -> str:
    """One-line, length-limited rendering of an expression for messages."""
    flat = re.sub(r"[\t\r\n]+", " ", source)
    flat = "".join(ch if ch.isprintable() else repr(ch)[1:-1] for ch in flat)
    return flat if len(flat) <= limit else flat[: limit - 3] + "..."


def _short(token: str, limit: int = 40) -> str:
    return token if len(token) <= limit else token[: limit - 3] + "..."


class ExpressionError(ValueError):
    """A load expression was rejected or evaluated to a non-finite value.

    The message is ``"<field>: <reason>"`` followed by ``' in "<source>"'`` when
    the source text is known; ``reason`` quotes ``token``.
    """

    def __init__(self, field: str, token: str, reason: str, source: str | None = None):
        self.field = field
        self.token = token
        self.reason = reason
        self.source = source
        message = f"{field}: {reason}"
        if source is not None:
            message += f' in "{_display(source)}"'
        super().__init__(message)

    def __reduce__(self):  # keep pickling (e.g. to Dask workers) working
        return (type(self), (self.field, self.token, self.reason, self.source))


def _const(value: float) -> _Fn:
    c = np.float64(value)

    def fn(phi: np.ndarray, t: np.ndarray) -> np.ndarray:
        return c

    return fn


def _phi(phi: np.ndarray, t: np.ndarray) -> np.ndarray:
    return phi


def _time(phi: np.ndarray, t: np.ndarray) -> np.ndarray:
    return t


def _unary(op: Callable[[np.ndarray], np.ndarray], a: _Fn) -> _Fn:
    def fn(phi: np.ndarray, t: np.ndarray) -> np.ndarray:
        return op(a(phi, t))

    return fn


def _binary(op: Callable[[np.ndarray, np.ndarray], np.ndarray], a: _Fn, b: _Fn) -> _Fn:
    def fn(phi: np.ndarray, t: np.ndarray) -> np.ndarray:
        return op(a(phi, t), b(phi, t))

    return fn


def _reduce(op: Callable[[np.ndarray, np.ndarray], np.ndarray], args: list[_Fn]) -> _Fn:
    first, rest = args[0], args[1:]

    def fn(phi: np.ndarray, t: np.ndarray) -> np.ndarray:
        acc = first(phi, t)
        for g in rest:
            acc = op(acc, g(phi, t))
        return acc

    return fn


def _compare(ops: list[Callable[[np.ndarray, np.ndarray], np.ndarray]], operands: list[_Fn]) -> _Fn:
    def fn(phi: np.ndarray, t: np.ndarray) -> np.ndarray:
        values = [g(phi, t) for g in operands]  # each operand evaluated once
        truth = ops[0](values[0], values[1])
        for i in range(1, len(ops)):
            truth = np.logical_and(truth, ops[i](values[i], values[i + 1]))
        return np.asarray(truth, dtype=np.float64)

    return fn


def _where(cond: _Fn, a: _Fn, b: _Fn) -> _Fn:
    def fn(phi: np.ndarray, t: np.ndarray) -> np.ndarray:
        c = cond(phi, t)
        chosen = np.where(c != 0, a(phi, t), b(phi, t))
        return np.where(np.isnan(c), np.nan, chosen)

    return fn


class _Compiler:
    """Walks the syntax tree of one expression and builds its closure tree."""

    def __init__(self, field: str, text: str, src: str):
        self.field = field
        self.text = text  # as given, for messages
        self.src = src  # stripped text that was parsed; node offsets refer to it
        self.uses_phi = False
        self.uses_t = False

    # -- helpers -----------------------------------------------------------
    def error(self, token: str, reason: str) -> ExpressionError:
        return ExpressionError(self.field, token, reason, self.text)

    def segment(self, node: ast.AST) -> str:
        """Source text of ``node``, on one line and length-limited."""
        seg = ast.get_source_segment(self.src, node)
        if seg is None:  # pragma: no cover - every parsed node has positions
            seg = ast.unparse(node)
        return _short(" ".join(seg.split()))

    # -- dispatch ----------------------------------------------------------
    def compile(self, node: ast.AST, depth: int) -> _Fn:
        if depth > MAX_DEPTH:
            token = self.segment(node)
            raise self.error(token, f"expression nested too deeply (more than {MAX_DEPTH} levels) at '{token}'")
        method = getattr(self, "_c_" + type(node).__name__, None)
        if method is None:
            raise self._rejected(node)
        return method(node, depth + 1)

    def _rejected(self, node: ast.AST) -> ExpressionError:
        seg = self.segment(node)
        if isinstance(node, ast.Attribute):
            token = "." + node.attr
            return self.error(token, f"attribute access '{token}' is not allowed")
        if isinstance(node, ast.Subscript):
            return self.error(seg, f"subscript '{seg}' is not allowed")
        if isinstance(node, ast.Lambda):
            return self.error("lambda", "'lambda' is not allowed")
        if isinstance(node, ast.BoolOp):
            word = "and" if isinstance(node.op, ast.And) else "or"
            return self.error(
                word, f"boolean operator '{word}' is not allowed (use comparisons, min, max or where)"
            )
        if isinstance(node, ast.IfExp):
            return self.error("if", "conditional expression 'if ... else' is not allowed (use where(cond, a, b))")
        if isinstance(node, ast.NamedExpr):
            return self.error(":=", "assignment ':=' is not allowed")
        if isinstance(node, ast.Starred):
            return self.error(seg, f"starred expression '{seg}' is not allowed")
        kind = _NODE_KINDS.get(type(node), type(node).__name__.lower())
        return self.error(seg, f"{kind} '{seg}' is not allowed")

    # -- leaves ------------------------------------------------------------
    def _c_Expression(self, node: ast.Expression, depth: int) -> _Fn:
        return self.compile(node.body, depth)

    def _c_Constant(self, node: ast.Constant, depth: int) -> _Fn:
        value = node.value
        seg = self.segment(node)
        if isinstance(value, bool) or value is None or value is Ellipsis:
            raise self.error(seg, f"constant '{seg}' is not allowed")
        if isinstance(value, (int, float)):
            try:
                number = float(value)
            except OverflowError:
                number = math.inf
            if not math.isfinite(number):
                raise self.error(seg, f"number '{seg}' is out of range (not a finite float)")
            return _const(number)
        if isinstance(value, complex):
            raise self.error(seg, f"complex number '{seg}' is not allowed")
        if isinstance(value, (str, bytes)):
            raise self.error(seg, f"string {seg} is not allowed")
        raise self.error(seg, f"constant '{seg}' is not allowed")  # pragma: no cover

    def _c_Name(self, node: ast.Name, depth: int) -> _Fn:
        name = node.id
        if name == "phi":
            self.uses_phi = True
            return _phi
        if name == "t":
            self.uses_t = True
            return _time
        if name == "pi":
            return _const(math.pi)
        if name in _FUNCTIONS:
            raise self.error(name, f"function '{name}' must be called, e.g. '{name}(phi)'")
        raise self.error(name, f"unknown name '{name}' (allowed names: phi, t, pi)")

    # -- operators ---------------------------------------------------------
    def _c_UnaryOp(self, node: ast.UnaryOp, depth: int) -> _Fn:
        if isinstance(node.op, ast.Not):
            raise self.error("not", "boolean operator 'not' is not allowed (use comparisons or where)")
        if isinstance(node.op, ast.Invert):
            raise self.error("~", "operator '~' is not allowed")
        operand = self.compile(node.operand, depth)
        if isinstance(node.op, ast.USub):
            return _unary(np.negative, operand)
        return _unary(np.positive, operand)  # ast.UAdd

    def _c_BinOp(self, node: ast.BinOp, depth: int) -> _Fn:
        op = _BINARY_OPS.get(type(node.op))
        if op is None:
            symbol = _REJECTED_BINARY_OPS.get(type(node.op), type(node.op).__name__)
            raise self.error(symbol, f"operator '{symbol}' is not allowed")
        # a + b + c + ... is a flat chain in the source (a left-leaning tree here):
        # its length is limited, not counted as nesting
        terms, x = 1, node
        while isinstance(x, ast.BinOp):
            terms, x = terms + 1, x.left
        if terms > MAX_TERMS:
            token = self.segment(node)
            raise self.error(token, f"more than {MAX_TERMS} terms in one chain of operators "
                                    f"at '{token}'")
        left = self.compile(node.left, depth - 1 if isinstance(node.left, ast.BinOp) else depth)
        right = self.compile(node.right, depth)
        return _binary(op, left, right)

    def _c_Compare(self, node: ast.Compare, depth: int) -> _Fn:
        ops = []
        for op_node in node.ops:
            op = _COMPARE_OPS.get(type(op_node))
            if op is None:
                symbol = _REJECTED_COMPARE_OPS.get(type(op_node), type(op_node).__name__)
                raise self.error(symbol, f"comparison '{symbol}' is not allowed")
            ops.append(op)
        operands = [self.compile(n, depth) for n in [node.left, *node.comparators]]
        return _compare(ops, operands)

    def _c_Call(self, node: ast.Call, depth: int) -> _Fn:
        func = node.func
        if not isinstance(func, ast.Name):
            if isinstance(func, ast.Attribute):
                raise self._rejected(func)
            seg = self.segment(func)
            raise self.error(seg, f"call of '{seg}' is not allowed")
        name = func.id
        if name not in _FUNCTIONS:
            if name in _VARIABLES:
                raise self.error(name, f"'{name}' is not a function")
            raise self.error(
                name, f"function '{name}' is not allowed (allowed functions: {_ALLOWED_FUNCTIONS_TEXT})"
            )
        if node.keywords:
            kw = node.keywords[0]
            if kw.arg is None:
                token = "**" + self.segment(kw.value)
                raise self.error(token, f"keyword unpacking '{token}' is not allowed in call of '{name}'")
            raise self.error(kw.arg, f"keyword argument '{kw.arg}' is not allowed in call of '{name}'")
        for arg in node.args:
            if isinstance(arg, ast.Starred):
                token = self.segment(arg)
                raise self.error(token, f"starred argument '{token}' is not allowed in call of '{name}'")
        n = len(node.args)
        if name in _UNARY_FUNCTIONS and n != 1:
            raise self.error(name, f"function '{name}' takes exactly 1 argument ({n} given)")
        if name in _VARIADIC_FUNCTIONS and n < 2:
            raise self.error(name, f"function '{name}' takes at least 2 arguments ({n} given)")
        if name == "where" and n != 3:
            raise self.error(name, f"function 'where' takes exactly 3 arguments (cond, a, b) ({n} given)")
        args = [self.compile(a, depth) for a in node.args]
        if name in _UNARY_FUNCTIONS:
            return _unary(_UNARY_FUNCTIONS[name], args[0])
        if name in _VARIADIC_FUNCTIONS:
            return _reduce(_VARIADIC_FUNCTIONS[name], args)
        return _where(*args)


def _syntax_error(field: str, text: str, exc: SyntaxError) -> ExpressionError:
    token = None
    line, offset = exc.text, exc.offset
    if line is not None and offset is not None and offset >= 1:
        match = _SYNTAX_TOKEN.match(line[offset - 1 :])
        if match:
            token = match.group(1)
    msg = exc.msg or "invalid syntax"
    if token is None:
        return ExpressionError(field, "end of expression", f"syntax error at end of expression ({msg})", text)
    return ExpressionError(field, token, f"syntax error at '{token}' ({msg})", text)


def _compile_text(text: object, field: str) -> tuple[_Fn, bool, bool]:
    """Validate and compile ``text``; returns (function, uses_phi, uses_t)."""
    if not isinstance(text, str):
        kind = type(text).__name__
        raise ExpressionError(field, kind, f"expected a string expression or a number, got {kind}")
    if len(text) > MAX_LENGTH:
        token = f"{len(text)} characters"
        raise ExpressionError(field, token, f"expression is too long ({token}, limit {MAX_LENGTH})", text)
    # Line breaks (TOML multi-line strings) are plain blanks here; replacing
    # them one for one keeps every column offset valid for messages.
    src = text.replace("\r", " ").replace("\n", " ").strip()
    if not src:
        raise ExpressionError(field, "", "empty expression", text)
    for ch in src:
        if ch in _FORBIDDEN_CHARS:
            what = _FORBIDDEN_CHARS[ch]
            raise ExpressionError(field, ch, f"{what} is not allowed", text)
        if not (" " <= ch <= "~" or ch in "\t\n\r"):
            token = ch if ch.isprintable() else repr(ch)[1:-1]
            raise ExpressionError(field, token, f"character '{token}' is not allowed", text)
    level = 0
    for ch in src:
        if ch in "([{":
            level += 1
            if level > MAX_DEPTH:
                raise ExpressionError(
                    field, ch, f"brackets nested too deeply (more than {MAX_DEPTH} levels) at '{ch}'", text
                )
        elif ch in ")]}":
            level -= 1
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # e.g. SyntaxWarning for '1(2)'; rejected below anyway
            tree = ast.parse(src, mode="eval")
    except SyntaxError as exc:
        raise _syntax_error(field, text, exc) from None
    except (ValueError, MemoryError, RecursionError) as exc:  # pragma: no cover - defensive
        raise ExpressionError(field, _short(src), f"cannot parse '{_short(src)}' ({exc})", text) from None
    compiler = _Compiler(field, text, src)
    fn = compiler.compile(tree, 0)
    return fn, compiler.uses_phi, compiler.uses_t


@dataclass(frozen=True)
class Expression:
    """A validated load expression of ``phi`` (rad) and ``t`` (s).

    ``field`` is the full location used in messages, e.g.
    ``"studies/x.toml: loads[0].fy"``.  Constructing an ``Expression`` directly
    validates ``text`` exactly like :func:`parse_expression`.
    """

    field: str
    text: str
    _fn: _Fn = _dc_field(init=False, repr=False, compare=False)
    _uses_phi: bool = _dc_field(init=False, repr=False, compare=False)
    _uses_t: bool = _dc_field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        fn, uses_phi, uses_t = _compile_text(self.text, self.field)
        object.__setattr__(self, "_fn", fn)
        object.__setattr__(self, "_uses_phi", uses_phi)
        object.__setattr__(self, "_uses_t", uses_t)

    def __reduce__(self):  # closures do not pickle; recompile from the text instead
        return (type(self), (self.field, self.text))

    @property
    def depends_on_time(self) -> bool:
        """True if the text mentions ``t`` (syntactically: ``0*t`` counts)."""
        return self._uses_t

    @property
    def is_constant(self) -> bool:
        """True if the text mentions neither ``phi`` nor ``t``."""
        return not (self._uses_phi or self._uses_t)

    def evaluate(self, phi: np.ndarray | float, t: np.ndarray | float = 0.0) -> np.ndarray:
        """Evaluate on ``phi`` and ``t``, broadcast together; returns float64.

        The result has the shape of ``np.broadcast(phi, t)`` (a 0-d array for
        scalars).  Raises :class:`ExpressionError` if any value is NaN or
        infinite, naming the first such ``phi`` and ``t``.
        """
        phi_a = np.asarray(phi, dtype=np.float64)
        t_a = np.asarray(t, dtype=np.float64)
        shape = np.broadcast_shapes(phi_a.shape, t_a.shape)
        with np.errstate(all="ignore"):
            raw = self._fn(phi_a, t_a)
        out = np.array(np.broadcast_to(raw, shape), dtype=np.float64)
        finite = np.isfinite(out)
        if not finite.all():
            idx = np.unravel_index(int(np.argmin(finite)), shape)
            p = float(np.broadcast_to(phi_a, shape)[idx])
            tt = float(np.broadcast_to(t_a, shape)[idx])
            raise ExpressionError(
                self.field,
                self.text,
                f"non-finite value at phi={p!r}, t={tt!r} (result {float(out[idx])!r})",
                self.text,
            )
        return out


def parse_expression(text: str | int | float, field: str) -> Expression:
    """Parse a load expression from a study file.

    ``text`` is the TOML value: a string expression, or a plain number (which
    becomes a constant expression).  Booleans and other types are rejected
    with :class:`ExpressionError`, as is any text outside the whitelist.
    """
    if isinstance(text, (bool, np.bool_)):
        raise ExpressionError(field, "bool", f"expected a string expression or a number, got bool ({text!r})")
    if isinstance(text, (int, np.integer)):
        try:
            number = float(text)
        except OverflowError:
            number = math.inf
        if not math.isfinite(number):
            token = f"{int(text).bit_length()}-bit integer"
            raise ExpressionError(field, token, f"number ({token}) is out of range (not a finite float)")
        return Expression(field, str(int(text)))
    if isinstance(text, (float, np.floating)):
        number = float(text)
        if not math.isfinite(number):
            token = repr(number)
            raise ExpressionError(field, token, f"number '{token}' is not finite")
        return Expression(field, repr(number))
    return Expression(field, text)  # strings; other types rejected in __post_init__
