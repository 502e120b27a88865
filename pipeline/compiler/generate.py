"""The generated module of one mechanism: the emitters' lines in plan order
inside fixed loop skeletons (real Python files in pipeline/compiler/skeleton,
pasted verbatim: header, advance_closed or advance_newton, pipeline.kernels.walk, careful,
crank_dynamics, batch, sweep_stages, no_lanes, parallel).  A sweep's module
(with an output rocker) has the header, sweep_stages, its lanes and parallel,
and imports the rest from the module of its mechanism (no rocker).

Kernels of a generated module (all close over the mechanism; their
signatures carry candidates, crank angles, loads, settings and outputs):

* ``constants(par)``: every per-candidate constant, computed once;
* ``position``: every group at one crank angle (careful path);
* ``start``/``advance``: the continuation (predictor-corrector for class III);
* ``revolution``: scene curves at a list of crank angles (pipeline.kernels.walk's,
  compiled once per installation: the module gives it ``advance`` and ``start``);
* ``forces_at``/``forces_curve``: kinetostatics at one / every position;
* ``evaluate_careful``/``evaluate``: the sweep's stages for one candidate /
  a batch (lock-step lanes where the groups have a lane form, the careful
  path for every lane the fast path cannot vouch for);
* ``batch``: full kinematics (and forces) of many candidates, reduced to peaks;
* ``begin``/``acceleration``/``rk4``/``terms_curve``: crank dynamics (pipeline.kernels.dynamics's,
  compiled once per installation: the module gives it ``advance`` and ``start``).
"""

from __future__ import annotations

import re

import numpy as np

from .. import group_types
from .emit import constants_of, emitters_for, watched_groups
from .force_equations import force_kernel
from .lane_forces import lane_force_kernel
from .lanes import lane_kernel, no_rocker_kernel
from .names import NO_POINT, Names, literal, text, wrap_line
from .skeleton import part


def _array(name, a, dtype):
    a = np.asarray(a)
    body = repr(a.tolist()) if a.size else "[]"
    shape = a.shape
    return f"{name} = np.array({body}, dtype=np.{dtype}).reshape({shape})"


def group_type_imports() -> list[str]:
    """The generated module's imports of the group types' library kernels: each
    folder's ``kernels.__all__`` (``pipeline.group_types``)."""
    return [f"from {mod.__name__} import {', '.join(mod.__all__)}"
            for mod in group_types.part("kernels")]


def generate(plan, rocker=None, digest="", lanes_width=8, watch=True, shared=None) -> str:
    """Python source of the kernels of ``plan`` (``rocker``: the output
    rocker's (pivot, point) names, for the sweep's dwell and stroke).  Without
    ``watch`` no group is watched between positions (the benchmark's baseline
    of the watch's cost; never for results).

    ``shared`` (with a rocker): (module name, function names) of the module of
    ``plan`` without a rocker, whose kernels do not depend on the rocker
    (positions, the continuation, the watch, forces, the scene's revolution and
    batch, crank dynamics).  The sweep's module then imports them from it and
    defines only what the rocker changes (its careful stages, lanes and
    ``evaluate``): a scene and a sweep of one mechanism share those kernels'
    compiled code (numba's cache), instead of compiling them once each."""
    n = Names(plan)
    ems = emitters_for(plan, n)
    n_triads = sum(e.continued for e in ems)
    # the study's names are data: in comments only, as ascii() writes them
    # (pipeline.compiler.names); every identifier comes from an index
    out = [part("header").format(n_groups=plan.n_kinematic, digest=digest)]
    out += group_type_imports()
    out += _group_list(plan, ems)
    out += _plan_constants(plan, n, n_triads)
    out += _force_constants(plan, ems, watch)
    for e in ems:
        out += e.module_constants()
    if shared is not None:
        out += _shared_kernels(plan, n, ems, rocker, lanes_width, watch, shared)
        return _checked("\n".join(out))
    consts = constants_of(plan, n, ems)
    names_k = [c[0] for c in consts]
    unpack = _unpack(names_k)
    out.append(_fn("constants(par)",
                   "Every per-candidate constant of the mechanism, computed once per "
                   "candidate\n(before the position loop): the row's dimensions and what "
                   "follows from them.",
                   [f"{k} = {v}" for k, v in consts] + ["return " + _tuple(names_k)]))
    out.append(_position_fn(plan, n, ems, unpack))
    out.append(_start_fn(ems, unpack))
    out.append(_spaced(part("advance_newton" if n_triads else "advance_closed")))
    out.append(force_kernel(plan, n))
    out.append(_transmission_fn(plan, ems, unpack))
    out.append(_spaced(module_walk() + part("careful") + part("crank_dynamics")
                       + part("batch")))
    out.append(_sweep_parts(plan, n, ems, rocker, lanes_width, watch))
    return _checked("\n".join(out))     # ends with the blank line after the last part


