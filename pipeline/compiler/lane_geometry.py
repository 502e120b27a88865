"""Lane lines that the lock-step positions (``emit``'s ``lanes``) and the force
lanes (``lane_force_groups``) share: a per-candidate angle's hoisted cos/sin, a
guide's unit direction, and the point where two lines meet."""

from __future__ import annotations

from .names import lane


def hoisted_cos_sin(e, *keys):
    """``derived`` entries: cos and sin of the angles ``keys``, once per candidate."""
    out = []
    for key in keys:
        a = e.k(key)
        out += [(f"{a}_cos", f"math.cos({a})"), (f"{a}_sin", f"math.sin({a})")]
    return out


def lane_direction(e, u, angle_key, j):
    """Lane lines of a guide's unit direction ``u``x, ``u``y (kernels.groups.guide_direction
    as a vector): e(angle) hoisted, or, for a guide turning with the link at gidx
    columns j, j + 1, that link's vector normalised and turned by the hoisted
    cos/sin of the angle (a link of no length: the careful path)."""
    c, s = lane(f"{e.k(angle_key)}_cos"), lane(f"{e.k(angle_key)}_sin")
    if e.ix[j] < 0:
        return [f"{u}x = {c}", f"{u}y = {s}"]
    a, b = e.xy(j), e.xy(j + 1)
    return [f"vx = {b}x - {a}x", f"vy = {b}y - {a}y", "r2 = vx * vx + vy * vy",
            "bad = bad | (not (r2 > 0.0))",
            "f = 1.0 / math.sqrt(r2)",
            f"{u}x = f * ({c} * vx - {s} * vy)",
            f"{u}y = f * ({s} * vx + {c} * vy)"]


def lane_meet(G1, e1, G2, e2, B):
    """Lane lines of ``B`` where two lines meet (kernels.groups.line_meet): line i
    through G_i along u_i (locals u1x ... u2y) at the offset e_i along n_i = u_i
    turned +90 deg; ``m`` the margin |sin| of the angle between them (near 0:
    the careful path)."""
    return ["n1x = -u1y", "n1y = u1x", "n2x = -u2y", "n2y = u2x",
            "den = u1x * n2x + u1y * n2y",
            "m = abs(den)",
            "low = low | (not (m >= margin_safe))",
            f"gx = {G1}x - {G2}x", f"gy = {G1}y - {G2}y",
            f"s1 = ({e2} - {e1} * (n1x * n2x + n1y * n2y) - (gx * n2x + gy * n2y)) / den",
            f"{B}x = {G1}x + {e1} * n1x + s1 * u1x",
            f"{B}y = {G1}y + {e1} * n1y + s1 * u1y"]
