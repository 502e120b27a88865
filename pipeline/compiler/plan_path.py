"""The plan path: a scene's positions, forces and crank dynamics by kernels
compiled once per installation that read the mechanism's plan as data, so that
a scene of a new mechanism compiles nothing of its own (``PIPELINE_PLAN_PATH=0``:
the generated module's kernels instead).

How it stays the generated module's bits: its kernels are written from the same
emitters (``pipeline.compiler.emit``), in the same order.  Each group's lines
(its careful path, its derived constants, its start) are the emitter's own,
written once for a prototype of the group whose points and constants are
variables instead of the module's constants: point j of the group is ``P{j}``,
read from the plan; constant ``key`` is ``c_{key}``, read from the constants
array.  A group type, a guide of fixed direction or not, a kind of input and
law: each way an emitter writes its lines is a *form*, with its own small
kernels (``group_{f}``, ``derive_{f}``, ``start_{f}``); ``position`` calls them
in plan order, ``advance`` is the skeleton's.  The forces are the generated
``forces_at`` as a tape (``force_tape``, run by ``pipeline.kernels.tape``).  The
same operations on the same values in the same order give the same bits
(strict IEEE: no contraction, no reassociation); tests/compiler/test_plan_path.py
compares every shipped mechanism on both paths.

The forms are those of the library's warm-up mechanism (``pipeline.compiler.
warmup``: every group type and input law); a group of a form it does not have
keeps the plan off this path (``plan_constants`` returns None, and the scene
compiles the generated module), as does a force system the tape cannot say.

The constants array K of a plan (``plan_constants``): a header, the constants
in the order of the generated ``constants(par)`` (from K[5]), then the module
arrays of its groups (a table law's spline: (start, rows, columns) of each,
then their values).

    K[0] groups, K[1] groups before the centres of mass, K[2] fixed points,
    K[3] class III groups, K[4] gidx columns (W), K[5] where the constants start;
    then per fixed point (point, slot of x), per group (form, slot of its
    first constant, its W point indices, its row of the continuation state,
    where its arrays' descriptions start or -1).
"""

from __future__ import annotations

import ast
import hashlib
import pprint
import re
from dataclasses import astuple, dataclass
from functools import cache
from pathlib import Path

import numpy as np

from .emit import emitter_classes, emitters_for, watched_groups
from .names import NO_POINT, Names
from .skeleton import part

H_SIZE = 6              # the header's fixed part
_ROW_EXTRA = 4          # a group's row: form, first slot, W points, triad row, arrays
_PROTO = 10_000         # a prototype's point j is point _PROTO + j (P{j} in its lines)
W = 8                   # a group's points (the plan's gidx columns)


class _FormNames(Names):
    """Names of a prototype group's lines: point ``_PROTO + j`` is ``P{j}``, the
    group's constant ``key`` is ``c_{key}``."""

    def I(self, point: int) -> str:     # noqa: E743 (Names' own name)
        point = int(point)
        if point < _PROTO:
            raise ValueError("a form's lines name a point of the plan")
        return f"P{point - _PROTO}"

    def K(self, g: int, key: str) -> str:
        super().K(g, key)           # (the same check of the key)
        return f"c_{key}"


def _strip(lines):
    """The lines without their comment lines (a comment names the study's points)."""
    out = []
    for text in lines:
        for sub in text.split("\n"):
            if not sub.lstrip().startswith("#"):
                out.append(sub)
    return tuple(out)


@dataclass(frozen=True)
class Form:
    """One way an emitter writes a group's lines, with its points and constants
    as variables: ``slots`` its constants in the generated order (parameters,
    then ``derived`` (name, expression)), ``careful`` its lines of ``position``,
    ``start`` (a0, b0, phi_start) of a group solved by continuation, ``arrays``
    (name, dimensions) of the module constants its lines read (a table law's
    spline: on this path, arrays in K's tail)."""
    code: int
    slots: tuple
    careful: tuple
    derived: tuple
    start: tuple | None
    arrays: tuple