def _group_list(plan, ems):
    """The comment listing the groups in solve order."""
    return (["# the groups, in solve order"]
            + [f"#   {e.title()}" for e in ems[:plan.n_kinematic]] + [""])


def _plan_constants(plan, n, n_triads):
    """The plan's sizes, gravity, and the indices of its points and of the
    columns of a candidate's parameter row, as the module's constants."""
    out = ["# ---- the mechanism's plan, as constants ----",
           # the sizes the kernels allocate work arrays by (work, force_work, watch_work)
           # as np.int64, not literals: one compiled version of each serves every mechanism
           f"N_POINTS = np.int64({plan.n_points})",
           f"N_GROUPS = np.int64({plan.n_groups})",
           f"N_KINEMATIC = {plan.n_kinematic}   # groups before the hidden centres of mass",
           f"N_TRIADS = np.int64({n_triads})   # class III groups, either kind (rows of the "
           "continuation state)",
           f"N_PARAMS = {len(plan.par_names)}",
           f"GRAVITY = {literal(plan.gravity)}",
           ""]
    # np.int64: numba types a plain int global as a literal, and every call of a
    # library kernel (a group type's) with other literal indices compiled a
    # version of that kernel of its own, for each group and each mechanism; as
    # int64 values one compiled version serves them all (from numba's cache)
    out.append("# point indices in pos/d1/d2")
    out += [f"{n.I(i)} = np.int64({i})   # {text(p)}" for i, p in enumerate(plan.point_names)]
    out += [f"{NO_POINT} = np.int64(-1)   # none: a guide, line or link of fixed direction",
            "", "# columns of a candidate's parameter row"]
    out += [f"PAR_{n.par(i)} = {i}   # {text(p)}" for i, p in enumerate(plan.par_names)]
    return out + [""]


def _force_constants(plan, ems, watch):
    """The force analysis' tables (bodies, joints, slides, loads), the watched
    groups and the crank's body, as the module's constants."""
    watched = watched_groups(plan, ems, watch)
    return [
        "# force analysis: bodies, joints, slides, loads",
        _array("BODY_COM", plan.body_com, "int64"),
        _array("BODY_TURN", plan.body_turn.reshape(-1, 2), "int64"),
        _array("BODY_MASS_OFF", plan.body_mass_off, "int64"),
        _array("JOINT_POINT", plan.joint_point, "int64"),
        _array("JOINT_BODIES", plan.joint_bodies.reshape(-1, 2), "int64"),
        _array("SLIDE_BODIES", plan.slide_bodies.reshape(-1, 2), "int64"),
        _array("SLIDE_DIR", plan.slide_dir.reshape(-1, 2), "int64"),
        _array("SLIDE_ANGLE", plan.slide_angle, "float64"),
        _array("LOAD_BODY", plan.load_body, "int64"),
        _array("LOAD_POINT", plan.load_point, "int64"),
        "# groups whose margin the walks watch between positions (pipeline.kernels.watch)",
        _array("WATCH_G", watched, "int64"),
        f"N_WATCH = np.int64({len(watched)})",
        f"CRANK_BODY = {plan.crank_body}",
        f"CRANK_PIVOT = {plan.crank_pivot}   # the shaking moment's reference point",
        f"N_BODIES = np.int64({len(plan.body_names)})",
        f"N_JOINTS = np.int64({len(plan.joint_names)})",
        f"N_SLIDES = np.int64({len(plan.slide_names)})",
        f"N_INPUTS = np.int64({plan.n_inputs})   # inputs besides the crank: their drives "
        "follow the slides' rows of slide_out",
        ""]


def _shared_kernels(plan, n, ems, rocker, lanes_width, watch, shared):
    """A sweep's module past its constants: the import of the kernels the rocker
    does not change from the mechanism's own module (``shared``), then the
    sweep's parts."""
    sweep = _sweep_parts(plan, n, ems, rocker, lanes_width, watch)
    own = set(defined_functions(sweep))
    names = [f for f in shared[1] if f not in own]
    return ["# ---- the kernels the rocker does not change: the mechanism's own module ----",
            wrap_line(f"from {shared[0]} import " + _tuple(names)), sweep]


