"""The sweep's force stage in lock-step lanes.

LANES candidates that passed the positions stage in the lanes, and the stroke
and margin gates, are solved together position by position: kinematics to
the acceleration analogs, the applied and inertia loads, the force equations
(``force_equations.eliminated``, the same lines as ``forces_at``), the
running maxima of |M_bal| and of the output rocker's |angular acceleration|,
the working point's acceleration, and |u x w|, |u . w| of every transmission
item (``Emitter.transmission_items``); the lane loop is the innermost loop,
straight-line code, so LLVM turns it into packed vector instructions.

Two kinds of lines (``BIT_FOR_BIT``, ``TO_ROUNDING``):

* the careful kernels' own operations in their own order
  (``kernels.groups.crank``, ``kernels.triad.class3`` from a solution handed
  over, the centres of mass as ``AttachEmitter.careful``, an input's tip by
  ``polar_point`` or ``slider_input``, an RRP on a guide of fixed direction,
  ``kernels.forces.applied_loads``), compiled without contraction like them:
  the numbers of the scalar force stage to the bit.  Their library calls come
  from tables made by the same calls: the crank's cos/sin of phi1 + phiM0
  (once per value of phiM0), an input's law and e(q) (the lane walk's table,
  handed over like a class III solution), a fixed slide's sin/cos (once per
  candidate);
* where the careful kernel calls the library at every position (an RRR's
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

from .emit import (AttachEmitter, ClassIIIEmitter, ClassIIISliderEmitter, CrankEmitter,
                   InputEmitter, PRPEmitter,
                   RPPEmitter, RRPEmitter, RRREmitter, _wrap_line, constant_names, lane,
                   lane_direction, lane_meet)
from ..kernels.inputs import ROTARY
from .force_equations import MM, UNROLLED_MAX, eliminated, is_square, slide_angle
from .skeleton import part

# the groups whose careful kernels the force lanes repeat operation for operation
# (a candidate gets the scalar force stage's bits; an RRP only on a guide of fixed
# direction), and those whose lane form takes the positions stage's way without a
# library call (the cosine law without acos, guide directions as link vectors
# turned by hoisted cos/sin): the scalar force stage's numbers to rounding
BIT_FOR_BIT = (CrankEmitter, ClassIIIEmitter, AttachEmitter, InputEmitter)
TO_ROUNDING = (RRREmitter, PRPEmitter, RPPEmitter, RRPEmitter, ClassIIISliderEmitter)


def lane_form(plan, ems) -> str:
    """Why the force stage of ``plan`` has no lane form ('' where it has one)."""
    if not is_square(plan):
        return "its force system is not square"
    for e in ems:
        if not isinstance(e, BIT_FOR_BIT + TO_ROUNDING):
            return (f"{type(e).__name__[:-len('Emitter')]} groups have no lane form of "
                    "their forces")
    return ""


def same_bits(plan, ems) -> bool:
    """Whether the force lanes of ``plan`` give the scalar force stage's bits:
    every group's lines are its careful kernel's, and every slide has a fixed
    direction (its normal from the same sin/cos of the same angle)."""
    return (all(isinstance(e, BIT_FOR_BIT) or _on_a_fixed_guide(e) for e in ems)
            and all(int(plan.slide_dir[k, 0]) < 0 for k in range(len(plan.slide_names))))


def _on_a_fixed_guide(e) -> bool:
    """An RRP or a class III group with a slider whose guide has a fixed
    direction: its lines are the careful kernel's (the hoisted cos/sin of the
    guide's angle is the same call on the same angle)."""
    col = {RRPEmitter: 3, ClassIIISliderEmitter: 6}.get(type(e))     # the guide link's column
    return col is not None and e.ix[col] < 0


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
    nb, nj = len(plan.body_names), len(plan.joint_names)
    triads = [e for e in ems if e.continued]
    crank = [e for e in ems if isinstance(e, CrankEmitter)]
    inputs = [e for e in ems if isinstance(e, InputEmitter)]
    handed = 4 * len(triads) + 4 * len(inputs)      # the lane walk's columns handed over
    ns = len(plan.slide_names)
    rows = consts + [f"mass{b}" for b in range(nb)] + [f"jS{b}" for b in range(nb)]
    rows += [f"slide{k}_{x}" for k in range(ns) for x in ("cos", "sin")]
    rows += ["pm", "pe", "bad"] + [f"sign{e.triad_row}" for e in triads]
    # the transmission items (transmission()'s), their angles' cos/sin hoisted
    items = [it for e in ems[:plan.n_kinematic] for it in e.transmission_items()[1]]
    angles = [(q, j, x) for q, (kind, args) in enumerate(items) if kind == "lines"
              for j, x in ((0, args[2]), (1, args[5]))]
    rows += [f"tr{q}_{j}_{f}" for q, j, _ in angles for f in ("cos", "sin")]
    tr_col = 2 * nj + 2
    ft = handed + 2 * len(crank)     # per position: e(a), e(b) of each class III group,
    #                                  e(q) (or q), q', q'' of each input, the crank's cos/sin

    def c(name):
        return f"FS[F_{name} * LANES + l]"

    def t(q):
        return f"FT[k, {q} * LANES + l]"

    L = ["bad = False", "z = 0.0"]
    for fi, off in zip(plan.fixed_idx, plan.fixed_off):
        i = int(fi)
        L += [f"P{i}_0 = {c(names.par(off))}", f"P{i}_1 = {c(names.par(int(off) + 1))}",
              f"V{i}_0 = 0.0", f"V{i}_1 = 0.0", f"A{i}_0 = 0.0", f"A{i}_1 = 0.0"]
    for e in ems:
        L += [f"# {e.title()}"]
        if isinstance(e, CrankEmitter):
            o, tip = e.ix[0], e.ix[1]
            q = handed + 2 * crank.index(e)
            ln = c(e.k("length"))
            L += [f"cc = {t(q)}", f"sc = {t(q + 1)}",
                  f"P{tip}_0 = P{o}_0 + {ln} * cc", f"P{tip}_1 = P{o}_1 + {ln} * sc",
                  f"V{tip}_0 = V{o}_0 - {ln} * sc", f"V{tip}_1 = V{o}_1 + {ln} * cc",
                  f"A{tip}_0 = A{o}_0 - {ln} * cc", f"A{tip}_1 = A{o}_1 - {ln} * sc"]
        elif isinstance(e, ClassIIIEmitter):
            L += _class3_lines(e, c, t)
        elif isinstance(e, ClassIIISliderEmitter):
            L += _class3_slider_lines(e, c, t)
        elif isinstance(e, InputEmitter):
            L += _input_lines(e, c, t, 4 * len(triads) + 4 * inputs.index(e))
        elif isinstance(e, RRPEmitter):
            L += _rrp_lines(e)
        elif isinstance(e, RRREmitter):
            L += _rrr_lines(e)
        elif isinstance(e, PRPEmitter):
            L += (_direction_lines(e, "u1", "t1", "guide1_angle", 1)
                  + _direction_lines(e, "u2", "t2", "guide2_angle", 4)
                  + _meet_lines(e.ix[0], lane(e.k("guide1_offset")), e.ix[3],
                                lane(e.k("guide2_offset")), e.ix[6]))
        elif isinstance(e, RPPEmitter):
            cs, ss = lane(f"{e.k('slot_angle')}_cos"), lane(f"{e.k('slot_angle')}_sin")
            L += (_direction_lines(e, "u1", "t1", "guide_angle", 2)
                  + _from_position_lanes([f"u2x = {cs} * u1x - {ss} * u1y",
                                          f"u2y = {ss} * u1x + {cs} * u1y"])
                  + ["t21 = t11", "t22 = t12"]
                  + _meet_lines(e.ix[1], lane(e.k("guide_offset")), e.ix[0],
                                f"-{lane(e.k('slot_offset'))}", e.ix[4]))
        else:
            L += _attach_lines(e, c)
    L += ["# applied and inertia loads at each centre of mass (kernels.forces.applied_loads)"]
    for b in range(nb):
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
        L += [f"LD{b}_0 = -{c(f'mass{b}')} * ax",
              f"LD{b}_1 = -{c(f'mass{b}')} * GRAVITY - {c(f'mass{b}')} * ay",
              f"LD{b}_2 = -{c(f'jS{b}')} * eb"]
    for q in range(len(plan.load_body)):
        b, p = int(plan.load_body[q]), int(plan.load_point[q])
        s = int(plan.body_com[b])
        L += [f"fx = loads[k, {q}, 0]", f"fy = loads[k, {q}, 1]",
              f"LD{b}_0 += fx", f"LD{b}_1 += fy", f"LD{b}_2 += loads[k, {q}, 2]"]
        if p >= 0:
            L += [f"LD{b}_2 += ((P{p}_0 - P{s}_0) * fy - (P{p}_1 - P{s}_1) * fx) * {MM!r}"]
    L += _force_lines(body, nj, c)
    L += ["# the running maximum of |M_bal| (force_stage's test, NaN and inf included)",
          f"pm = {c('pm')}",
          f"{c('pm')} = mb if ((abs(mb) > abs(pm)) | (not (mb - mb == 0.0))) else pm"]
    L += _peak_lines(plan, rocker, c)
    for q, (kind, args) in enumerate(items):
        L += _transmission_lines(q, kind, args, c)
        L += [f"RB[k, {tr_col + 2 * q} * LANES + l] = abs(ux * wy - uy * wx)",
              f"RB[k, {tr_col + 2 * q + 1} * LANES + l] = abs(ux * wx + uy * wy)"]
    L += [f"{c('bad')} = 1.0 if bad else {c('bad')}"]
    flat = [f"F_{r} = {i}" for i, r in enumerate(rows)]
    src = ["# ---- the force stage in lanes (pipeline.compiler.lane_forces) ----",
           "HAS_LANE_FORCES = True", f"N_FROWS = {len(rows)}   # rows of FS[row * LANES + lane]",
           f"FT_COLS = {ft}   # FT[k, col * LANES + lane]: e(a), e(b) of each class III group, "
           "e(q) (or q), q', q'' of each input, the crank's cos/sin", f"N_RCOLS = {tr_col + 2 * len(items)}   # RB[k, col * LANES + lane]: "
           "the reactions (x, y) of each joint, the working point's acceleration (x, y), "
           "|u x w|, |u . w| of each transmission item",
           f"ACC_COL = {2 * nj}   # RB's columns of the working point's acceleration",
           f"N_TRANS = {len(items)}   # the transmission items (transmission()'s)",
           f"TR_COL = {tr_col}   # RB's column of the first",
           f"SAME_BITS = {same_bits(plan, ems)}   # the force lanes give the scalar force "
           "stage's bits (else its numbers to rounding)"]
    src += flat
    src += ["", "", "@njit(**JIT)   # strict, like the scalar force stage: its bits",
            "def force_lanes(FS, FT, RB, n_lanes, npos, tol, tsing, omega1, eps1, loads, iw):",
            '    """Positions 0 .. npos - 1 of every lane: the reactions and the working',
            "    point's (iw) acceleration into RB, the running maxima of |M_bal| and of",
            '    the rocker\'s |angular acceleration| and the lane\'s verdict into FS."""',
            "    for l in range(n_lanes):",
            f"        {c('pm')} = 0.0",
            f"        {c('pe')} = 0.0",
            f"        {c('bad')} = 0.0"]
    src += [f"        {c(f'sign{e.triad_row}')} = 0.0" for e in triads]
    src += ["    for k in range(npos):",
            "        # a trip count known only at run time: LLVM vectorizes this loop (FT and RB",
            "        # indexed [k, col * LANES + l]: flat indices kept it scalar)",
            "        for l in range(n_lanes):"]
    src += ["            " + x for x in L]
    src += ["", ""]
    # force_lane_in: one candidate into lane l
    src += ["@njit(inline='always', **JIT)",
            "def force_lane_in(par, l, trail, FS, FT, phis, crank_tab):",
            '    """Candidate ``par`` into force lane ``l``: its constants, masses and the',
            '    class III solutions of the lane walk (``trail``), and the crank\'s cos/sin',
            "    of phis[k] + phiM0 (crank_tab: the last phiM0 in row 0, the table after",
            '    it; computed again only for another phiM0)."""',
            "    K = constants(par)"]
    if angles:
        src += ["    " + x for x in _wrap_line("(" + ", ".join(consts) + ",) = K", 90).split("\n")]
        for q, j, x in angles:
            src += [f"    FS[F_tr{q}_{j}_cos * LANES + l] = math.cos({x})   # (metrics._line's)",
                    f"    FS[F_tr{q}_{j}_sin * LANES + l] = math.sin({x})"]
    for i, r in enumerate(consts):
        src.append(f"    FS[F_{r} * LANES + l] = K[{i}]")
    for b in range(nb):
        off = int(plan.body_mass_off[b])
        src += [f"    FS[F_mass{b} * LANES + l] = par[{off}]",
                f"    FS[F_jS{b} * LANES + l] = par[{off + 1}]"]
    for k in range(ns):
        src += [f"    a = {slide_angle(plan, names, k)}   # slide {k}'s angle (forces_at's)",
                f"    FS[F_slide{k}_cos * LANES + l] = math.cos(a)",
                f"    FS[F_slide{k}_sin * LANES + l] = math.sin(a)"]
    src += ["    npos = phis.shape[0]"]
    if handed:
        src += ["    for k in range(npos):",
                f"        for q in range({handed}):",
                "            FT[k, q * LANES + l] = trail[k, q]"]
    for j, e in enumerate(crank):
        q = handed + 2 * j
        m0 = f"K[{consts.index(e.k('phiM0'))}]"
        src += [f"    m0 = {m0}",
                "    if not (crank_tab[0, 0] == m0):   # (kernels.groups.crank's cos, sin)",
                "        crank_tab[0, 0] = m0",
                "        for k in range(npos):",
                "            crank_tab[1 + k, 0] = math.cos(phis[k] + m0)",
                "            crank_tab[1 + k, 1] = math.sin(phis[k] + m0)",
                "    for k in range(npos):",
                f"        FT[k, {q} * LANES + l] = crank_tab[1 + k, 0]",
                f"        FT[k, {q + 1} * LANES + l] = crank_tab[1 + k, 1]"]
    src += ["", ""]
    src += [part("lane_forces")]
    return "\n".join(src) + "\n"