def _module_arrays(lines):
    """[(name, array)] of an emitter's module constants: ``NAME = np.array(literal)``
    each (read as a literal, never run); None where a line is another thing."""
    out = []
    for st in ast.parse("\n".join(lines)).body:
        ok = (isinstance(st, ast.Assign) and len(st.targets) == 1
              and isinstance(st.targets[0], ast.Name) and isinstance(st.value, ast.Call)
              and ast.unparse(st.value.func) == "np.array" and len(st.value.args) == 1
              and not st.value.keywords)
        if not ok:
            return None
        a = np.array(ast.literal_eval(st.value.args[0]), dtype=np.float64)
        if a.ndim not in (1, 2):
            return None
        out.append((st.targets[0].id, a))
    return out


def group_form(plan, g, triad_row):
    """(form, arrays) of group ``g`` of ``plan``: its ``Form`` and the values of
    its module arrays; None where its lines are not a form's."""
    names = _FormNames(plan)
    cls = emitter_classes()[int(plan.codes[g])]
    e = cls(plan, names, g, triad_row)
    arrays = _module_arrays(e.module_constants())
    if arrays is None:
        return None
    e.ix = [_PROTO + j if x >= 0 else x for j, x in enumerate(e.ix)]
    e.pname = lambda j: "''"
    e.title = lambda: "group"
    if e.continued:
        e.triad_row = "trow"
    derived = tuple(e.derived())
    form = Form(int(plan.codes[g]), tuple(e.params()) + tuple(d[0] for d in derived),
                _strip(e.careful()), derived,
                (e.k("a0"), e.k("b0"), e.k("phi_start")) if e.continued else None,
                tuple((name, a.ndim) for name, a in arrays))
    return form, [a for _, a in arrays]


def _triad_rows(ems):
    """Each group's row of the continuation state (-1: none), as ``emitters_for``
    gives them to the generated module's emitters ``ems``."""
    return [e.triad_row for e in ems]


@cache
def forms() -> tuple:
    """Every form of the warm-up mechanism's groups, in a fixed order."""
    from .warmup import mechanism
    plan = mechanism().compile()
    out = {}
    for g, row in enumerate(_triad_rows(emitters_for(plan, Names(plan)))):
        f = group_form(plan, g, row)
        if f is not None:
            out.setdefault(f[0], None)
    return tuple(out)


def plan_constants(plan, par=None):
    """The constants array of ``plan`` (header, then every constant of the
    row ``par``, the plan's own by default, derived constants included, then
    its module arrays); None where a group is of no form of this path."""
    lay = _layout(plan)
    return None if lay is None else _constants(lay, plan.par if par is None else par)


def _constants(lay, par):
    """The constants array of the plan of layout ``lay`` at the row ``par``."""
    head, cols, tail = lay[0], lay[1], lay[3]
    par = np.asarray(par, dtype=np.float64)
    K = np.concatenate([head, np.where(cols >= 0, par[cols], 0.0), tail])
    plan_kernels().derive(K)
    return K


_LAYOUTS: dict = {}


def _layout(plan):
    """(header, the parameter column of each constant (-1: derived), the watched
    groups, the tail of module arrays) of ``plan``, kept per plan structure;
    None off the path."""
    from . import structure_key
    key = structure_key(plan)
    if key not in _LAYOUTS:
        _LAYOUTS[key] = _new_layout(plan)
    return _LAYOUTS[key]


