"""The required motion law of the output rocker ([output.motion_law]) and the
law error of a design against it.

A law gives the rocker's normalised displacement (0 at the dwell, 1 at the
full swing) against the cycle angle psi, in degrees over one turn of the main
shaft: psi = rot * (phi1 - phi0) + phase, so psi grows as the crank turns
whichever its direction (DOMAIN.md section 9: the OV-7 cyclogram).  Either

* phases, contiguous round the turn, each a dwell (the displacement stays) or
  a swing to the displacement ``level`` with a law inside it: linear,
  cycloidal or harmonic (x: the fraction of the phase, y: the fraction of the
  swing)

      linear     y = x
      harmonic   y = (1 - cos(pi x)) / 2
      cycloidal  y = x - sin(2 pi x) / (2 pi)

  e.g. the OV-7 eyelets: dwell 240 -> 30 deg, forward 30 -> 130, back
  130 -> 240; or

* a table of cycle angles against displacement (any units, e.g. a design's
  own rocker angle; normalised by its smallest and largest value), periodic,
  interpolated linearly or by a periodic cubic spline.

The law error of a design (``law_error`` in ``pipeline.kernels.metrics``, the
one formula of the sweep and of a scene): the rocker's angle over the
revolution normalised the same way, against the law at the grid's positions;
RMS and largest deviation.  With ``align = "best"`` (the default) the law is
shifted round the turn to fit best, as the crank's mounting phase would align
it (the dwell error aligns its best window the same way); ``law_shift`` says by
how much.  With ``align = "fixed"`` the law is held at psi as given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..base.limits import ANGLE, LAW_VALUE

LAWS = ("linear", "cycloidal", "harmonic")
ALIGN = ("best", "fixed")
INTERPOLATIONS = ("linear", "cubic")


def swing(law: str, x):
    """The fraction of a swing done at the fraction ``x`` of its phase."""
    x = np.asarray(x, float)
    if law == "linear":
        return x
    if law == "harmonic":
        return 0.5 * (1.0 - np.cos(np.pi * x))
    if law == "cycloidal":
        return x - np.sin(2.0 * np.pi * x) / (2.0 * np.pi)
    raise ValueError(f"unknown swing law {law!r}")


@dataclass(frozen=True)
class Phase:
    start: float        # deg, cycle angle in [0, 360)
    length: float       # deg, > 0
    law: str            # "dwell" or one of LAWS
    level0: float       # displacement at the start
    level1: float       # and at the end


@dataclass(frozen=True)
class MotionLaw:
    phases: tuple = ()          # Phase, contiguous round the turn
    angles: tuple = ()          # table: cycle angles, deg, increasing, span < 360
    values: tuple = ()          # table: normalised displacement
    interpolation: str = "linear"
    align: str = "best"
    phase: float = 0.0          # deg: the cycle angle at phi1 = phi0

    @property
    def kind(self):
        return "phases" if self.phases else "table"

    def at(self, psi):
        """The normalised displacement at cycle angles ``psi`` (deg, any range)."""
        psi = np.mod(np.asarray(psi, float), 360.0)
        if self.phases:
            # each angle in the phase that started last before it (the smallest
            # distance past a start; a distance that rounds to a full turn is 0)
            x = np.stack([np.mod(psi - p.start, 360.0) for p in self.phases])
            x = np.where(x >= 360.0 - 1e-9, 0.0, x)
            k = np.argmin(x, axis=0)
            x = np.take_along_axis(x, k[None], axis=0)[0]
            out = np.empty(psi.shape)
            for j, p in enumerate(self.phases):
                here = k == j
                t = np.minimum(x[here] / p.length, 1.0)
                y = np.zeros(t.shape) if p.law == "dwell" else swing(p.law, t)
                out[here] = p.level0 + (p.level1 - p.level0) * y
            return out
        a = np.asarray(self.angles, float)
        v = np.asarray(self.values, float)
        xa = np.append(a, a[0] + 360.0)
        ya = np.append(v, v[0])
        t = a[0] + np.mod(psi - a[0], 360.0)       # into [a0, a0 + 360)
        if self.interpolation == "cubic":
            from scipy.interpolate import CubicSpline
            return CubicSpline(xa, ya, bc_type="periodic")(t)
        return np.interp(t, xa, ya)

    def cycle_angles(self, crank, phis):
        """Cycle angle psi (deg, [0, 360)) of crank angles ``phis`` (rad)."""
        return np.mod(np.degrees(crank.rot * (np.asarray(phis, float) - crank.phi0))
                      + self.phase, 360.0)

    def on_grid(self, crank, phis):
        """The law at the crank angles ``phis`` of a revolution grid."""
        return self.at(self.cycle_angles(crank, phis))

    @property
    def best(self):
        return self.align == "best"

    def error(self, theta, crank, phis) -> dict:
        """law_error (RMS), law_error_max and law_shift (deg) of the rocker
        angles ``theta`` at the n positions ``phis`` of a uniform revolution."""
        from ..kernels.metrics import law_error
        theta = np.ascontiguousarray(theta, dtype=np.float64)
        n = theta.shape[0]
        law = self.on_grid(crank, phis)
        rms, top, s = law_error(theta, np.concatenate([law, law]), 0, self.best, np.empty(n))
        return {"law_error": float(rms), "law_error_max": float(top),
                "law_shift": s * 360.0 / n if s >= 0 else math.nan, "law_align": self.align}


def parse_motion_law(sec) -> MotionLaw:
    """[output.motion_law] (``sec``: a ``pipeline.study.section.Section``)."""
    align = sec.string("align", "best", choices=ALIGN)
    phase = sec.number("phase", 0.0, within=ANGLE)
    has_phases, has_table = sec.has("phases"), sec.has("angles") or sec.has("values")
    if has_phases == has_table:
        raise sec.error("", "give either phases = [{ from, to, law, level }, ...] or a table "
                            "(angles = [...], values = [...]), not both" if has_phases else
                        "give the law: phases = [{ from, to, law, level }, ...] or a table "
                        "(angles = [...], values = [...])")
    if has_phases:
        law = MotionLaw(phases=_phases(sec), align=align, phase=phase)
        sec.done()
        return law
    angles = sec.numbers("angles", within=ANGLE)
    values = sec.numbers("values", within=LAW_VALUE)
    interpolation = sec.string("interpolation", "linear", choices=INTERPOLATIONS)
    if len(angles) != len(values):
        raise sec.error("values", f"{len(values)} values for {len(angles)} angles")
    if len(angles) < 3:
        raise sec.error("angles", f"a table needs at least 3 points, got {len(angles)}")
    a = np.asarray(angles)
    if not (np.diff(a) > 0).all():
        k = int(np.flatnonzero(np.diff(a) <= 0)[0])
        raise sec.error("angles", f"must increase: {a[k]:g} is followed by {a[k + 1]:g}")
    if not a[-1] - a[0] < 360.0:
        raise sec.error("angles", f"must span less than one turn (the law is periodic): "
                                  f"{a[0]:g} .. {a[-1]:g} deg")
    v = np.asarray(values)
    lo, hi = float(v.min()), float(v.max())
    if not hi > lo:
        raise sec.error("values", "do not move: the law needs a swing")
    sec.done()
    return MotionLaw(angles=tuple(float(x) for x in a),
                     values=tuple(float(x) for x in (v - lo) / (hi - lo)),
                     interpolation=interpolation, align=align, phase=phase)


JOIN_TOL = 1e-9         # deg: a phase starts where the one before ends


def check_turn(sec, spans):
    """Phases that follow each other round the turn and cover it once (a
    motion law's, an organ's in ``[cycle]``): ``spans`` [(its study item,
    start in [0, 360) deg, length deg)] in order.  A gap or an overlap raises
    the next item's one-line error, a span other than one turn the section
    ``sec``'s."""
    for (_, start, length), (nxt, start2, _) in zip(spans, spans[1:] + spans[:1]):
        end = (start + length) % 360.0
        if abs((start2 - end + 180.0) % 360.0 - 180.0) > JOIN_TOL:
            gap = (start2 - end) % 360.0
            what = (f"a gap of {gap:g} deg" if gap < 180.0 else
                    f"an overlap of {360.0 - gap:g} deg")
            raise nxt.error("from", f"the phases must join round the turn: this one starts at "
                                    f"{start2:g} deg, the one before ends at {end:g} ({what})")
    total = sum(s[2] for s in spans)
    if abs(total - 360.0) > 1e-6:
        raise sec.error("phases", f"the phases span {total:g} deg; they must cover the turn "
                                  "exactly once (360 deg)")


