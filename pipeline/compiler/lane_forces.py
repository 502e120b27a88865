"""The sweep's force stage in lock-step lanes.

LANES candidates that passed the positions stage in the lanes, and the stroke
and margin gates, are solved together position by position: kinematics to
the acceleration analogs, the applied and inertia loads, the force equations
(``force_equations.eliminated``, the same lines as ``forces_at``), the
running maxima of |M_bal| and of the output rocker's |angular acceleration|,
the working point's acceleration, and |u x w|, |u . w| of every transmission
item (``Emitter.transmission_items``); the lane loop is the innermost loop,
straight-line code, so LLVM turns it into packed vector instructions.

Two kinds of lines (each emitter's ``force_lanes``: ``SAME_BITS``, ``TO_ROUNDING``):

* the careful kernels' own operations in their own order
  (``kernels.groups.crank``, a class III group's kernel from a solution handed
  over, the centres of mass as ``AttachEmitter.careful``, an input's tip by
  ``polar_point`` or ``slider_input``, a slider dyad on a guide of fixed direction,
  ``kernels.forces.applied_loads``), compiled without contraction like them:
  the numbers of the scalar force stage to the bit.  Their library calls come
  from tables made by the same calls: the crank's cos/sin of phi1 + phiM0
  (once per value of phiM0), an input's law and e(q) (the lane walk's table,
  handed over like a class III solution), a fixed slide's sin/cos (once per
  candidate);
* where the careful kernel calls the library at every position (a dyad's
  acos, a guide or slide turning with a link: atan2 then sin/cos), the
  positions stage's lane form without a library call (the cosine law without
  acos, the link's unit vector turned by the hoisted cos/sin of the angle),
  the analogs by the careful kernel's lines on it: the same numbers to
  rounding (``SAME_BITS`` False in such a module; tests/compiler holds them
  to the lanes' agreement with the careful path).

Where the scalar stage would stop or leave the handed solution (its closure
residual above Newton's tolerance, det J changing sign or below the
singularity margin, a group that does not assemble, a link of no length),
the lane says so (row F_bad) and its candidate takes the scalar force stage,
as before.  The peak reaction, the working point's peak |a| and the smallest
transmission angle are found afterwards from what the lanes wrote, by the
scalar stage's own loops (``may_reach`` and ``math.hypot``; ``fold_angle``'s
skip and ``math.atan2``: library calls).

A mechanism with a group or a force system the lanes do not know (see
``lane_form``) keeps the scalar force stage for every candidate.
"""

from __future__ import annotations

import re

from .emit import SAME_BITS, CrankEmitter, constant_names
from .force_equations import MM, UNROLLED_MAX, eliminated, is_square, slide_angle
from .lane_force_groups import input_lines, peak_lines, transmission_lines
from .names import wrap_line
from .skeleton import part

def lane_form(plan, ems) -> str:
    """Why the force stage of ``plan`` has no lane form ('' where it has one)."""
    if not is_square(plan):
        return "its force system is not square"
    for e in ems:       # (each emitter's ``force_lanes``: SAME_BITS or TO_ROUNDING)
        if e.force_lanes is None:
            return (f"{type(e).__name__[:-len('Emitter')]} groups have no lane form of "
                    "their forces")
    return ""


def same_bits(plan, ems) -> bool:
    """Whether the force lanes of ``plan`` give the scalar force stage's bits:
    every group's lines are its careful kernel's, and every slide has a fixed
    direction (its normal from the same sin/cos of the same angle)."""
    return (all(e.force_lanes == SAME_BITS or _on_a_fixed_guide(e) for e in ems)
            and all(int(plan.slide_dir[k, 0]) < 0 for k in range(len(plan.slide_names))))


def _on_a_fixed_guide(e) -> bool:
    """A group on a guide (``guide_col``, its link's column) of fixed direction:
    its lines are the careful kernel's (the hoisted cos/sin of the guide's angle
    is the same call on the same angle)."""
    return e.guide_col is not None and e.ix[e.guide_col] < 0