def _new_layout(plan):
    index = {Form(*f): i for i, f in enumerate(plan_kernels().FORMS)}
    names = Names(plan)
    ems = emitters_for(plan, names)
    rows = _triad_rows(ems)
    found = [group_form(plan, g, rows[g]) for g in range(len(plan.codes))]
    if plan.gidx.shape[1] != W or any(f is None or f[0] not in index for f in found):
        return None
    n_g, n_f = len(plan.codes), len(plan.fixed_idx)
    h_consts = H_SIZE + 2 * n_f + n_g * (W + _ROW_EXTRA)
    head = [n_g, plan.n_kinematic, n_f, sum(r >= 0 for r in rows), W, h_consts]
    cols, slot = [], h_consts
    for i, off in zip(plan.fixed_idx, plan.fixed_off):
        head += [int(i), slot]
        cols += [int(off), int(off) + 1]
        slot += 2
    col_of = {name: j for j, name in enumerate(names.par_local)}
    groups, tail, starts = [], [], []
    for g, (form, arrays) in enumerate(found):
        groups.append([index[form], slot] + [int(x) for x in plan.gidx[g]] + [rows[g], -1])
        cols += [col_of[names.K(g, key)] for key in names.group_keys[g]]
        cols += [-1] * len(form.derived)            # the derived ones: ``derive``
        slot += len(form.slots)
        if arrays:      # each: (where its values start, rows, columns), then the values
            groups[-1][-1] = len(tail)
            at = len(tail) + 3 * len(arrays)
            for a in arrays:
                starts.append(len(tail))
                tail += [at, a.shape[0] if a.ndim == 2 else 1, a.shape[-1]]
                at += a.size
            for a in arrays:
                tail += a.ravel().tolist()
    for i in starts:            # indices into K: the tail starts after the constants
        tail[i] += slot
    for row in groups:
        row[-1] += slot if row[-1] >= 0 else 0
        head += row
    tail = np.array(tail, dtype=np.float64)
    watch = np.array(watched_groups(plan, ems), dtype=np.int64)
    return np.array(head, dtype=np.float64), np.array(cols, dtype=np.int64), watch, tail


# -- the module's source --------------------------------------------------------------

def _form_functions(i, form):
    """The kernels of form ``i``: ``group_i`` (its lines of ``position``),
    ``derive_i`` (its derived constants into K) and ``start_i`` (a group solved by
    continuation); each reads its constants (and module arrays) from K first."""
    n_params = len(form.slots) - len(form.derived)
    pts = ", ".join(f"P{j}" for j in range(W))
    load = [f"    {s} = K[kb + {j}]" for j, s in enumerate(form.slots)]
    for j, (name, ndim) in enumerate(form.arrays):      # (where, rows, columns) at ext
        at, rows, cols = (f"np.int64(K[ext + {3 * j + q}])" for q in range(3))
        view = f"K[{at}:{at} + {rows} * {cols}]"
        load.append(f"    {name} = " + (f"{view}.reshape(({rows}, {cols}))" if ndim == 2
                                        else view))
    out = ["@njit(**JIT_INNER)",
           f"def group_{i}(K, kb, ext, {pts}, trow, phi, order, tols, state, pos, d1, d2, "
           "sing, slack):",
           *load,
           *("    " + x for x in form.careful),
           "    return st, m", "", ""]
    out += ["@njit(**JIT_INNER)", f"def derive_{i}(K, kb):", *load[:n_params]]
    for j, (name, expr) in enumerate(form.derived):
        out += [f"    {name} = {expr}", f"    K[kb + {n_params + j}] = {name}"]
    out += ["    return 0", "", ""]
    if form.start is not None:
        a0, b0, ps = form.start
        out += ["@njit(**JIT_INNER)", f"def start_{i}(K, kb, trow, state):",
                *load[:len(form.slots)],
                f"    start_triad(state, np.int64(trow), {a0}, {b0})",
                f"    return {ps}", "", ""]
    return out


def _dispatch(call, nforms, result, pick=None):
    """A chain of ``if f == i: <call of form i>`` lines."""
    out = []
    first = True
    for i in range(nforms):
        if pick is not None and not pick(i):
            continue
        out.append(f"{'if' if first else 'elif'} f == {i}:")
        out.append(f"    {result}{call.format(i=i)}")
        first = False
    return out


def source() -> str:
    """The plan path's module (its name: ``_module_name``)."""
    from .generate import group_type_imports
    fs = forms()
    out = [part("header").format(n_groups="any number of", digest=_digest()),
           *group_type_imports(),
           "# the plan path (pipeline.compiler.plan_path): one kernel per form of a group",
           f"N_FORMS = {len(fs)}",
           "# the forms, in the order of their kernels (plan_path.Form's fields)",
           "FORMS = " + pprint.pformat(tuple(astuple(f) for f in fs), width=90),
           f"{NO_POINT} = np.int64(-1)   # none: a guide, line or link of fixed direction",
           ""]
    for i, f in enumerate(fs):
        out += _form_functions(i, f)
    out += _position_source(fs) + _derive_source(fs) + _start_source(fs) + _advance_source()
    return "\n".join(out)