def _accept_and_place_lines(e, c):
    """``kernels.triad._accept`` at a solution handed over (no move: the sign of
    det J and the margin, as the lane's verdict) and ``_place``, on det,
    margin, taken and the cos/sin of a, b and b + U435."""
    i2, i3, i4, i5 = e.ix[0], e.ix[3], e.ix[4], e.ix[5]
    l23, l34, l35 = (c(e.k(x)) for x in ("L23", "L34", "L35"))
    sign = c(f"sign{e.triad_row}")
    return [
        "sgn = 1.0 if det > 0.0 else -1.0",
        f"prev = {sign}",
        "bad = bad | (not taken) | ((prev != 0.0) & (sgn != prev)) | (not (margin >= tsing))",
        f"{sign} = sgn",
        "# _place",
        f"P{i3}_0 = P{i2}_0 + {l23} * ca", f"P{i3}_1 = P{i2}_1 + {l23} * sa",
        f"P{i4}_0 = P{i3}_0 + {l34} * cb", f"P{i4}_1 = P{i3}_1 + {l34} * sb",
        f"P{i5}_0 = P{i3}_0 + {l35} * cc", f"P{i5}_1 = P{i3}_1 + {l35} * sc",
    ]


def _triad_analog_lines(e, c, order):
    """``kernels.triad._place_analogs``' lines for the class III vertices 3, 4, 5:
    the first analogs (``order`` 1: from a1, b1, with the first analogs' own
    zero a1 = b1 = 0 as the local z) or the second (2: from a2, b2 and a1, b1),
    on the cos/sin of a, b and b + U435."""
    i2, i3, i4, i5 = e.ix[0], e.ix[3], e.ix[4], e.ix[5]
    l23, l34, l35 = (c(e.k(x)) for x in ("L23", "L34", "L35"))
    D, ak, bk, a1, b1 = ("V", "a1", "b1", "z", "z") if order == 1 else ("A", "a2", "b2", "a1", "b1")
    return [
        f"{D}{i3}_0 = {D}{i2}_0 - {l23} * {a1} * {a1} * ca - {l23} * {ak} * sa",
        f"{D}{i3}_1 = {D}{i2}_1 - {l23} * {a1} * {a1} * sa + {l23} * {ak} * ca",
        f"{D}{i4}_0 = {D}{i3}_0 - {l34} * ({bk} * sb + {b1} * {b1} * cb)",
        f"{D}{i4}_1 = {D}{i3}_1 + {l34} * ({bk} * cb - {b1} * {b1} * sb)",
        f"{D}{i5}_0 = {D}{i3}_0 - {l35} * ({bk} * sc + {b1} * {b1} * cc)",
        f"{D}{i5}_1 = {D}{i3}_1 + {l35} * ({bk} * cc - {b1} * {b1} * sc)",
    ]