def _c(name):
    """A lane's entry of the force lanes' row ``name`` (FS)."""
    return f"FS[F_{name} * LANES + l]"


def _t(q):
    """A lane's entry of column ``q`` of the table handed over at position k (FT)."""
    return f"FT[k, {q} * LANES + l]"


def lane_force_kernel(plan, names, ems, rocker) -> str:
    """Source of the force lanes of ``plan`` (``force_lanes``, ``force_lane_in``,
    their constants and the driver ``force_flush``), or of the skeleton without
    them; ``rocker``: the output rocker's (pivot, point) names (the peak
    angular acceleration)."""
    why = lane_form(plan, ems)
    if not all(e.fast for e in ems[:plan.n_kinematic]):
        why = "no lane path: a group without a lane form of its positions"
    body, m = eliminated(plan, names, lanes=True) if not why else ([], 0)
    if not why and m > UNROLLED_MAX:
        why = f"its force system leaves {m} unknowns to the run time (more than unrolled)"
    if why:
        return part("no_lane_forces").format(why=why)
    consts = constant_names(plan, names, ems)
    triads = [e for e in ems if e.continued]
    crank = [e for e in ems if isinstance(e, CrankEmitter)]
    inputs = [e for e in ems if e.takes_law]
    handed = 4 * len(triads) + 4 * len(inputs)      # the lane walk's columns handed over
    # the transmission items (transmission()'s), their angles' cos/sin hoisted
    items = [it for e in ems[:plan.n_kinematic] for it in e.transmission_items()[1]]
    angles = [(q, j, x) for q, (kind, args) in enumerate(items) if kind == "lines"
              for j, x in ((0, args[2]), (1, args[5]))]
    rows = _force_rows(plan, consts, triads, angles)
    src = _force_constants(plan, ems, rows, items, handed + 2 * len(crank))
    L = _position_lines(plan, names, ems, handed, len(triads))
    L += _load_lines(plan)
    L += _force_lines(body, len(plan.joint_names), _c)
    L += _metric_lines(plan, rocker, items)
    src += _force_lanes(triads, L)
    src += _force_lane_in(plan, names, consts, angles, crank, handed)
    src += [part("lane_forces")]
    return "\n".join(src) + "\n"


def _force_rows(plan, consts, triads, angles):
    """The rows of FS: the candidate's constants, masses and moments of inertia,
    each slide's cos/sin, the running maxima and verdict, each class III
    group's branch, the transmission angles' cos/sin."""
    nb, ns = len(plan.body_names), len(plan.slide_names)
    rows = consts + [f"mass{b}" for b in range(nb)] + [f"jS{b}" for b in range(nb)]
    rows += [f"slide{k}_{x}" for k in range(ns) for x in ("cos", "sin")]
    rows += ["pm", "pe", "bad"] + [f"sign{e.triad_row}" for e in triads]
    return rows + [f"tr{q}_{j}_{f}" for q, j, _ in angles for f in ("cos", "sin")]


def _force_constants(plan, ems, rows, items, ft):
    """The module's constants of the force lanes: the rows of FS, the columns of
    FT (``ft``: per position, e(a), e(b) of each class III group, e(q) (or q),
    q', q'' of each input, the crank's cos/sin) and of RB."""
    nj = len(plan.joint_names)
    tr_col = 2 * nj + 2
    return ["# ---- the force stage in lanes (pipeline.compiler.lane_forces) ----",
            "HAS_LANE_FORCES = True", f"N_FROWS = {len(rows)}   # rows of FS[row * LANES + lane]",
            f"FT_COLS = {ft}   # FT[k, col * LANES + lane]: e(a), e(b) of each class III group, "
            "e(q) (or q), q', q'' of each input, the crank's cos/sin",
            f"N_RCOLS = {tr_col + 2 * len(items)}   # RB[k, col * LANES + lane]: "
            "the reactions (x, y) of each joint, the working point's acceleration (x, y), "
            "|u x w|, |u . w| of each transmission item",
            f"ACC_COL = {2 * nj}   # RB's columns of the working point's acceleration",
            f"N_TRANS = {len(items)}   # the transmission items (transmission()'s)",
            f"TR_COL = {tr_col}   # RB's column of the first",
            f"SAME_BITS = {same_bits(plan, ems)}   # the force lanes give the scalar force "
            "stage's bits (else its numbers to rounding)"] + [
        f"F_{r} = {i}" for i, r in enumerate(rows)]


