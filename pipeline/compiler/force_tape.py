"""The generated ``forces_at`` of a plan as a tape (``pipeline.kernels.tape``):
the source ``force_equations.force_kernel`` writes, read back as a syntax tree
(never run) and turned into one operation per operation of the source, in its
order.  What the tape cannot say (the general solver of a plan whose system is
not square, a system too large for the unrolled solve) gives None: the scene
then compiles the generated module's ``forces_curve``.
"""

from __future__ import annotations

import ast
import math
import re

import numpy as np

from ..kernels import tape as T
from .force_equations import force_kernel
from .names import Names

_BIN = {ast.Add: T.ADD, ast.Sub: T.SUB, ast.Mult: T.MUL, ast.Div: T.DIV}
_CMP = {ast.Gt: T.GT, ast.Eq: T.EQ, ast.NotEq: T.NE}
_CALL1 = {"abs": T.ABS, "math.sin": T.SIN, "math.cos": T.COS}
_LOADS = {"pos": T.LOAD_POS, "d1": T.LOAD_D1, "loads_out": T.LOAD_LOADS,
          "slide_out": T.LOAD_SLIDE}
_STORES = {"r_out": T.STORE_R, "slide_out": T.STORE_SLIDE}


class NotATape(ValueError):
    """The source holds what the tape does not say."""