def _class3_lines(e, c, t):
    """kernels.triad.class3 at a solution handed over (``handed``, ``_accept``
    without a move, ``_place``, first and second analogs), operation for
    operation."""
    i2, i6, i7, i3, i4, i5 = e.ix[:6]
    k = e.k
    l23, l34, l35, l46, l57 = (c(k(x)) for x in ("L23", "L34", "L35", "L46", "L57"))
    uc, us = c(f"{k('U435')}_cos"), c(f"{k('U435')}_sin")
    r = 4 * e.triad_row
    return [
        f"ca = {t(r)}", f"sa = {t(r + 1)}", f"cb = {t(r + 2)}", f"sb = {t(r + 3)}",
        f"cc = cb * {uc} - sb * {us}", f"sc = sb * {uc} + cb * {us}",
        "# closure_unit: the residual and det J at the handed solution",
        f"p3x = P{i2}_0 + {l23} * ca", f"p3y = P{i2}_1 + {l23} * sa",
        f"r4x = p3x + {l34} * cb - P{i6}_0", f"r4y = p3y + {l34} * sb - P{i6}_1",
        f"r5x = p3x + {l35} * cc - P{i7}_0", f"r5y = p3y + {l35} * sc - P{i7}_1",
        f"f1 = r4x * r4x + r4y * r4y - {l46} * {l46}",
        f"f2 = r5x * r5x + r5y * r5y - {l57} * {l57}",
        f"j11 = 2.0 * {l23} * (-r4x * sa + r4y * ca)",
        f"j12 = 2.0 * {l34} * (-r4x * sb + r4y * cb)",
        f"j21 = 2.0 * {l23} * (-r5x * sa + r5y * ca)",
        f"j22 = 2.0 * {l35} * (-r5x * sc + r5y * cc)",
        f"taken = max(abs(f1) / (2.0 * {l46}), abs(f2) / (2.0 * {l57})) <= tol * max({l46}, {l57})",
        "det = j11 * j22 - j12 * j21",
        f"margin = abs(det) / (4.0 * {l23} * {l46} * {l57} * max({l34}, {l35}))",
    ] + _accept_and_place_lines(e, c) + [
        "# first analogs",
        f"r4x = P{i4}_0 - P{i6}_0", f"r4y = P{i4}_1 - P{i6}_1",
        f"r5x = P{i5}_0 - P{i7}_0", f"r5y = P{i5}_1 - P{i7}_1",
        f"j11 = {l23} * (-r4x * sa + r4y * ca)", f"j12 = {l34} * (-r4x * sb + r4y * cb)",
        f"j21 = {l23} * (-r5x * sa + r5y * ca)", f"j22 = {l35} * (-r5x * sc + r5y * cc)",
        f"rhs1 = -(r4x * (V{i2}_0 - V{i6}_0) + r4y * (V{i2}_1 - V{i6}_1))",
        f"rhs2 = -(r5x * (V{i2}_0 - V{i7}_0) + r5y * (V{i2}_1 - V{i7}_1))",
        "dj = j11 * j22 - j12 * j21",
        "a1 = (rhs1 * j22 - j12 * rhs2) / dj", "b1 = (j11 * rhs2 - rhs1 * j21) / dj",
    ] + _triad_analog_lines(e, c, 1) + [
        "# second analogs",
        f"q4x = V{i4}_0 - V{i6}_0", f"q4y = V{i4}_1 - V{i6}_1",
        f"q5x = V{i5}_0 - V{i7}_0", f"q5y = V{i5}_1 - V{i7}_1",
        f"k3x = A{i2}_0 - {l23} * a1 * a1 * ca", f"k3y = A{i2}_1 - {l23} * a1 * a1 * sa",
        f"k4x = k3x - {l34} * b1 * b1 * cb - A{i6}_0",
        f"k4y = k3y - {l34} * b1 * b1 * sb - A{i6}_1",
        f"k5x = k3x - {l35} * b1 * b1 * cc - A{i7}_0",
        f"k5y = k3y - {l35} * b1 * b1 * sc - A{i7}_1",
        "rhs1 = -(q4x * q4x + q4y * q4y) - (r4x * k4x + r4y * k4y)",
        "rhs2 = -(q5x * q5x + q5y * q5y) - (r5x * k5x + r5y * k5y)",
        "a2 = (rhs1 * j22 - j12 * rhs2) / dj", "b2 = (j11 * rhs2 - rhs1 * j21) / dj",
    ] + _triad_analog_lines(e, c, 2)


