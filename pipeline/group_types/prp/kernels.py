"""The PRP dyad's kernel: where the guide lines of two blocks meet.

Conventions of ``pipeline.kernels.groups``: points read from and written to
``pos``/``d1``/``d2`` to ``order``; returns (status, margin)."""

import math

from numba import njit

from ...kernels.config import JIT, SINGULAR
from ...kernels.groups import _nan_point as nan_point, guide_direction, line_meet

__all__ = ("prp",)


@njit(**JIT)
def prp(pos, d1, d2, ig1, ga1, gb1, ig2, ga2, gb2, ib, angle1, offset1, angle2, offset2,
        order, sing_tol):
    """PRP dyad: two blocks joined by the revolute B, each sliding on a known
    guide.  Guide i runs through the known point G_i with a fixed direction
    (ga_i < 0: the absolute ``angle_i``) or one that turns with the link
    ga_i->gb_i (``angle_i`` relative to it); block i carries B at the
    perpendicular distance ``offset_i`` from its guide (on the +90 deg side).
    B is where the two lines of B meet (``kernels.groups.line_meet``); the margin |sin| of
    the angle between the guides is 0 where they are parallel (SINGULAR)."""
    th1, t11, t12 = guide_direction(pos, d1, d2, ga1, gb1, angle1, order)
    th2, t21, t22 = guide_direction(pos, d1, d2, ga2, gb2, angle2, order)
    if not (math.isfinite(th1) and math.isfinite(th2)):   # a guide link of no length
        nan_point(pos, d1, d2, ib)
        return SINGULAR, 0.0
    return line_meet(pos, d1, d2, ib, ig1, th1, t11, t12, offset1, ig2, th2, t21, t22,
                      offset2, order, sing_tol)