# a group's row of the plan (its form, first constant, points, triad row, arrays), in a
# loop over the groups g
_GROUP_ROW = [f"        r = np.int64({H_SIZE}) + 2 * np.int64(K[2]) + g * (np.int64(K[4]) + "
              f"{_ROW_EXTRA})",
              "        f = np.int64(K[r])",
              "        kb = np.int64(K[r + 1])"]
_GROUP_POINTS = ["        " + ", ".join(f"P{j}" for j in range(W)) + " = "
                 + ", ".join(f"np.int64(K[r + {2 + j}])" for j in range(W)),
                 f"        trow = np.int64(K[r + {2 + W}])",
                 f"        ext = np.int64(K[r + {3 + W}])"]


def _position_source(fs):
    pts = ", ".join(f"P{j}" for j in range(W))
    body = ["@njit(**JIT_INNER)",
            "def position(K, phi, order, tols, state, pos, d1, d2, margins, with_com):",
            '    """Every group at crank angle ``phi`` in plan order: the generated',
            "    ``position``'s lines, read from the plan (``pipeline.compiler.plan_path``).\"\"\"",
            "    n_groups = np.int64(K[0])",
            "    n_kinematic = np.int64(K[1])",
            "    sing = tols[T_SINGULAR]",
            "    slack = tols[T_ASSEMBLY_SLACK]",
            "    status = OK",
            "    margins[n_groups] = -1.0",
            "    for q in range(np.int64(K[2])):",
            f"        i = np.int64(K[{H_SIZE} + 2 * q])",
            f"        s = np.int64(K[{H_SIZE + 1} + 2 * q])",
            "        pos[i, 0] = K[s]",
            "        pos[i, 1] = K[s + 1]",
            "        d1[i, 0] = 0.0",
            "        d1[i, 1] = 0.0",
            "        d2[i, 0] = 0.0",
            "        d2[i, 1] = 0.0",
            "    for g in range(n_groups):",
            "        if g == n_kinematic and not with_com:",
            "            return status",
            *_GROUP_ROW, *_GROUP_POINTS,
            "        st, m = OK, 0.0"]
    call = (f"group_{{i}}(K, kb, ext, {pts}, trow, phi, order, tols, state, pos, d1, d2, sing, "
            "slack)")
    body += ["        " + x for x in _dispatch(call, len(fs), "st, m = ")]
    return body + ["        margins[g] = m",
                   "        if status == OK and st != OK:",
                   "            status = st",
                   "            margins[n_groups] = g",
                   "    return status", "", ""]


def _derive_source(fs):
    return (["@njit(**JIT)", "def derive(K):",
             '    """Every derived constant of the plan, into its slot of K."""',
             "    for g in range(np.int64(K[0])):", *_GROUP_ROW]
            + ["        " + x for x in _dispatch("derive_{i}(K, kb)", len(fs), "")]
            + ["    return 0", "", ""])


def _start_source(fs):
    cont = [i for i, f in enumerate(fs) if f.start is not None]
    out = ["@njit(**JIT_INNER)", "def start(K, state):",
           '    """Every class III group from its declared guess; the crank angle of the',
           '    first one\'s guesses (NaN: none, closed form)."""',
           "    phi = math.nan",
           "    first = True",
           "    for g in range(np.int64(K[0])):", *_GROUP_ROW,
           f"        trow = np.int64(K[r + {2 + W}])",
           "        p = math.nan"]
    out += ["        " + x for x in _dispatch("start_{i}(K, kb, trow, state)", len(fs),
                                             "p = ", pick=lambda i: i in cont)]
    return out + ["        if trow >= 0 and first:", "            phi = p",
                  "            first = False", "    return phi", "", ""]