def _class3_slider_lines(e, c, t):
    """kernels.triad.class3_slider at a solution handed over (``slider_handed``,
    ``_accept`` without a move, ``_place``, first and second analogs), operation
    for operation; the guide's direction as ``rrp``'s (hoisted for a fixed one:
    the same bits)."""
    i2, i6, i7, i3, i4, i5 = e.ix[:6]
    k = e.k
    l23, l34, l35, l46, off = (c(k(x)) for x in ("L23", "L34", "L35", "L46", "guide_offset"))
    uc, us = c(f"{k('U435')}_cos"), c(f"{k('U435')}_sin")
    r = 4 * e.triad_row
    guide = (_from_position_lanes(lane_direction(e, "u1", "guide_angle", 6))
             + _direction_analogs(e, "t1", 6)
             + ["ux = u1x", "uy = u1y", "nx = -uy", "ny = ux", "th1 = t11", "th2 = t12"])
    return guide + [
        f"ca = {t(r)}", f"sa = {t(r + 1)}", f"cb = {t(r + 2)}", f"sb = {t(r + 3)}",
        f"cc = cb * {uc} - sb * {us}", f"sc = sb * {uc} + cb * {us}",
        "# slider_closure_unit: the residuals and det J at the handed solution",
        f"p3x = P{i2}_0 + {l23} * ca", f"p3y = P{i2}_1 + {l23} * sa",
        f"r4x = p3x + {l34} * cb - P{i6}_0", f"r4y = p3y + {l34} * sb - P{i6}_1",
        f"f1 = 0.5 * (r4x * r4x + r4y * r4y - {l46} * {l46})",
        f"f2 = nx * (p3x + {l35} * cc - P{i7}_0) + ny * (p3y + {l35} * sc - P{i7}_1) - {off}",
        f"j11 = {l23} * (-r4x * sa + r4y * ca)", f"j12 = {l34} * (-r4x * sb + r4y * cb)",
        f"j21 = {l23} * (-nx * sa + ny * ca)", f"j22 = {l35} * (-nx * sc + ny * cc)",
        f"taken = max(abs(f1) / {l46}, abs(f2)) <= tol * max({l23}, {l46})",
        "det = j11 * j22 - j12 * j21",
        f"margin = abs(det) / ({l23} * {l46} * max({l34}, {l35}))",
    ] + _accept_and_place_lines(e, c) + [
        "# first analogs: r4.(P4' - P6') = 0, n.(P5' - G') - th' u.(P5 - G) = 0",
        f"r4x = P{i4}_0 - P{i6}_0", f"r4y = P{i4}_1 - P{i6}_1",
        f"w5x = P{i5}_0 - P{i7}_0", f"w5y = P{i5}_1 - P{i7}_1",
        f"j11 = {l23} * (-r4x * sa + r4y * ca)", f"j12 = {l34} * (-r4x * sb + r4y * cb)",
        f"j21 = {l23} * (-nx * sa + ny * ca)", f"j22 = {l35} * (-nx * sc + ny * cc)",
        f"rhs1 = -(r4x * (V{i2}_0 - V{i6}_0) + r4y * (V{i2}_1 - V{i6}_1))",
        f"rhs2 = (-(nx * (V{i2}_0 - V{i7}_0) + ny * (V{i2}_1 - V{i7}_1)) "
        "+ th1 * (ux * w5x + uy * w5y))",
        "dj = j11 * j22 - j12 * j21",
        "a1 = (rhs1 * j22 - j12 * rhs2) / dj", "b1 = (j11 * rhs2 - rhs1 * j21) / dj",
    ] + _triad_analog_lines(e, c, 1) + [
        "# second analogs",
        f"q4x = V{i4}_0 - V{i6}_0", f"q4y = V{i4}_1 - V{i6}_1",
        f"v5x = V{i5}_0 - V{i7}_0", f"v5y = V{i5}_1 - V{i7}_1",
        f"k3x = A{i2}_0 - {l23} * a1 * a1 * ca", f"k3y = A{i2}_1 - {l23} * a1 * a1 * sa",
        f"k4x = k3x - {l34} * b1 * b1 * cb - A{i6}_0",
        f"k4y = k3y - {l34} * b1 * b1 * sb - A{i6}_1",
        f"k5x = k3x - {l35} * b1 * b1 * cc - A{i7}_0",
        f"k5y = k3y - {l35} * b1 * b1 * sc - A{i7}_1",
        "rhs1 = -(q4x * q4x + q4y * q4y) - (r4x * k4x + r4y * k4y)",
        "rhs2 = (-(nx * k5x + ny * k5y) + 2.0 * th1 * (ux * v5x + uy * v5y)",
        f"        + th2 * (ux * w5x + uy * w5y) + th1 * th1 * {off})",
        "a2 = (rhs1 * j22 - j12 * rhs2) / dj", "b2 = (j11 * rhs2 - rhs1 * j21) / dj",
    ] + _triad_analog_lines(e, c, 2)