def _position_lines(plan, names, ems, handed, n_triads):
    """A lane's lines of the positions, velocity and acceleration analogs of
    every point: the fixed points', then each group's."""
    L = ["bad = False", "z = 0.0"]
    for fi, off in zip(plan.fixed_idx, plan.fixed_off):
        i = int(fi)
        L += [f"P{i}_0 = {_c(names.par(off))}", f"P{i}_1 = {_c(names.par(int(off) + 1))}",
              f"V{i}_0 = 0.0", f"V{i}_1 = 0.0", f"A{i}_0 = 0.0", f"A{i}_1 = 0.0"]
    crank = [e for e in ems if isinstance(e, CrankEmitter)]
    inputs = [e for e in ems if e.takes_law]
    for e in ems:
        L += [f"# {e.title()}"]
        if isinstance(e, CrankEmitter):
            L += _crank_lines(e, handed + 2 * crank.index(e))
        elif e.takes_law:
            L += input_lines(e, _c, _t, 4 * n_triads + 4 * inputs.index(e))
        else:
            L += e.force_lines(_c, _t)
    return L


def _crank_lines(e, q):
    """A crank's tip from its cos/sin in FT's columns q, q + 1 (kernels.groups.crank)."""
    o, tip = e.ix[0], e.ix[1]
    ln = _c(e.k("length"))
    return [f"cc = {_t(q)}", f"sc = {_t(q + 1)}",
            f"P{tip}_0 = P{o}_0 + {ln} * cc", f"P{tip}_1 = P{o}_1 + {ln} * sc",
            f"V{tip}_0 = V{o}_0 - {ln} * sc", f"V{tip}_1 = V{o}_1 + {ln} * cc",
            f"A{tip}_0 = A{o}_0 - {ln} * cc", f"A{tip}_1 = A{o}_1 - {ln} * sc"]


def _load_lines(plan):
    """A lane's lines of the applied and inertia loads LD at each centre of mass
    (kernels.forces.applied_loads), the external loads added."""
    L = ["# applied and inertia loads at each centre of mass (kernels.forces.applied_loads)"]
    for b in range(len(plan.body_names)):
        s = int(plan.body_com[b])
        ta, tb = (int(v) for v in plan.body_turn.reshape(-1, 2)[b])
        L += [f"ax = (A{s}_0 * omega1 * omega1 + V{s}_0 * eps1) * {MM!r}",
              f"ay = (A{s}_1 * omega1 * omega1 + V{s}_1 * eps1) * {MM!r}"]
        if ta < 0:
            L += ["eb = 0.0"]
        else:
            L += [f"dx = P{tb}_0 - P{ta}_0", f"dy = P{tb}_1 - P{ta}_1",
                  f"d1x = V{tb}_0 - V{ta}_0", f"d1y = V{tb}_1 - V{ta}_1",
                  f"d2x = A{tb}_0 - A{ta}_0", f"d2y = A{tb}_1 - A{ta}_1",
                  "r2 = dx * dx + dy * dy", "c1 = dx * d1y - dy * d1x",
                  "c2 = dx * d2y - dy * d2x", "th1 = c1 / r2",
                  "th2 = c2 / r2 - 2.0 * (dx * d1x + dy * d1y) * c1 / (r2 * r2)",
                  "eb = th2 * omega1 * omega1 + th1 * eps1"]
        L += [f"LD{b}_0 = -{_c(f'mass{b}')} * ax",
              f"LD{b}_1 = -{_c(f'mass{b}')} * GRAVITY - {_c(f'mass{b}')} * ay",
              f"LD{b}_2 = -{_c(f'jS{b}')} * eb"]
    for q in range(len(plan.load_body)):
        b, p = int(plan.load_body[q]), int(plan.load_point[q])
        s = int(plan.body_com[b])
        L += [f"fx = loads[k, {q}, 0]", f"fy = loads[k, {q}, 1]",
              f"LD{b}_0 += fx", f"LD{b}_1 += fy", f"LD{b}_2 += loads[k, {q}, 2]"]
        if p >= 0:
            L += [f"LD{b}_2 += ((P{p}_0 - P{s}_0) * fy - (P{p}_1 - P{s}_1) * fx) * {MM!r}"]
    return L