class _Tape:
    def __init__(self, plan):
        self.ops: list[list[int]] = []
        self.values: list[float] = []
        self.consts: dict[bytes, int] = {}
        self.names: dict[str, int] = {}
        self.par_col = {f"PAR_{n}": j for j, n in enumerate(Names(plan).par_local)}

    def reg(self, value=0.0) -> int:
        self.values.append(value)
        return len(self.values) - 1

    def const(self, x: float) -> int:
        key = np.float64(x).tobytes()
        if key not in self.consts:
            self.consts[key] = self.reg(float(x))
        return self.consts[key]

    def name(self, n: str) -> int:
        if n not in self.names:
            self.names[n] = self.reg(math.nan)
        return self.names[n]

    def emit(self, op, d=0, a=0, b=0, c=0) -> int:
        self.ops.append([op, d, a, b, c])
        return len(self.ops) - 1

    # -- expressions: the register holding the value
    def expr(self, e, dst=None) -> int:
        if isinstance(e, ast.Constant) and isinstance(e.value, (bool, int, float)):
            return self._to(dst, self.const(float(e.value)))
        if isinstance(e, ast.Name):
            return self._to(dst, self.name(e.id))
        if isinstance(e, ast.Attribute) and ast.unparse(e) == "math.nan":
            return self._to(dst, self.const(math.nan))
        d = self.reg() if dst is None else dst
        if isinstance(e, ast.BinOp) and type(e.op) in _BIN:
            a, b = self.expr(e.left), self.expr(e.right)
            self.emit(_BIN[type(e.op)], d, a, b)
        elif (isinstance(e, ast.BinOp) and isinstance(e.op, ast.Pow)
              and isinstance(e.right, ast.Constant) and e.right.value == 2
              and type(e.right.value) is int):
            self.emit(T.SQUARE, d, self.expr(e.left))
        elif isinstance(e, ast.UnaryOp) and isinstance(e.op, ast.USub):
            self.emit(T.NEG, d, self.expr(e.operand))
        elif isinstance(e, ast.UnaryOp) and isinstance(e.op, ast.Not):
            self.emit(T.NOT, d, self.expr(e.operand))
        elif (isinstance(e, ast.Compare) and len(e.ops) == 1 and type(e.ops[0]) in _CMP):
            a, b = self.expr(e.left), self.expr(e.comparators[0])
            self.emit(_CMP[type(e.ops[0])], d, a, b)
        elif isinstance(e, ast.Call) and not e.keywords and ast.unparse(e.func) in _CALL1 \
                and len(e.args) == 1:
            self.emit(_CALL1[ast.unparse(e.func)], d, self.expr(e.args[0]))
        elif isinstance(e, ast.Call) and ast.unparse(e.func) == "math.atan2" \
                and len(e.args) == 2 and not e.keywords:
            a, b = self.expr(e.args[0]), self.expr(e.args[1])
            self.emit(T.ATAN2, d, a, b)
        elif isinstance(e, ast.Subscript) and isinstance(e.value, ast.Name):
            self._load(e, d)
        else:
            raise NotATape(ast.unparse(e))
        return d

    def _to(self, dst, r):
        if dst is not None and dst != r:
            self.emit(T.MOV, dst, r)
            return dst
        return r

    def _index(self, e) -> int:
        if isinstance(e, ast.Constant) and type(e.value) is int:
            return e.value
        if isinstance(e, ast.Name) and re.fullmatch(r"I_\d+", e.id):
            return int(e.id[2:])
        if isinstance(e, ast.Name) and e.id in self.par_col:
            return self.par_col[e.id]
        raise NotATape(ast.unparse(e))

    def _pair(self, e):
        s = e.slice
        if not (isinstance(s, ast.Tuple) and len(s.elts) == 2):
            raise NotATape(ast.unparse(e))
        return self._index(s.elts[0]), self._index(s.elts[1])

    def _load(self, e, d):
        arr = e.value.id
        if arr == "par":
            self.emit(T.LOAD_PAR, d, self._index(e.slice))
        elif arr in _LOADS:
            self.emit(_LOADS[arr], d, *self._pair(e))
        else:
            raise NotATape(ast.unparse(e))

    # -- statements
    def block(self, body):
        for s in body:
            self.stmt(s)

    def stmt(self, s):
        if isinstance(s, ast.Assign):
            self._assign(s.targets, s.value)
        elif isinstance(s, ast.AugAssign) and isinstance(s.op, ast.Sub) \
                and isinstance(s.target, ast.Name):
            t = self.name(s.target.id)
            self.emit(T.SUB, t, t, self.expr(s.value))
        elif isinstance(s, ast.If) and not s.orelse:
            cond = self.expr(s.test)
            jump = self.emit(T.JUMP_IF_FALSE, 0, cond)
            self.block(s.body)
            self.ops[jump][1] = len(self.ops)
        elif isinstance(s, ast.Expr) and isinstance(s.value, ast.Call) \
                and ast.unparse(s.value.func) == "applied_loads":
            self.emit(T.APPLIED_LOADS)
        elif isinstance(s, ast.Return) and s.value is not None:
            self.emit(T.RETURN, 0, self.expr(s.value))
        else:
            raise NotATape(ast.unparse(s).split("\n")[0])

    def _assign(self, targets, value):
        if len(targets) == 1 and isinstance(targets[0], ast.Tuple):
            # a swap: every value first, then the targets
            elts = targets[0].elts
            if not (isinstance(value, ast.Tuple) and len(value.elts) == len(elts)):
                raise NotATape(ast.unparse(value))
            tmp = [self.expr(v, self.reg()) for v in value.elts]
            for t, r in zip(elts, tmp):
                self._store(t, r)
            return
        if len(targets) == 1 and isinstance(targets[0], ast.Name):
            self.expr(value, self.name(targets[0].id))
            return
        r = self.expr(value)
        for t in targets:
            self._store(t, r)

    def _store(self, t, r):
        if isinstance(t, ast.Name):
            self.emit(T.MOV, self.name(t.id), r)
        elif isinstance(t, ast.Subscript) and isinstance(t.value, ast.Name) \
                and t.value.id in _STORES:
            a, b = self._pair(t)
            self.emit(_STORES[t.value.id], 0, a, b, r)
        else:
            raise NotATape(ast.unparse(t))


def force_tape(plan):
    """(ops, regs) of ``plan``'s generated ``forces_at`` as a tape: ops (n, 5)
    int64, regs the register file's first values (the literals); None where
    the source is not a tape's."""
    fn = ast.parse(force_kernel(plan, Names(plan))).body[0]
    body = fn.body[1:] if isinstance(fn.body[0], ast.Expr) and isinstance(
        fn.body[0].value, ast.Constant) else fn.body          # (its docstring)
    t = _Tape(plan)
    try:
        t.block(body)
    except NotATape:
        return None
    return np.array(t.ops, dtype=np.int64).reshape(-1, 5), np.array(t.values, dtype=np.float64)