def _attach_lines(e, c):
    """AttachEmitter.careful's lines for a point turned with a link, order 2; for
    a point of fixed direction, ``kernels.groups.polar_point``'s at the angle's
    hoisted cos/sin (its own cos/sin of the same angle) and th' = th'' = 0."""
    base, a, b, out = e.ix[:4]
    cs, sn, ln = c(f"{e.k('angle')}_cos"), c(f"{e.k('angle')}_sin"), c(e.k("length"))
    if a < 0:
        return [
            f"P{out}_0 = P{base}_0 + {ln} * {cs}", f"P{out}_1 = P{base}_1 + {ln} * {sn}",
            f"V{out}_0 = V{base}_0 - {ln} * 0.0 * {sn}",
            f"V{out}_1 = V{base}_1 + {ln} * 0.0 * {cs}",
            f"A{out}_0 = A{base}_0 - {ln} * (0.0 * {sn} + 0.0 * 0.0 * {cs})",
            f"A{out}_1 = A{base}_1 + {ln} * (0.0 * {cs} - 0.0 * 0.0 * {sn})",
        ]
    return [
        f"vx = P{b}_0 - P{a}_0", f"vy = P{b}_1 - P{a}_1", "r2 = vx * vx + vy * vy",
        "bad = bad | (not (r2 > 0.0))",
        f"f = {ln} / math.sqrt(r2)",
        f"ex = f * ({cs} * vx - {sn} * vy)", f"ey = f * ({sn} * vx + {cs} * vy)",
        f"P{out}_0 = P{base}_0 + ex", f"P{out}_1 = P{base}_1 + ey",
        f"v1x = V{b}_0 - V{a}_0", f"v1y = V{b}_1 - V{a}_1",
        "cr1 = vx * v1y - vy * v1x", "th1 = cr1 / r2",
        f"V{out}_0 = V{base}_0 - th1 * ey", f"V{out}_1 = V{base}_1 + th1 * ex",
        f"v2x = A{b}_0 - A{a}_0", f"v2y = A{b}_1 - A{a}_1",
        "th2 = (vx * v2y - vy * v2x) / r2 - 2.0 * (vx * v1x + vy * v1y) * cr1 / (r2 * r2)",
        f"A{out}_0 = A{base}_0 - th2 * ey - th1 * th1 * ex",
        f"A{out}_1 = A{base}_1 + th2 * ex - th1 * th1 * ey",
    ]