def _phases(sec):
    items = sec.tables("phases")
    if not items:
        raise sec.error("phases", "at least one phase is needed")
    raw = []
    for it in items:
        start = it.number("from", within=ANGLE)
        end = it.number("to", within=ANGLE)
        law = it.string("law", choices=("dwell",) + LAWS)
        if law == "dwell":
            level = None
        else:
            level = it.number("level")
            if not 0.0 <= level <= 1.0:
                raise it.error("level", f"the normalised displacement is between 0 (the dwell) "
                                        f"and 1 (the full swing), got {level:g}")
        length = (end - start) % 360.0
        if not length > 0.0:
            raise it.error("to", f"the phase {start:g} -> {end:g} deg is empty")
        it.done()
        raw.append((it, start % 360.0, length, law, level))
    check_turn(sec, [r[:3] for r in raw])
    swings = [k for k, r in enumerate(raw) if r[3] != "dwell"]
    if not swings:
        raise sec.error("phases", "every phase is a dwell: the law needs a swing")
    # a dwell keeps the displacement the phase before it reached
    n = len(raw)
    end_level = [None] * n
    for k in range(n):
        if raw[k][3] != "dwell":
            end_level[k] = raw[k][4]
    for _ in range(2):          # twice round: every dwell finds the swing before it
        for k in range(n):
            if end_level[k] is None and end_level[k - 1] is not None:
                end_level[k] = end_level[k - 1]
    phases = []
    for k, (it, start, length, law, _) in enumerate(raw):
        l0, l1 = end_level[k - 1], end_level[k]
        if law != "dwell" and l0 == l1:
            raise it.error("level", f"the swing stays at {l1:g}: make it a dwell, or give "
                                    "the level it swings to")
        phases.append(Phase(start, length, law, l0, l1))
    levels = [p.level1 for p in phases]
    if min(levels) != 0.0 or max(levels) != 1.0:
        raise sec.error("phases", f"the levels reach {min(levels):g} .. {max(levels):g}; the "
                                  "normalised displacement must reach 0 (the dwell) and 1 "
                                  "(the full swing)")
    return tuple(phases)