def _position_fn(plan, n, ems, unpack):
    """Source of ``position``: every group at one crank angle (careful path)."""
    body = [unpack, "sing = tols[T_SINGULAR]", "slack = tols[T_ASSEMBLY_SLACK]", "status = OK",
            "margins[N_GROUPS] = -1.0   # the first group that fails (-1: none)",
            "# fixed pivots: positions from the row, zero analogs"]
    for fi, off in zip(plan.fixed_idx, plan.fixed_off):
        I = n.I(fi)
        body += [f"# fixed point {text(plan.point_names[int(fi)])}",
                 f"pos[{I}, 0] = {n.par(off)}", f"pos[{I}, 1] = {n.par(int(off) + 1)}",
                 f"d1[{I}, 0] = 0.0", f"d1[{I}, 1] = 0.0", f"d2[{I}, 0] = 0.0",
                 f"d2[{I}, 1] = 0.0"]
    for e in ems:
        lines = e.careful() + [f"margins[{e.g}] = m", "if status == OK and st != OK:",
                               "    status = st", f"    margins[N_GROUPS] = {e.g}"]
        if e.g == plan.n_kinematic:
            body += ["if not with_com:", "    return status",
                     "# ---- the centres of mass (force analysis and dynamics only)"]
        body += lines
    body.append("return status")
    return _fn("position(K, phi, order, tols, state, pos, d1, d2, margins, with_com)",
               "Every group at crank angle ``phi`` (rad), in plan order (careful path).\n"
               "Writes pos/d1/d2 (n_points, 2) to ``order`` (0 positions, 1 velocity\n"
               "analogs, 2 acceleration analogs) and margins[g]; the centres of mass only\n"
               "``with_com``.  Returns the first non-OK status (later groups still run\n"
               "and give NaN); margins[N_GROUPS] is the index of the group that gave it.",
               body, jit="**JIT_INNER")


def _start_fn(ems, unpack):
    """Source of ``start``: every class III group from its declared guess."""
    triads = [e for e in ems if e.continued]
    body = [unpack]
    for e in triads:
        body.append(f"start_triad(state, np.int64({e.triad_row}), {e.k('a0')}, {e.k('b0')})")
    body.append(f"return {triads[0].k('phi_start')}" if triads else "return math.nan")
    return _fn("start(K, state)",
               "Start every class III group from its declared guess; returns the crank\n"
               "angle where the guesses apply (NaN without class III groups: closed form).",
               body, jit="**JIT_INNER")


def _transmission_fn(plan, ems, unpack):
    """Source of ``transmission``: the smallest transmission angle at a position."""
    body = [unpack, "tr = math.inf"]
    for e in ems[:plan.n_kinematic]:
        body += e.transmission()
    body.append("return tr")
    return _fn("transmission(K, pos, best_cos=math.nan, best_sin=math.nan)",
               "The smallest transmission angle at this position (rad, in [0, pi/2]) over "
               "the\ndyads and the class III leads (``pipeline.peaks.transmission_items``); "
               "inf\nwhere the mechanism has none, or where every angle is certainly above "
               "the\nsmallest so far, whose cos and sin are best_cos, best_sin (NaN: none yet).",
               body)


def module_walk() -> str:
    """pipeline.kernels.walk's pasted text with the module's own ``advance`` and
    ``start``: called as the module's functions, not taken as arguments.  (A
    function passed as an argument is, to numba, the address of a Python object
    in this process: it would not cache the sweep's kernels that pass it.)"""
    text, n = re.subn(r"\b(?:advance|start), K\b", "K", part("walk", "pipeline.kernels"))
    if n == 0 or re.search(r"\b(?:advance|start),", text):
        raise ValueError("pipeline.kernels.walk: advance or start left as an argument")
    return text


def defined_functions(src: str) -> list[str]:
    """The names of the functions a generated source defines at module level."""
    return re.findall(r"^def (\w+)\(", src, re.M)


def _sweep_parts(plan, n, ems, rocker, lanes_width, watch) -> str:
    """What the output rocker changes: the sweep's careful stages, its lanes
    (or the skeleton without them) and ``evaluate``."""
    if rocker is not None:
        lanes = lane_kernel(plan, n, ems, rocker, lanes_width, watch)
        forces = lane_force_kernel(plan, n, ems, rocker)
    else:
        lanes = _spaced(no_rocker_kernel())
        forces = part("no_lane_forces").format(why="no output rocker declared")
    return (_spaced(part("sweep_stages")) + "\n" + lanes + "\n" + _spaced(forces) + "\n"
            + _spaced(part("parallel")))


def _checked(src: str) -> str:
    if not src.isascii():   # a name pasted without names.text: never write it
        raise ValueError("generated source holds a non-ASCII character: a name was not "
                         "written by pipeline.compiler.names.text")
    return src


def _spaced(text):
    """A pasted part of the module (pipeline/compiler/skeleton) with a blank line
    before and after it."""
    return "\n" + text + "\n"


def _tuple(names):
    return "(" + ", ".join(names) + ("," if len(names) == 1 else "") + ")"


def _unpack(names):
    return wrap_line(_tuple(names) + " = K")


def _fn(sig, doc, body, jit="**JIT"):
    ind = "    "
    text = [f"@njit({jit})", f"def {sig}:", ind + '"""' + doc.replace("\n", "\n" + ind) + '"""']
    for line in body:
        for sub in line.split("\n"):
            text.append(ind + sub)
    return "\n".join(text) + "\n\n"