def _from_position_lanes(lines):
    """The positions stage's lane lines (``Emitter.lanes``) on the force lanes'
    locals: a point's p3x, p3y as P3_0, P3_1, a constant's S[R_name, l] as
    FS[F_name * LANES + l]; a margin below the singularity tolerance (not the
    walk's safety margin) makes the lane bad."""
    out = []
    for line in lines:
        line = re.sub(r"\bS\[R_(\w+), l\]", r"FS[F_\1 * LANES + l]", line)
        line = re.sub(r"\bp(\d+)([xy])\b", lambda m: f"P{m[1]}_{'01'['xy'.index(m[2])]}", line)
        line = line.replace("low = low | (not (m >= margin_safe))",
                            "bad = bad | (not (m >= tsing))")
        if re.search(r"\bS\[|margin_safe|\blow\b", line):
            raise ValueError(f"a lane line the force lanes cannot take: {line!r}")
        out.append(line)
    return out


def _rrr_lines(e):
    """An RRR dyad by the positions stage's lane form (the cosine law without
    acos), its analogs by ``kernels.groups.rrr``'s 2 x 2 solves."""
    a, cc, b = e.ix[:3]
    return _from_position_lanes(e.lanes()) + [
        f"pax = P{b}_0 - P{a}_0", f"pay = P{b}_1 - P{a}_1",
        f"pcx = P{b}_0 - P{cc}_0", f"pcy = P{b}_1 - P{cc}_1",
        "dj = pax * pcy - pay * pcx",
        "# first analogs: (B - A).(B' - A') = 0, (B - C).(B' - C') = 0",
        f"h1 = pax * V{a}_0 + pay * V{a}_1", f"h2 = pcx * V{cc}_0 + pcy * V{cc}_1",
        f"V{b}_0 = (h1 * pcy - pay * h2) / dj", f"V{b}_1 = (pax * h2 - h1 * pcx) / dj",
        "# second analogs",
        f"ux = V{b}_0 - V{a}_0", f"uy = V{b}_1 - V{a}_1",
        f"wx = V{b}_0 - V{cc}_0", f"wy = V{b}_1 - V{cc}_1",
        f"h1 = pax * A{a}_0 + pay * A{a}_1 - (ux * ux + uy * uy)",
        f"h2 = pcx * A{cc}_0 + pcy * A{cc}_1 - (wx * wx + wy * wy)",
        f"A{b}_0 = (h1 * pcy - pay * h2) / dj", f"A{b}_1 = (pax * h2 - h1 * pcx) / dj",
    ]


