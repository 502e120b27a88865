"""The sweep's force stage in lock-step lanes.

LANES candidates that passed the positions stage in the lanes, and the stroke
and margin gates, are solved together position by position: kinematics to
the acceleration analogs, the applied and inertia loads, the force equations
(``force_equations.eliminated``, the same lines as ``forces_at``) and the
running maximum of |M_bal|; the lane loop is the innermost loop, straight-line
code, so LLVM turns it into packed vector instructions.

The lines are the careful kernels' own operations in their own order
(``kernels.groups.crank``, ``kernels.triad.class3`` from a solution handed
over, the centres of mass as ``AttachEmitter.careful``, ``kernels.forces.
applied_loads``), compiled without contraction like them: a candidate gets
the numbers of the scalar force stage to the bit.  The one library call of
those kernels, the crank's cos/sin of phi1 + phiM0, comes from a table
computed once per value of phiM0 by the same call.

Where the scalar stage would stop or leave the handed solution (its closure
residual above Newton's tolerance, det J changing sign or below the
singularity margin, a link of no length), the lane says so (row F_bad) and
its candidate takes the scalar force stage, as before.  The peak reaction is
found afterwards from the reactions the lanes wrote, by the scalar stage's
own loop (``may_reach`` and ``math.hypot``, a library call).

A mechanism with a group or a force system the lanes do not know (see
``lane_form``) keeps the scalar force stage for every candidate.
"""

from __future__ import annotations

import re

from .emit import AttachEmitter, ClassIIIEmitter, CrankEmitter, constant_names
from .force_equations import MM, UNROLLED_MAX, eliminated, is_square
from .skeleton import part


def lane_form(plan, ems) -> str:
    """Why the force stage of ``plan`` has no lane form ('' where it has one)."""
    if not is_square(plan):
        return "its force system is not square"
    if len(plan.slide_names) or plan.n_inputs:
        return "it has prismatic pairs or inputs besides the crank"
    for e in ems:
        if isinstance(e, (CrankEmitter, ClassIIIEmitter)):
            continue
        if isinstance(e, AttachEmitter) and e.ix[1] >= 0:
            continue
        return f"{type(e).__name__[:-len('Emitter')]} groups have no lane form of their forces"
    return ""