def _metric_lines(plan, rocker, items):
    """A lane's lines of the sweep's metrics at this position: the running maximum
    of |M_bal|, the peaks, |u x w| and |u . w| of each transmission item, the
    lane's verdict."""
    tr_col = 2 * len(plan.joint_names) + 2
    L = ["# the running maximum of |M_bal| (force_stage's test, NaN and inf included)",
         f"pm = {_c('pm')}",
         f"{_c('pm')} = mb if ((abs(mb) > abs(pm)) | (not (mb - mb == 0.0))) else pm"]
    L += peak_lines(plan, rocker, _c)
    for q, (kind, args) in enumerate(items):
        L += transmission_lines(q, kind, args, _c)
        L += [f"RB[k, {tr_col + 2 * q} * LANES + l] = abs(ux * wy - uy * wx)",
              f"RB[k, {tr_col + 2 * q + 1} * LANES + l] = abs(ux * wx + uy * wy)"]
    # the verdict as arithmetic on 0 and 1 (their max), exact: a select of the row's
    # own value is a masked store (microcoded on AMD's AVX2 cores)
    return L + ["bad_now = 1.0 if bad else 0.0", f"bad_was = {_c('bad')}",
                f"{_c('bad')} = bad_was + bad_now - bad_was * bad_now"]


def _force_lanes(triads, L):
    """Source of ``force_lanes``: the lines ``L`` of one lane at one position, in
    the loops over positions and lanes."""
    src = ["", "", "@njit(**JIT)   # strict, like the scalar force stage: its bits",
           "def force_lanes(FS, FT, RB, n_lanes, npos, tol, tsing, omega1, eps1, loads, iw):",
           '    """Positions 0 .. npos - 1 of every lane: the reactions and the working',
           "    point's (iw) acceleration into RB, the running maxima of |M_bal| and of",
           '    the rocker\'s |angular acceleration| and the lane\'s verdict into FS."""',
           "    for l in range(n_lanes):",
           f"        {_c('pm')} = 0.0",
           f"        {_c('pe')} = 0.0",
           f"        {_c('bad')} = 0.0"]
    src += [f"        {_c(f'sign{e.triad_row}')} = 0.0" for e in triads]
    src += ["    for k in range(npos):",
            "        # a trip count known only at run time: LLVM vectorizes this loop (FT and RB",
            "        # indexed [k, col * LANES + l]: flat indices kept it scalar)",
            "        for l in range(n_lanes):"]
    return src + ["            " + x for x in L] + ["", ""]