def _input_lines(e, c, t, col):
    """An input's tip from its law's values the lane walk's table handed over
    (FT columns col .. col + 3: e(q) or q, q', q''), by
    ``kernels.groups.polar_point``'s lines (a rotary input) or
    ``kernels.inputs.slider_input``'s: the careful path's operations, its bits."""
    piv, tip = e.ix[0], e.ix[1]
    q1, q2 = t(col + 2), t(col + 3)
    if e.kind == ROTARY:
        ln = c(e.k("length"))
        return [f"cq = {t(col)}", f"sq = {t(col + 1)}", f"q1 = {q1}", f"q2 = {q2}",
                f"P{tip}_0 = P{piv}_0 + {ln} * cq", f"P{tip}_1 = P{piv}_1 + {ln} * sq",
                f"V{tip}_0 = V{piv}_0 - {ln} * q1 * sq", f"V{tip}_1 = V{piv}_1 + {ln} * q1 * cq",
                f"A{tip}_0 = A{piv}_0 - {ln} * (q2 * sq + q1 * q1 * cq)",
                f"A{tip}_1 = A{piv}_1 + {ln} * (q2 * cq - q1 * q1 * sq)"]
    a = e.k("guide_angle")
    gc, gs = c(f"{a}_cos"), c(f"{a}_sin")
    return [f"qq = {t(col)}", f"q1 = {q1}", f"q2 = {q2}",
            f"P{tip}_0 = P{piv}_0 + qq * {gc}", f"P{tip}_1 = P{piv}_1 + qq * {gs}",
            f"V{tip}_0 = V{piv}_0 + q1 * {gc}", f"V{tip}_1 = V{piv}_1 + q1 * {gs}",
            f"A{tip}_0 = A{piv}_0 + q2 * {gc}", f"A{tip}_1 = A{piv}_1 + q2 * {gs}"]


def _rrp_lines(e):
    """An RRP dyad by the positions stage's lane form (``kernels.groups.rrp``'s
    lines on the guide's unit vector), its analogs by ``rrp``'s lines."""
    a, g, b = e.ix[:3]
    return _from_position_lanes(e.lanes()) + _direction_analogs(e, "t1", 3) + [
        "th1 = t11", "th2 = t12",
        f"rx = P{b}_0 - P{a}_0", f"ry = P{b}_1 - P{a}_1",
        "ru = rx * u1x + ry * u1y",
        "# B' = G' + s' u + s th' n ; r.(B' - A') = 0",
        f"tx = V{g}_0 + s * th1 * nx - V{a}_0", f"ty = V{g}_1 + s * th1 * ny - V{a}_1",
        "s1 = -(rx * tx + ry * ty) / ru",
        f"V{b}_0 = V{g}_0 + s1 * u1x + s * th1 * nx",
        f"V{b}_1 = V{g}_1 + s1 * u1y + s * th1 * ny",
        "# B'' = G'' + s'' u + 2 s' th' n + s (th'' n - th'^2 u); r.(B'' - A'') + |B' - A'|^2 = 0",
        f"ex = A{g}_0 + 2.0 * s1 * th1 * nx + s * (th2 * nx - th1 * th1 * u1x) - A{a}_0",
        f"ey = A{g}_1 + 2.0 * s1 * th1 * ny + s * (th2 * ny - th1 * th1 * u1y) - A{a}_1",
        f"wx = V{b}_0 - V{a}_0", f"wy = V{b}_1 - V{a}_1",
        "s2 = -((wx * wx + wy * wy) + rx * ex + ry * ey) / ru",
        f"A{b}_0 = ex + A{a}_0 + s2 * u1x", f"A{b}_1 = ey + A{a}_1 + s2 * u1y",
    ]


def _direction_analogs(e, t, j):
    """The analogs ``t``1, ``t``2 of a guide's angle after ``emit.lane_direction``'s
    lines (``geometry.angle_analogs``' lines on the guide link's vector vx, vy
    and its r2; 0 for a guide of fixed direction)."""
    if e.ix[j] < 0:
        return [f"{t}1 = 0.0", f"{t}2 = 0.0"]
    a, b = e.ix[j], e.ix[j + 1]
    return [
        f"g1x = V{b}_0 - V{a}_0", f"g1y = V{b}_1 - V{a}_1",
        f"g2x = A{b}_0 - A{a}_0", f"g2y = A{b}_1 - A{a}_1",
        "gc1 = vx * g1y - vy * g1x",
        f"{t}1 = gc1 / r2",
        f"{t}2 = (vx * g2y - vy * g2x) / r2 - 2.0 * (vx * g1x + vy * g1y) * gc1 / (r2 * r2)",
    ]


def _direction_lines(e, u, t, key, j):
    """A guide's unit direction ``u``x, ``u``y by the positions stage's lane form
    (``emit.lane_direction``) and the analogs ``t``1, ``t``2 of its angle
    (``geometry.angle_analogs``' lines on the guide link's vector; 0 for a
    guide of fixed direction)."""
    return _from_position_lanes(lane_direction(e, u, key, j)) + _direction_analogs(e, t, j)


def _meet_lines(g1, e1, g2, e2, b):
    """B (point ``b``) where two guide lines meet, by the positions stage's lane
    form (``emit.lane_meet``), and its analogs (``kernels.groups._line_meet``'s
    lines on the directions u1, u2 and the analogs t11 ... t22 of their
    angles)."""
    return _from_position_lanes(lane_meet(f"p{g1}", e1, f"p{g2}", e2, f"p{b}") + [
        f"s2 = (P{b}_0 - P{g2}_0) * u2x + (P{b}_1 - P{g2}_1) * u2y",
        "dn = n1x * n2y - n1y * n2x",
        f"h1 = n1x * V{g1}_0 + n1y * V{g1}_1 + t11 * s1",
        f"h2 = n2x * V{g2}_0 + n2y * V{g2}_1 + t21 * s2",
        f"V{b}_0 = (h1 * n2y - n1y * h2) / dn", f"V{b}_1 = (n1x * h2 - h1 * n2x) / dn",
        f"h1 = (n1x * A{g1}_0 + n1y * A{g1}_1 + 2.0 * t11 * ((V{b}_0 - V{g1}_0) * u1x + "
        f"(V{b}_1 - V{g1}_1) * u1y) + t12 * s1 + t11 * t11 * {e1})",
        f"h2 = (n2x * A{g2}_0 + n2y * A{g2}_1 + 2.0 * t21 * ((V{b}_0 - V{g2}_0) * u2x + "
        f"(V{b}_1 - V{g2}_1) * u2y) + t22 * s2 + t21 * t21 * {e2})",
        f"A{b}_0 = (h1 * n2y - n1y * h2) / dn", f"A{b}_1 = (n1x * h2 - h1 * n2x) / dn",
    ])