def lane_force_kernel(plan, names, ems) -> str:
    """Source of the force lanes of ``plan`` (``force_lanes``, ``force_lane_in``,
    their constants and the driver ``force_flush``), or of the skeleton without
    them."""
    why = lane_form(plan, ems)
    if not all(e.fast for e in ems[:plan.n_kinematic]):
        why = "no lane path: a group without a lane form of its positions"
    body, m = eliminated(plan, names) if not why else ([], 0)
    if not why and m > UNROLLED_MAX:
        why = f"its force system leaves {m} unknowns to the run time (more than unrolled)"
    if why:
        return part("no_lane_forces").format(why=why)
    consts = constant_names(plan, names, ems)
    nb, nj = len(plan.body_names), len(plan.joint_names)
    triads = [e for e in ems if isinstance(e, ClassIIIEmitter)]
    crank = [e for e in ems if isinstance(e, CrankEmitter)]
    rows = consts + [f"mass{b}" for b in range(nb)] + [f"jS{b}" for b in range(nb)]
    rows += ["pm", "bad"] + [f"sign{e.triad_row}" for e in triads]
    ft = 4 * len(triads) + 2 * len(crank)     # per position: e(a), e(b) of each, crank cos/sin

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
            q = 4 * len(triads) + 2 * crank.index(e)
            ln = c(e.k("length"))
            L += [f"cc = {t(q)}", f"sc = {t(q + 1)}",
                  f"P{tip}_0 = P{o}_0 + {ln} * cc", f"P{tip}_1 = P{o}_1 + {ln} * sc",
                  f"V{tip}_0 = V{o}_0 - {ln} * sc", f"V{tip}_1 = V{o}_1 + {ln} * cc",
                  f"A{tip}_0 = A{o}_0 - {ln} * cc", f"A{tip}_1 = A{o}_1 - {ln} * sc"]
        elif isinstance(e, ClassIIIEmitter):
            L += _class3_lines(e, c, t)
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
    L += _force_lines(body, nj)
    L += ["# the running maximum of |M_bal| (force_stage's test, NaN and inf included)",
          f"pm = {c('pm')}",
          f"{c('pm')} = mb if ((abs(mb) > abs(pm)) | (not (mb - mb == 0.0))) else pm",
          f"{c('bad')} = 1.0 if bad else {c('bad')}"]
    flat = [f"F_{r} = {i}" for i, r in enumerate(rows)]
    src = ["# ---- the force stage in lanes (pipeline.compiler.lane_forces) ----",
           "HAS_LANE_FORCES = True", f"N_FROWS = {len(rows)}   # rows of FS[row * LANES + lane]",
           f"FT_COLS = {ft}   # FT[k, col * LANES + lane]: e(a), e(b) of each class III group, "
           "the crank's cos/sin", f"N_RCOLS = {2 * nj}   # RB[k, col * LANES + lane]: the "
           "reactions (x, y) of each joint"]
    src += flat
    src += ["", "", "@njit(**JIT)   # strict, like the scalar force stage: its bits",
            "def force_lanes(FS, FT, RB, n_lanes, npos, tol, tsing, omega1, eps1, loads):",
            '    """Positions 0 .. npos - 1 of every lane: the reactions into RB, the',
            '    running maximum of |M_bal| and the lane\'s verdict into FS."""',
            "    for l in range(n_lanes):",
            f"        {c('pm')} = 0.0",
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
    for i, r in enumerate(consts):
        src.append(f"    FS[F_{r} * LANES + l] = K[{i}]")
    for b in range(nb):
        off = int(plan.body_mass_off[b])
        src += [f"    FS[F_mass{b} * LANES + l] = par[{off}]",
                f"    FS[F_jS{b} * LANES + l] = par[{off + 1}]"]
    src += ["    npos = phis.shape[0]"]
    if triads:
        src += ["    for k in range(npos):",
                f"        for q in range({4 * len(triads)}):",
                "            FT[k, q * LANES + l] = trail[k, q]"]
    for j, e in enumerate(crank):
        q = 4 * len(triads) + 2 * j
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


def _class3_lines(e, c, t):
    """kernels.triad.class3 at a solution handed over (``handed``, ``_accept``
    without a move, ``_place``, first and second analogs), operation for
    operation."""
    i2, i6, i7, i3, i4, i5 = e.ix[:6]
    k = e.k
    l23, l34, l35, l46, l57 = (c(k(x)) for x in ("L23", "L34", "L35", "L46", "L57"))
    uc, us = c(f"{k('U435')}_cos"), c(f"{k('U435')}_sin")
    r = 4 * e.triad_row
    sign = c(f"sign{e.triad_row}")
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
        "sgn = 1.0 if det > 0.0 else -1.0",
        f"prev = {sign}",
        "bad = bad | (not taken) | ((prev != 0.0) & (sgn != prev)) | (not (margin >= tsing))",
        f"{sign} = sgn",
        "# _place",
        f"P{i3}_0 = P{i2}_0 + {l23} * ca", f"P{i3}_1 = P{i2}_1 + {l23} * sa",
        f"P{i4}_0 = P{i3}_0 + {l34} * cb", f"P{i4}_1 = P{i3}_1 + {l34} * sb",
        f"P{i5}_0 = P{i3}_0 + {l35} * cc", f"P{i5}_1 = P{i3}_1 + {l35} * sc",
        "# first analogs",
        f"r4x = P{i4}_0 - P{i6}_0", f"r4y = P{i4}_1 - P{i6}_1",
        f"r5x = P{i5}_0 - P{i7}_0", f"r5y = P{i5}_1 - P{i7}_1",
        f"j11 = {l23} * (-r4x * sa + r4y * ca)", f"j12 = {l34} * (-r4x * sb + r4y * cb)",
        f"j21 = {l23} * (-r5x * sa + r5y * ca)", f"j22 = {l35} * (-r5x * sc + r5y * cc)",
        f"rhs1 = -(r4x * (V{i2}_0 - V{i6}_0) + r4y * (V{i2}_1 - V{i6}_1))",
        f"rhs2 = -(r5x * (V{i2}_0 - V{i7}_0) + r5y * (V{i2}_1 - V{i7}_1))",
        "dj = j11 * j22 - j12 * j21",
        "a1 = (rhs1 * j22 - j12 * rhs2) / dj", "b1 = (j11 * rhs2 - rhs1 * j21) / dj",
        f"V{i3}_0 = V{i2}_0 - {l23} * z * z * ca - {l23} * a1 * sa",
        f"V{i3}_1 = V{i2}_1 - {l23} * z * z * sa + {l23} * a1 * ca",
        f"V{i4}_0 = V{i3}_0 - {l34} * (b1 * sb + z * z * cb)",
        f"V{i4}_1 = V{i3}_1 + {l34} * (b1 * cb - z * z * sb)",
        f"V{i5}_0 = V{i3}_0 - {l35} * (b1 * sc + z * z * cc)",
        f"V{i5}_1 = V{i3}_1 + {l35} * (b1 * cc - z * z * sc)",
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
        f"A{i3}_0 = A{i2}_0 - {l23} * a1 * a1 * ca - {l23} * a2 * sa",
        f"A{i3}_1 = A{i2}_1 - {l23} * a1 * a1 * sa + {l23} * a2 * ca",
        f"A{i4}_0 = A{i3}_0 - {l34} * (b2 * sb + b1 * b1 * cb)",
        f"A{i4}_1 = A{i3}_1 + {l34} * (b2 * cb - b1 * b1 * sb)",
        f"A{i5}_0 = A{i3}_0 - {l35} * (b2 * sc + b1 * b1 * cc)",
        f"A{i5}_1 = A{i3}_1 + {l35} * (b2 * cc - b1 * b1 * sc)",
    ]