def _force_lane_in(plan, names, consts, angles, crank, handed):
    """Source of ``force_lane_in``: one candidate into force lane l (its constants,
    masses, slides' and transmission angles' cos/sin, the lane walk's columns
    handed over, the crank's cos/sin)."""
    src = ["# its own function: compiled beside the run (pipeline.compiler.beside)",
           "@njit(**JIT_INNER)",
           "def force_lane_in(par, l, trail, FS, FT, phis, crank_tab):",
           '    """Candidate ``par`` into force lane ``l``: its constants, masses and the',
           '    class III solutions of the lane walk (``trail``), and the crank\'s cos/sin',
           "    of phis[k] + phiM0 (crank_tab: the last phiM0 in row 0, the table after",
           '    it; computed again only for another phiM0)."""',
           "    K = constants(par)"]
    if angles:
        src += ["    " + x for x in wrap_line("(" + ", ".join(consts) + ",) = K", 90).split("\n")]
        for q, j, x in angles:
            src += [f"    FS[F_tr{q}_{j}_cos * LANES + l] = math.cos({x})   # (metrics._line's)",
                    f"    FS[F_tr{q}_{j}_sin * LANES + l] = math.sin({x})"]
    for i, r in enumerate(consts):
        src.append(f"    FS[F_{r} * LANES + l] = K[{i}]")
    for b in range(len(plan.body_names)):
        off = int(plan.body_mass_off[b])
        src += [f"    FS[F_mass{b} * LANES + l] = par[{off}]",
                f"    FS[F_jS{b} * LANES + l] = par[{off + 1}]"]
    for k in range(len(plan.slide_names)):
        src += [f"    a = {slide_angle(plan, names, k)}   # slide {k}'s angle (forces_at's)",
                f"    FS[F_slide{k}_cos * LANES + l] = math.cos(a)",
                f"    FS[F_slide{k}_sin * LANES + l] = math.sin(a)"]
    src += ["    npos = phis.shape[0]"]
    if handed:
        src += ["    for k in range(npos):",
                f"        for q in range({handed}):",
                "            FT[k, q * LANES + l] = trail[k, q]"]
    for j, e in enumerate(crank):
        src += _crank_table_lines(f"K[{consts.index(e.k('phiM0'))}]", handed + 2 * j)
    return src + ["", ""]


def _crank_table_lines(m0, q):
    """force_lane_in's lines of a crank's cos/sin of phis[k] + phiM0 (``m0``) into
    FT's columns q, q + 1, the table made again only for another phiM0."""
    return [f"    m0 = {m0}",
            "    if not (crank_tab[0, 0] == m0):   # (kernels.groups.crank's cos, sin)",
            "        crank_tab[0, 0] = m0",
            "        for k in range(npos):",
            "            crank_tab[1 + k, 0] = math.cos(phis[k] + m0)",
            "            crank_tab[1 + k, 1] = math.sin(phis[k] + m0)",
            "    for k in range(npos):",
            f"        FT[k, {q} * LANES + l] = crank_tab[1 + k, 0]",
            f"        FT[k, {q + 1} * LANES + l] = crank_tab[1 + k, 1]"]


def _force_lines(body, nj, c):
    """``forces_at``'s lines (``force_equations.eliminated``) on the lane's locals:
    the loads LD, the positions P; the reactions into RB, M_bal into mb (the
    slides' forces are not kept: the sweep's metrics do not read them)."""
    out = ["# the force equations (force_equations.eliminated: forces_at's lines)"]
    skip = False
    for line in body:
        if line.startswith("applied_loads("):
            skip = True             # the loads are the lines above
            continue
        if skip:                    # the call's second line
            skip = False
            continue
        if line.startswith("slide_out["):
            continue
        line = re.sub(r"SLIDE_(COS|SIN)_(\d+)",
                      lambda m_: c(f"slide{m_[2]}_{m_[1].lower()}"), line)
        line = re.sub(r"LANE_CONST\((\w+)\)", lambda m_: c(m_[1]), line)
        line = re.sub(r"\bd1\[I_(\d+), (\d)\]", r"V\1_\2", line)
        line = re.sub(r"-loads_out\[(\d+), (\d)\]", r"-LD\1_\2", line)
        line = re.sub(r"pos\[I_(\d+), (\d)\]", r"P\1_\2", line)
        m = re.fullmatch(r"r_out\[(\d+), (\d)\] = (\w+)", line)
        if m:
            j, q, v = int(m[1]), int(m[2]), m[3]
            line = f"RB[k, {2 * j + q} * LANES + l] = {v}"
        m = re.fullmatch(r"return (.+)", line)
        if m:
            line = f"mb = {m[1]}"
        if re.search(r"\b(pos|d1|d2|loads_out|r_out|slide_out|work_a|work_b|par)\[", line):
            raise ValueError(f"a line of forces_at the lanes cannot take: {line!r}")
        out.append(line)
    return out