def _transmission_lines(q, kind, args, c):
    """Transmission item ``q`` (``Emitter.transmission_items``) at this position:
    the directions u, w that ``kernels.metrics``' dyad_transmission,
    lead_transmission or lines_transmission hands to ``fold_angle``, by their
    lines (a line's angle: its hoisted cos/sin, ``_line``'s own calls)."""
    P = lambda i, x: f"P{i}_{x}"    # noqa: E731
    if kind == "dyad":
        a, b, cc = args
        return [f"ux = {P(a, 0)} - {P(b, 0)}", f"uy = {P(a, 1)} - {P(b, 1)}",
                f"wx = {P(cc, 0)} - {P(b, 0)}", f"wy = {P(cc, 1)} - {P(b, 1)}"]
    if kind == "lead":
        j, p, a, b, cc, d = args
        return [f"jx = {P(j, 0)}", f"jy = {P(j, 1)}",
                f"ax = {P(a, 0)} - jx", f"ay = {P(a, 1)} - jy",
                f"bx = {P(b, 0)} - jx", f"by = {P(b, 1)} - jy",
                f"cx = {P(cc, 0)} - jx", f"cy = {P(cc, 1)} - jy",
                f"dx = {P(d, 0)} - jx", f"dy = {P(d, 1)} - jy",
                "l1x = ay - by", "l1y = bx - ax", "l1w = ax * by - ay * bx",
                "l2x = cy - dy", "l2y = dx - cx", "l2w = cx * dy - cy * dx",
                f"ux = {P(p, 0)} - jx", f"uy = {P(p, 1)} - jy",
                "wx = l1y * l2w - l1w * l2y", "wy = l1w * l2x - l1x * l2w"]
    out = []
    for (i0, i1), (v, w) in (((args[0], args[1]), ("ux", "uy")),
                             ((args[3], args[4]), ("wx", "wy"))):
        j = 0 if v == "ux" else 1
        cs, sn = c(f"tr{q}_{j}_cos"), c(f"tr{q}_{j}_sin")
        if i0 < 0:
            out += [f"{v} = {cs}", f"{w} = {sn}"]
        else:
            out += [f"dx = {P(i1, 0)} - {P(i0, 0)}", f"dy = {P(i1, 1)} - {P(i0, 1)}",
                    f"{v} = {cs} * dx - {sn} * dy", f"{w} = {sn} * dx + {cs} * dy"]
    return out


def _peak_lines(plan, rocker, c):
    """force_stage's SET_WANT_PEAKS lines: the working point's acceleration
    (its point index ``iw`` known at run time: a select over the points) into
    RB's last two columns (force_flush takes their peak |a| with the scalar
    stage's own loop), and the running maximum of the output rocker's
    |angular acceleration| (the same lines as force_stage's)."""
    n = len(plan.point_names)
    col = 2 * len(plan.joint_names)

    def pick(stem):
        expr = f"{stem.format(n - 1)}"
        for i in range(n - 2, -1, -1):
            expr = f"({stem.format(i)} if iw == {i} else {expr})"
        return expr
    piv, pt = plan.point(rocker[0]), plan.point(rocker[1])
    return [
        "# the working point's |a| = |r'' omega1^2 + r' eps1| (mm/s^2), its peak in force_flush",
        "w2 = omega1 * omega1",
        f"RB[k, {col} * LANES + l] = {pick('A{}_0')} * w2 + {pick('V{}_0')} * eps1",
        f"RB[k, {col + 1} * LANES + l] = {pick('A{}_1')} * w2 + {pick('V{}_1')} * eps1",
        "# the output rocker's eps = theta'' omega1^2 + theta' eps1 (geometry.angle_analogs)",
        f"dx = P{pt}_0 - P{piv}_0", f"dy = P{pt}_1 - P{piv}_1",
        f"d1x = V{pt}_0 - V{piv}_0", f"d1y = V{pt}_1 - V{piv}_1",
        f"d2x = A{pt}_0 - A{piv}_0", f"d2y = A{pt}_1 - A{piv}_1",
        "r2 = dx * dx + dy * dy", "c1 = dx * d1y - dy * d1x", "th1 = c1 / r2",
        "th2 = (dx * d2y - dy * d2x) / r2 - 2.0 * (dx * d1x + dy * d1y) * c1 / (r2 * r2)",
        "ep = abs(th2 * w2 + th1 * eps1)",
        f"pe = {c('pe')}",
        f"{c('pe')} = ep if ((ep > pe) | (not (ep - ep == 0.0))) else pe",
    ]


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
