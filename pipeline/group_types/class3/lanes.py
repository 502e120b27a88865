"""The class III group's lines of the lane paths (either kind: with lead 5-7,
or with a block on a guide in its place): in the sweep's positions stage,
Newton in lock-step lanes (``walk_lines``; ``setup_lines``, its start in
``setup_lane``), and in the force lanes, the careful kernel at the solution the
walk handed over (``force_lines``, ``slider_force_lines``), operation for
operation.

The unknown angles a, b live as unit vectors e(a), e(b); a Newton update is a
rotation by a small angle, with cos/sin from their series (exact to rounding
for |angle| <= SMALL_ANGLE, larger corrections are refused); the predictor
rotates by the last increment (the secant predictor of the careful walk).
"""

from __future__ import annotations

from ...compiler.lane_force_groups import direction_analogs, from_position_lanes
from ...compiler.lane_geometry import lane_direction
from ...compiler.lanes import NEWTON_STEPS
from ...compiler.names import lane

SMALL_ANGLE = 0.05        # largest rotation taken by the cos/sin series, rad


def _rot_lines(c, s, delta):
    """e <- e rotated by ``delta`` (a small angle): cos/sin by their series."""
    return [
        f"z = {delta} * {delta}",
        "cd = 1.0 - z * (0.5 - z * (1.0 / 24.0 - z * (1.0 / 720.0 - z * (1.0 / 40320.0"
        " - z * (1.0 / 3628800.0)))))",
        f"sd = {delta} * (1.0 - z * (1.0 / 6.0 - z * (1.0 / 120.0 - z * (1.0 / 5040.0"
        " - z * (1.0 / 362880.0 - z * (1.0 / 39916800.0))))))",
        f"{c}, {s} = {c} * cd - {s} * sd, {s} * cd + {c} * sd",
    ]


def _triad_terms(e):
    """The names a class III group's lane lines use: its points, its lengths (and
    the slider's guide offset), the cos/sin of its fixed angle U435, and its rows
    of the lane array."""
    k = e.k
    t = f"t{e.triad_row}"
    P2, P6, P7, P3, P4, P5 = (e.xy(j) for j in range(6))
    T = dict(P2=P2, P6=P6, P7=P7, P3=P3, P4=P4, P5=P5,
             slider=e.slider,
             cu=lane(f"{k('U435')}_cos"), su=lane(f"{k('U435')}_sin"),
             r={x: f"S[R_{t}_{x}, l]" for x in ("ca", "sa", "cb", "sb", "dca", "dsa", "dcb",
                                                 "dsb", "sign")})
    T.update((x, lane(k(x))) for x in ("L23", "L34", "L35", "L46"))
    T["off" if T["slider"] else "L57"] = lane(k("guide_offset" if T["slider"] else "L57"))
    return T


def _triad_predictor_lines(e, T):
    """The closure solved, then e(a), e(b) turned by the last increment."""
    r = T["r"]
    if T["slider"]:
        out = [f"# {e.title()}: Newton on |P4 - P6| = L46 and n.(P5 - {T['P7']}) = offset, "
               "n the",
               "# guide's unit normal (the kernel's slider_closure_unit)"]
        out += lane_direction(e, "gu", "guide_angle", 6) + ["gnx = -guy", "gny = gux"]
    else:
        out = [f"# {e.title()}: Newton on the closure |P4 - P6| = L46, |P5 - P7| = L57"]
    return out + [
        "# predictor: e(a), e(b) turned by the last increment (secant)",
        f"ca0 = {r['ca']}", f"sa0 = {r['sa']}", f"cb0 = {r['cb']}", f"sb0 = {r['sb']}",
        f"ca = ca0 * {r['dca']} - sa0 * {r['dsa']}",
        f"sa = sa0 * {r['dca']} + ca0 * {r['dsa']}",
        f"cb = cb0 * {r['dcb']} - sb0 * {r['dsb']}",
        f"sb = sb0 * {r['dcb']} + cb0 * {r['dsb']}",
        "corr_a = 0.0", "corr_b = 0.0"]