def _advance_source():
    """The skeleton's two advances (N_GROUPS read from the plan) and the one that
    picks, with its first-class forms and ``start``'s."""
    out = []
    for name in ("advance_newton", "advance_closed"):
        text = part(name).replace("def advance(", f"def {name}(")
        out.append(re.sub(r"\bN_GROUPS\b", "np.int64(K[0])", text))
    return out + [
        "@njit(**JIT_INNER)",
        "def advance(K, phi_from, phi_to, order, tols, state, pos, d1, d2, margins, with_com):",
        '    """``advance_newton`` with class III groups, else ``advance_closed``."""',
        "    if K[3] > 0.0:",
        "        return advance_newton(K, phi_from, phi_to, order, tols, state, pos, d1, "
        "d2, margins, with_com)",
        "    return advance_closed(K, phi_from, phi_to, order, tols, state, pos, d1, d2, "
        "margins, with_com)", "", "",
        "advance_first_class = njit(**JIT_FIRST_CLASS)(getattr(advance, 'py_func', advance))",
        "start_first_class = njit(**JIT_FIRST_CLASS)(getattr(start, 'py_func', start))",
        ""]


def _digest() -> str:
    from . import library_digest
    return library_digest(False)


@cache
def _module_name(digest) -> str:
    """The plan path module's name: from everything its source is written from
    (the library digest: the compiler, kernels and group types; and the model,
    which compiles the warm-up mechanism), so that a process imports it without
    writing its source (which compiles the warm-up mechanism, scipy's spline
    of its table law among it) where it is there."""
    h = hashlib.sha256(digest.encode())
    model = Path(__file__).resolve().parent.parent / "model"
    for f in sorted(model.glob("**/*.py")):
        h.update(str(f.relative_to(model)).encode())
        h.update(f.read_bytes())
    return "pipeline_plan_" + h.hexdigest()[:20]


@cache
def _module_for(digest):
    from . import _imported
    return _imported(source, _module_name(digest))


def plan_kernels():
    """The plan path's module, imported (written first if new)."""
    return _module_for(_digest())


def on_plan_path() -> bool:
    """Whether scenes take the plan path (``PIPELINE_PLAN_PATH=0``: never, the
    generated module's kernels instead; a benchmark's baseline)."""
    import os
    return (os.environ.get("PIPELINE_PLAN_PATH", "1") != "0"
            and os.environ.get("NUMBA_DISABLE_JIT", "0") in ("", "0"))


def covers(plan, forces=False) -> bool:
    """Whether a scene of ``plan`` (with ``forces``) runs on the plan path alone."""
    return (on_plan_path() and _layout(plan) is not None
            and (not forces or force_tape_of(plan) is not None))


def revolution(plan, par, phis, phi_close, order, tols, *outputs):
    """The generated module's ``revolution`` (``pipeline.kernels.walk``'s walk, its
    outputs and status) on the plan path; None where ``plan`` is not on it (the
    caller then takes the generated module's)."""
    lay = _layout(plan) if on_plan_path() else None
    if lay is None:
        return None
    from ..kernels.walk import revolution as walk
    advance, start = first_class()
    K = _constants(lay, par)
    return walk(advance, start, K, lay[2], np.int64(K[3]), phis, phi_close, order, tols,
                *outputs)


_FIRST_CLASS: list = []


def first_class() -> tuple:
    """The plan path's ``advance`` and ``start`` as first-class functions looked up
    once (``kernels.walk.FixedFunction``), for the kernels that Python calls often
    (a long run, ``rk4``, takes the Dispatchers' direct calls)."""
    if not _FIRST_CLASS:
        from ..kernels.walk import ADVANCE, START, FixedFunction
        mod = plan_kernels()
        _FIRST_CLASS[:] = [FixedFunction(mod.advance_first_class, ADVANCE),
                           FixedFunction(mod.start_first_class, START)]
    return tuple(_FIRST_CLASS)


def _masses(plan):
    """The mass model as the generated module's MASSES: gravity, then the plan's
    index tables (int64, C order, as the plan holds them)."""
    return (float(plan.gravity), plan.body_com, plan.body_turn, plan.body_mass_off,
            plan.load_body, plan.load_point)


_TAPES: dict = {}


def force_tape_of(plan):
    """``force_tape.force_tape(plan)``, kept per plan structure (a scene's
    forces along a motion ask for it at every position)."""
    from . import structure_key
    from .force_tape import force_tape
    key = structure_key(plan)
    if key not in _TAPES:
        _TAPES[key] = force_tape(plan)
    return _TAPES[key]


