"""A straight-line program run from data: the generated ``forces_at`` of a
mechanism (``pipeline.compiler.force_equations``) as a tape of operations on
a register file, so that a scene's forces need no compile of their own
(``pipeline.compiler.force_tape`` writes the tape, ``pipeline.compiler.plan_path``
runs it).

Each operation is one IEEE operation of the generated source, on the same
operands in the same order: the tape gives the generated kernel's bits.  A
row of ``ops`` is (code, dst, a, b, c); registers hold every local of the
source, its literals (loaded once, in ``regs``) and truth values (1.0, 0.0).
"""

import math

from numba import njit

from .config import JIT, JIT_ALLOC
from .forces import applied_loads

MOV, ADD, SUB, MUL, DIV, NEG, ABS, SIN, COS, ATAN2, SQUARE = range(11)
GT, EQ, NE, NOT, JUMP_IF_FALSE = range(11, 16)
LOAD_POS, LOAD_D1, LOAD_LOADS, LOAD_PAR, LOAD_SLIDE = range(16, 21)
STORE_R, STORE_SLIDE, APPLIED_LOADS, RETURN = range(21, 25)


@njit(**JIT)
def run_tape(ops, R, gravity, body_com, body_turn, body_mass_off, load_body, load_point, par,
             pos, d1, d2, omega1, eps1, loads_k, loads_out, r_out, slide_out):
    """The tape ``ops`` on registers ``R`` at one position; returns what the
    source returns (M_bal [N*m])."""
    pc = 0
    n = ops.shape[0]
    while pc < n:
        op = ops[pc, 0]
        d = ops[pc, 1]
        a = ops[pc, 2]
        b = ops[pc, 3]
        pc += 1
        if op == MOV:
            R[d] = R[a]
        elif op == ADD:
            R[d] = R[a] + R[b]
        elif op == SUB:
            R[d] = R[a] - R[b]
        elif op == MUL:
            R[d] = R[a] * R[b]
        elif op == DIV:
            R[d] = R[a] / R[b]
        elif op == NEG:
            R[d] = -R[a]
        elif op == ABS:
            R[d] = abs(R[a])
        elif op == SIN:
            R[d] = math.sin(R[a])
        elif op == COS:
            R[d] = math.cos(R[a])
        elif op == ATAN2:
            R[d] = math.atan2(R[a], R[b])
        elif op == SQUARE:
            R[d] = R[a] ** 2
        elif op == GT:
            R[d] = 1.0 if R[a] > R[b] else 0.0
        elif op == EQ:
            R[d] = 1.0 if R[a] == R[b] else 0.0
        elif op == NE:
            R[d] = 1.0 if R[a] != R[b] else 0.0
        elif op == NOT:
            R[d] = 1.0 if R[a] == 0.0 else 0.0
        elif op == JUMP_IF_FALSE:
            if R[a] == 0.0:
                pc = d
        elif op == LOAD_POS:
            R[d] = pos[a, b]
        elif op == LOAD_D1:
            R[d] = d1[a, b]
        elif op == LOAD_LOADS:
            R[d] = loads_out[a, b]
        elif op == LOAD_PAR:
            R[d] = par[a]
        elif op == LOAD_SLIDE:
            R[d] = slide_out[a, b]
        elif op == STORE_R:
            r_out[a, b] = R[ops[pc - 1, 4]]
        elif op == STORE_SLIDE:
            slide_out[a, b] = R[ops[pc - 1, 4]]
        elif op == APPLIED_LOADS:
            applied_loads(pos, d1, d2, omega1, eps1, gravity, par, body_com, body_turn,
                          body_mass_off, load_body, load_point, loads_k, loads_out)
        elif op == RETURN:
            return R[a]
    return math.nan


@njit(**JIT_ALLOC)
def tape_forces_curve(ops, regs, gravity, body_com, body_turn, body_mass_off, load_body,
                      load_point, par, pos, d1, d2, omega1, eps1, loads, loads_out, r_out,
                      slide_out, m_out):
    """The generated ``forces_curve``: the tape at every position k of pos/d1/d2."""
    R = regs.copy()
    for k in range(pos.shape[0]):
        m_out[k] = run_tape(ops, R, gravity, body_com, body_turn, body_mass_off, load_body,
                            load_point, par, pos[k], d1[k], d2[k], omega1, eps1, loads[k],
                            loads_out[k], r_out[k], slide_out[k])