def _triad_residual_lines(T):
    """The closure's residual F = (f1, f2) and its Jacobian J at e(a), e(b)."""
    P2, P3, P6, P7 = T["P2"], T["P3"], T["P6"], T["P7"]
    L23, L34, L35, L46, cu, su = (T[x] for x in ("L23", "L34", "L35", "L46", "cu", "su"))
    out = [f"cc = cb * {cu} - sb * {su}", f"sc = sb * {cu} + cb * {su}",
           f"{P3}x = {P2}x + {L23} * ca", f"{P3}y = {P2}y + {L23} * sa",
           f"r4x = {P3}x + {L34} * cb - {P6}x", f"r4y = {P3}y + {L34} * sb - {P6}y"]
    if T["slider"]:      # (slider_closure_unit: F1 halved, F2 a distance)
        return out + [
            f"f1 = 0.5 * (r4x * r4x + r4y * r4y - {L46} * {L46})",
            f"f2 = gnx * ({P3}x + {L35} * cc - {P7}x) + gny * ({P3}y + {L35} * sc - {P7}y)"
            f" - {T['off']}",
            f"j11 = {L23} * (r4y * ca - r4x * sa)",
            f"j12 = {L34} * (r4y * cb - r4x * sb)",
            f"j21 = {L23} * (gny * ca - gnx * sa)",
            f"j22 = {L35} * (gny * cc - gnx * sc)",
            "det = j11 * j22 - j12 * j21",
        ]
    return out + [
        f"r5x = {P3}x + {L35} * cc - {P7}x", f"r5y = {P3}y + {L35} * sc - {P7}y",
        f"f1 = r4x * r4x + r4y * r4y - {L46} * {L46}",
        f"f2 = r5x * r5x + r5y * r5y - {T['L57']} * {T['L57']}",
        f"j11 = 2.0 * {L23} * (r4y * ca - r4x * sa)",
        f"j12 = 2.0 * {L34} * (r4y * cb - r4x * sb)",
        f"j21 = 2.0 * {L23} * (r5y * ca - r5x * sa)",
        f"j22 = 2.0 * {L35} * (r5y * cc - r5x * sc)",
        "det = j11 * j22 - j12 * j21",
    ]


def _triad_newton_lines(T):
    """NEWTON_STEPS Newton steps, each a rotation of e(a), e(b) by small angles."""
    out = []
    for step in range(NEWTON_STEPS):
        out += [f"# Newton step {step + 1}: J (da, db) = F, then e(a), e(b) turned by -da, -db"]
        out += _triad_residual_lines(T)
        out += ["da = (f1 * j22 - j12 * f2) / det", "db = (j11 * f2 - f1 * j21) / det",
                "corr_a += da", "corr_b += db",
                f"big = big | (abs(da) > {SMALL_ANGLE}) | (abs(db) > {SMALL_ANGLE})",
                "na = -da", "nb = -db"]
        out += _rot_lines("ca", "sa", "na") + _rot_lines("cb", "sb", "nb")
    return out


def _triad_check_lines(T):
    """The confirming evaluation: residual, margin and branch checked."""
    L23, L34, L35, L46 = (T[x] for x in ("L23", "L34", "L35", "L46"))
    out = ["# renormalise the unit vectors (one Newton step for 1/|e|, no division)",
           "g = 1.5 - 0.5 * (ca * ca + sa * sa)", "ca *= g", "sa *= g",
           "g = 1.5 - 0.5 * (cb * cb + sb * sb)", "cb *= g", "sb *= g",
           "# confirming evaluation: the residual, and det J for the margin and the branch"]
    out += _triad_residual_lines(T)
    if T["slider"]:
        out += [f"res = max(abs(f1) / {L46}, abs(f2))",
                f"conv = res <= tol * max({L23}, {L46})",
                f"m = abs(det) / ({L23} * {L46} * max({L34}, {L35}))"]
    else:
        L57 = T["L57"]
        out += [f"res = max(abs(f1) / (2.0 * {L46}), abs(f2) / (2.0 * {L57}))",
                f"conv = res <= tol * max({L46}, {L57})",
                f"m = abs(det) / (4.0 * {L23} * {L46} * {L57} * max({L34}, {L35}))"]
    return out + [
        "sgn = 1.0 if det > 0.0 else -1.0",
        f"big = big | (not conv) | (sgn != {T['r']['sign']}) | (abs(corr_a) > jump) | "
        "(abs(corr_b) > jump)",
        "low = low | (not (m >= margin_safe))",
        "margin = min(margin, m)"]


