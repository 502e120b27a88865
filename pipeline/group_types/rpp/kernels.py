"""The RPP dyad's kernel (the Scotch yoke; PPR is the same chain).

Conventions of ``pipeline.kernels.groups``: points read from and written to
``pos``/``d1``/``d2`` to ``order``; returns (status, margin)."""

import math

from numba import njit

from ...kernels.config import JIT, SINGULAR
from ...kernels.groups import _nan_point as nan_point, guide_direction, line_meet

__all__ = ("rpp",)


@njit(**JIT)
def rpp(pos, d1, d2, ia, ig, ga, gb, ib, guide_angle, guide_offset, slot_angle, slot_offset,
        order, sing_tol):
    """RPP dyad (Scotch yoke): a block pinned at the known point A slides in a
    slot of the yoke, and the yoke slides on a guide.  The guide runs through
    the known point G with a fixed direction (ga < 0: absolute
    ``guide_angle``) or one that turns with the link ga->gb (``guide_angle``
    relative to it); the yoke's reference point B travels on the line at the
    perpendicular distance ``guide_offset`` from it.  The slot is fixed in the
    yoke at ``slot_angle`` from the guide, and A runs on it at the distance
    ``slot_offset`` from the slot's line through B.  So B is where the yoke's
    line and the slot's line through A (shifted back by the offset) meet:

        (B - G) . n_g = guide_offset,  (B - A) . n_s = -slot_offset,

    n = the direction turned +90 deg.  The margin |sin slot_angle| does not
    change with the crank (0: the slot runs along the guide, SINGULAR)."""
    th, t1, t2 = guide_direction(pos, d1, d2, ga, gb, guide_angle, order)
    if not math.isfinite(th):
        nan_point(pos, d1, d2, ib)
        return SINGULAR, 0.0
    return line_meet(pos, d1, d2, ib, ig, th, t1, t2, guide_offset, ia, th + slot_angle,
                      t1, t2, -slot_offset, order, sing_tol)