def _attach_lines(e, c):
    """AttachEmitter.careful's lines for a point turned with a link, order 2."""
    base, a, b, out = e.ix[:4]
    cs, sn, ln = c(f"{e.k('angle')}_cos"), c(f"{e.k('angle')}_sin"), c(e.k("length"))
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


def _force_lines(body, nj):
    """``forces_at``'s lines (``force_equations.eliminated``) on the lane's locals:
    the loads LD, the positions P; the reactions into RB, M_bal into mb."""
    out = ["# the force equations (force_equations.eliminated: forces_at's lines)"]
    skip = False
    for line in body:
        if line.startswith("applied_loads("):
            skip = True             # the loads are the lines above
            continue
        if skip:                    # the call's second line
            skip = False
            continue
        line = re.sub(r"-loads_out\[(\d+), (\d)\]", r"-LD\1_\2", line)
        line = re.sub(r"pos\[I_(\d+), (\d)\]", r"P\1_\2", line)
        m = re.fullmatch(r"r_out\[(\d+), (\d)\] = (\w+)", line)
        if m:
            j, q, v = int(m[1]), int(m[2]), m[3]
            line = f"RB[k, {2 * j + q} * LANES + l] = {v}"
        m = re.fullmatch(r"return (\w+)", line)
        if m:
            line = f"mb = {m[1]}"
        if re.search(r"\b(pos|d1|d2|loads_out|r_out|slide_out|work_a|work_b|par)\[", line):
            raise ValueError(f"a line of forces_at the lanes cannot take: {line!r}")
        out.append(line)
    return out
