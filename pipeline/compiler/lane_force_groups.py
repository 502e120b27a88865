"""The force lanes' lines of each group type, on the lane's locals (P3_0, V3_0,
A3_0 for point 3; a constant by ``c(name)``, a handed-over table column by
``t(col)``): the careful kernel's operations where they call no library
function at every position, else the positions stage's lane form with the
careful kernel's analog lines on it (``pipeline.compiler.lane_forces``
assembles them).  Also the lines of the motion's peaks and the transmission
items."""

from __future__ import annotations

import re

from ..kernels.inputs import ROTARY
from .lane_geometry import lane_direction, lane_meet


def attach_lines(e, c):
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


def from_position_lanes(lines):
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


def input_lines(e, c, t, col):
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


def direction_analogs(e, t, j):
    """The analogs ``t``1, ``t``2 of a guide's angle after ``lane_geometry.lane_direction``'s
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


def direction_lines(e, u, t, key, j):
    """A guide's unit direction ``u``x, ``u``y by the positions stage's lane form
    (``lane_geometry.lane_direction``) and the analogs ``t``1, ``t``2 of its angle
    (``geometry.angle_analogs``' lines on the guide link's vector; 0 for a
    guide of fixed direction)."""
    return from_position_lanes(lane_direction(e, u, key, j)) + direction_analogs(e, t, j)


def meet_lines(g1, e1, g2, e2, b):
    """B (point ``b``) where two guide lines meet, by the positions stage's lane
    form (``lane_geometry.lane_meet``), and its analogs (``kernels.groups.line_meet``'s
    lines on the directions u1, u2 and the analogs t11 ... t22 of their
    angles)."""
    return from_position_lanes(lane_meet(f"p{g1}", e1, f"p{g2}", e2, f"p{b}") + [
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


def transmission_lines(q, kind, args, c):
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


def peak_lines(plan, rocker, c):
    """force_stage's SET_WANT_PEAKS lines: the working point's acceleration
    (its point index ``iw`` known at run time: a select over the points,
    ``pick``'s blends rather than branches LLVM writes as masked stores) into
    RB's last two columns (force_flush takes their peak |a| with the scalar
    stage's own loop), and the running maximum of the output rocker's
    |angular acceleration| (the same lines as force_stage's)."""
    n = len(plan.point_names)
    col = 2 * len(plan.joint_names)

    def chosen(stem):
        expr = f"{stem.format(n - 1)}"
        for i in range(n - 2, -1, -1):
            expr = f"pick(iw == {i}, {stem.format(i)}, {expr})"
        return expr
    piv, pt = plan.point(rocker[0]), plan.point(rocker[1])
    return [
        "# the working point's |a| = |r'' omega1^2 + r' eps1| (mm/s^2), its peak in force_flush",
        "w2 = omega1 * omega1",
        f"RB[k, {col} * LANES + l] = {chosen('A{}_0')} * w2 + {chosen('V{}_0')} * eps1",
        f"RB[k, {col + 1} * LANES + l] = {chosen('A{}_1')} * w2 + {chosen('V{}_1')} * eps1",
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