def forces_curve_of(plan):
    """The generated module's ``forces_curve`` (par, pos, d1, d2, omega1, eps1, loads,
    loads_out, r_out, slide_out, m_out) on the plan path, ``plan``'s tape run by
    ``pipeline.kernels.tape``; None where ``plan`` is not on it (the caller then
    takes the generated module's)."""
    if not on_plan_path():
        return None
    tape = force_tape_of(plan)
    if tape is None:
        return None
    from ..kernels.tape import tape_forces_curve
    masses = _masses(plan)

    def forces_curve(par, *args):
        tape_forces_curve(*tape, *masses, par, *args)
    return forces_curve


class PlanDynamics:
    """What crank dynamics asks of a generated module (``skeleton/crank_dynamics``:
    its constants, sizes, mass model, first-class ``advance`` and ``start``,
    ``begin``, ``rk4``, ``terms_curve``) on the plan path: the integrators of
    ``pipeline.kernels.dynamics``, compiled once, on the plan path's ``advance``
    and ``start``.  (Not ``acceleration``, which scipy's DOP853 calls from Python:
    the reference method keeps the generated module's.)"""

    def __init__(self, plan, n_triads):
        mod = plan_kernels()
        self.plan = plan
        self.advance_first_class = mod.advance_first_class
        self.start_first_class = mod.start_first_class
        self.N_TRIADS = np.int64(n_triads)
        self.SIZES = (np.int64(plan.n_points), np.int64(plan.n_groups), self.N_TRIADS)
        self.MASSES = _masses(plan)

    def constants_array(self, par):
        return plan_constants(self.plan, par)

    def begin(self, K, phi, state, last):
        from ..kernels import dynamics
        dynamics.compile_integrator()
        dynamics.begin(first_class()[1], K, phi, state, last)

    def rk4(self, par, K, tols, *args):
        from ..kernels import dynamics
        dynamics.compile_integrator()
        return dynamics.rk4(self.advance_first_class, self.start_first_class, K, self.SIZES,
                            self.MASSES, par, tols, *args)

    def terms_curve(self, par, K, tols, *args):
        from ..kernels import dynamics
        dynamics.compile_integrator()
        return dynamics.terms_curve(*first_class(), K, self.SIZES, self.MASSES, par, tols,
                                    *args)


def dynamics_of(plan):
    """``PlanDynamics`` of ``plan``; None where ``plan`` is not on the plan path."""
    if not on_plan_path():
        return None
    lay = _layout(plan)
    if lay is None:
        return None
    return PlanDynamics(plan, int(lay[0][3]))


def compile_plan_path() -> bool:
    """Compile (or load from numba's cache) the plan path's kernels for the types
    a scene passes them, and the library kernels a scene calls from Python
    (``warmup.compile_group_kernels``): once per installation
    (``pipeline.compiler.beside.compile_library``: after the first sweep, or
    ``pipeline compile --library``), so that no scene compiles.  False where
    numba's JIT is disabled."""
    from ..kernels.tape import tape_forces_curve
    from ..kernels.walk import ADVANCE, START, compile_revolution
    from .warmup import compile_group_kernels, mechanism
    mod = plan_kernels()
    if not getattr(mod.advance_first_class, "compile", None):
        return False
    compile_revolution()
    mod.advance_first_class.compile(ADVANCE.signature)
    mod.start_first_class.compile(START.signature)
    plan = mechanism().compile()
    plan_constants(plan)            # (derive)
    empty = np.zeros((0, plan.n_points, 2))
    tape_forces_curve(np.zeros((1, 5), np.int64), np.zeros(1), 0.0, plan.body_com,
                      plan.body_turn, plan.body_mass_off, plan.load_body, plan.load_point,
                      plan.par, empty, empty, empty, 0.0, 0.0, np.zeros((0, 0, 3)),
                      np.zeros((0, 0, 3)), np.zeros((0, 0, 2)), np.zeros((0, 0, 2)),
                      np.zeros(0))
    compile_group_kernels()         # (those a scene calls from Python)
    return True


if __name__ == "__main__":     # (the whole library: pipeline compile --library)
    compile_plan_path()