def _triad_handover_lines(e, T):
    """The step's increment kept (the next predictor), the solution handed to
    the force stage, and P4, P5."""
    r, P3, P4, P5 = T["r"], T["P3"], T["P4"], T["P5"]
    L34, L35 = T["L34"], T["L35"]
    return [
        "# the increment of this step: the next predictor, and the careful walk's step bound",
        "ia_c = ca0 * ca + sa0 * sa", "ia_s = ca0 * sa - sa0 * ca",
        "ib_c = cb0 * cb + sb0 * sb", "ib_s = cb0 * sb - sb0 * cb",
        "big = big | (abs(ia_s) > step_change) | (abs(ib_s) > step_change) | (ia_c <= 0.0)"
        " | (ib_c <= 0.0)",
        f"{r['dca']} = ia_c", f"{r['dsa']} = ia_s", f"{r['dcb']} = ib_c", f"{r['dsb']} = ib_s",
        f"{r['ca']} = ca", f"{r['sa']} = sa", f"{r['cb']} = cb", f"{r['sb']} = sb",
        "# the solution at this position, handed to the force stage",
        f"theta[k, {1 + 4 * e.triad_row} * LANES + l] = ca",
        f"theta[k, {2 + 4 * e.triad_row} * LANES + l] = sa",
        f"theta[k, {3 + 4 * e.triad_row} * LANES + l] = cb",
        f"theta[k, {4 + 4 * e.triad_row} * LANES + l] = sb",
        f"{P4}x = {P3}x + {L34} * cb", f"{P4}y = {P3}y + {L34} * sb",
        f"{P5}x = {P3}x + {L35} * cc", f"{P5}y = {P3}y + {L35} * sc",
    ]


def walk_lines(e):
    """Lane lines of one class III group (or its sliding variant: P5 on a line
    instead of a lead): predictor, NEWTON_STEPS Newton steps, the confirming
    evaluation and the checks."""
    T = _triad_terms(e)
    return (_triad_predictor_lines(e, T) + _triad_newton_lines(T) + _triad_check_lines(T)
            + _triad_handover_lines(e, T))


def setup_lines(e):
    """setup_lane's lines of one class III group: e(a), e(b) at phis[0] from the
    careful solve, and the first increment from the analogs (a', b')."""
    t = f"t{e.triad_row}"
    j = e.triad_row
    P2, P3, P4 = (e.p(x) for x in (0, 3, 4))
    out = [f"# {e.title()}: e(a), e(b) at phis[0] and the first increment from the analogs",
           f"av = state[{j}, S_A]",
           f"bv = state[{j}, S_B]",
           f"S[R_{t}_ca, l] = math.cos(av)",
           f"S[R_{t}_sa, l] = math.sin(av)",
           f"S[R_{t}_cb, l] = math.cos(bv)",
           f"S[R_{t}_sb, l] = math.sin(bv)",
           f"S[R_{t}_a0c, l] = S[R_{t}_ca, l]",
           f"S[R_{t}_a0s, l] = S[R_{t}_sa, l]",
           f"S[R_{t}_b0c, l] = S[R_{t}_cb, l]",
           f"S[R_{t}_b0s, l] = S[R_{t}_sb, l]",
           f"S[R_{t}_sign, l] = state[{j}, S_DET_SIGN]"]
    out += [f"theta[0, {1 + 4 * j + q} * LANES + l] = S[R_{t}_{v}, l]"
            for q, v in enumerate(("ca", "sa", "cb", "sb"))]
    return out + [
        "# a' = (P3' - P2') . n(a) / L23, b' = (P4' - P3') . n(b) / L34",
        f"ad = ((d1[{P3}, 1] - d1[{P2}, 1]) * math.cos(av) - (d1[{P3}, 0] - d1[{P2}, 0])"
        f" * math.sin(av)) / {e.k('L23')}",
        f"bd = ((d1[{P4}, 1] - d1[{P3}, 1]) * math.cos(bv) - (d1[{P4}, 0] - d1[{P3}, 0])"
        f" * math.sin(bv)) / {e.k('L34')}",
        "h = phis[1] - phis[0]",
        "ok = ok and math.isfinite(ad) and math.isfinite(bd)",
        "if not ok:",
        "    ad = 0.0",
        "    bd = 0.0",
        f"S[R_{t}_dca, l] = math.cos(ad * h)",
        f"S[R_{t}_dsa, l] = math.sin(ad * h)",
        f"S[R_{t}_dcb, l] = math.cos(bd * h)",
        f"S[R_{t}_dsb, l] = math.sin(bd * h)",
        "if not ok:",
        f"    S[R_{t}_ca, l] = 1.0",
        f"    S[R_{t}_sa, l] = 0.0",
        f"    S[R_{t}_cb, l] = 1.0",
        f"    S[R_{t}_sb, l] = 0.0"]


def accept_and_place_lines(e, c):
    """``kernels._accept`` at a solution handed over (no move: the sign of
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


def triad_analog_lines(e, c, order):
    """``kernels._place_analogs``' lines for the class III vertices 3, 4, 5:
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


def second_analog_terms(e, c):
    """The terms of the second analogs' right-hand sides that both class III
    kernels share (``class3`` and ``class3_slider``, operation for operation):
    vertex 3's acceleration without a2's term (k3), and vertices 4 and 5 from it
    without b2's, less the accelerations of the leads' pivots 6 and 7 (k4, k5)."""
    i2, i6, i7 = e.ix[0], e.ix[1], e.ix[2]
    l23, l34, l35 = (c(e.k(x)) for x in ("L23", "L34", "L35"))
    return [
        f"k3x = A{i2}_0 - {l23} * a1 * a1 * ca", f"k3y = A{i2}_1 - {l23} * a1 * a1 * sa",
        f"k4x = k3x - {l34} * b1 * b1 * cb - A{i6}_0",
        f"k4y = k3y - {l34} * b1 * b1 * sb - A{i6}_1",
        f"k5x = k3x - {l35} * b1 * b1 * cc - A{i7}_0",
        f"k5y = k3y - {l35} * b1 * b1 * sc - A{i7}_1",
    ]


def force_lines(e, c, t):
    """``kernels.class3`` at a solution handed over (``handed``, ``_accept``
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
    ] + accept_and_place_lines(e, c) + [
        "# first analogs",
        f"r4x = P{i4}_0 - P{i6}_0", f"r4y = P{i4}_1 - P{i6}_1",
        f"r5x = P{i5}_0 - P{i7}_0", f"r5y = P{i5}_1 - P{i7}_1",
        f"j11 = {l23} * (-r4x * sa + r4y * ca)", f"j12 = {l34} * (-r4x * sb + r4y * cb)",
        f"j21 = {l23} * (-r5x * sa + r5y * ca)", f"j22 = {l35} * (-r5x * sc + r5y * cc)",
        f"rhs1 = -(r4x * (V{i2}_0 - V{i6}_0) + r4y * (V{i2}_1 - V{i6}_1))",
        f"rhs2 = -(r5x * (V{i2}_0 - V{i7}_0) + r5y * (V{i2}_1 - V{i7}_1))",
        "dj = j11 * j22 - j12 * j21",
        "a1 = (rhs1 * j22 - j12 * rhs2) / dj", "b1 = (j11 * rhs2 - rhs1 * j21) / dj",
    ] + triad_analog_lines(e, c, 1) + [
        "# second analogs",
        f"q4x = V{i4}_0 - V{i6}_0", f"q4y = V{i4}_1 - V{i6}_1",
        f"q5x = V{i5}_0 - V{i7}_0", f"q5y = V{i5}_1 - V{i7}_1",
    ] + second_analog_terms(e, c) + [
        "rhs1 = -(q4x * q4x + q4y * q4y) - (r4x * k4x + r4y * k4y)",
        "rhs2 = -(q5x * q5x + q5y * q5y) - (r5x * k5x + r5y * k5y)",
        "a2 = (rhs1 * j22 - j12 * rhs2) / dj", "b2 = (j11 * rhs2 - rhs1 * j21) / dj",
    ] + triad_analog_lines(e, c, 2)


def slider_force_lines(e, c, t):
    """``kernels.class3_slider`` at a solution handed over (``handed`` of the slider variant,
    ``_accept`` without a move, ``_place``, first and second analogs), operation
    for operation; the guide's direction as a slider dyad's (hoisted for a fixed one:
    the same bits)."""
    i2, i6, i7, i3, i4, i5 = e.ix[:6]
    k = e.k
    l23, l34, l35, l46, off = (c(k(x)) for x in ("L23", "L34", "L35", "L46", "guide_offset"))
    uc, us = c(f"{k('U435')}_cos"), c(f"{k('U435')}_sin")
    r = 4 * e.triad_row
    guide = (from_position_lanes(lane_direction(e, "u1", "guide_angle", 6))
             + direction_analogs(e, "t1", 6)
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
    ] + accept_and_place_lines(e, c) + [
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
    ] + triad_analog_lines(e, c, 1) + [
        "# second analogs",
        f"q4x = V{i4}_0 - V{i6}_0", f"q4y = V{i4}_1 - V{i6}_1",
        f"v5x = V{i5}_0 - V{i7}_0", f"v5y = V{i5}_1 - V{i7}_1",
    ] + second_analog_terms(e, c) + [
        "rhs1 = -(q4x * q4x + q4y * q4y) - (r4x * k4x + r4y * k4y)",
        "rhs2 = (-(nx * k5x + ny * k5y) + 2.0 * th1 * (ux * v5x + uy * v5y)",
        f"        + th2 * (ux * w5x + uy * w5y) + th1 * th1 * {off})",
        "a2 = (rhs1 * j22 - j12 * rhs2) / dj", "b2 = (j11 * rhs2 - rhs1 * j21) / dj",
    ] + triad_analog_lines(e, c, 2)
