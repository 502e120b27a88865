"""The class III group's lines of the generated module, either kind (the hooks
of ``pipeline.compiler.emit.Emitter``): the careful path by its library
kernel from its row of the continuation state, the lane form and the force
lanes' lines (``lanes``), and its instances in the library's warm-up
mechanism."""

from __future__ import annotations

import math

from ...compiler.emit import SAME_BITS, TO_ROUNDING, Emitter, guide_link, guide_words
from ...compiler.lane_geometry import hoisted_cos_sin
from ...compiler.names import wrap_line
from . import G_CLASS3, G_CLASS3_SLIDER
from .lanes import force_lines, setup_lines, slider_force_lines, walk_lines
from .model import ClassIII, ClassIIISlider


class _Triad(Emitter):
    """What either kind shares: the continuation state, the watch, the fixed angle
    U435 of the ternary link (its cos/sin hoisted) and the lane form."""
    watched = True
    fast = True
    slider = False

    def derived(self):
        u = self.k("U435")
        return [(u, f"ternary_angle({self.k('L34')}, {self.k('L45')}, {self.k('L35')}, "
                    f"{self.k('orientation')})"),
                (f"{u}_cos", f"math.cos({u})"), (f"{u}_sin", f"math.sin({u})")]

    def lanes(self):
        return walk_lines(self)

    def setup_lines(self):
        return setup_lines(self)


class ClassIIIEmitter(_Triad):
    code = G_CLASS3
    force_lanes = SAME_BITS

    def careful(self):
        i2, i6, i7, i3, i4, i5 = (self.p(j) for j in range(6))
        k = self.k
        return [f"# {self.title()}: ternary link {self.pname(3)}-{self.pname(4)}-"
                f"{self.pname(5)} on leads from {self.pname(0)}, {self.pname(1)}, "
                f"{self.pname(2)}; Newton on the closure from the continuation state row "
                f"{self.triad_row}",
                f"st, m = class3(pos, d1, d2, {i2}, {i6}, {i7}, {i3}, {i4}, {i5}, {k('L23')}, "
                f"{k('L34')}, {k('U435')}, {k('L35')}, {k('L46')}, {k('L57')}, state, "
                f"{_row(self)}, order, tols, {k('U435')}_cos, {k('U435')}_sin)"]

    def transmission_items(self):
        i2, i6, i7, i3, i4, i5 = self.ix[:6]
        n = self.pname
        return (f"leads {n(4)}-{n(1)} and {n(5)}-{n(2)}, each against the line to the meet of "
                "the other two leads",
                [("lead", (i4, i6, i2, i3, i5, i7)), ("lead", (i5, i7, i2, i3, i4, i6))])

    def force_lines(self, c, t):
        return force_lines(self, c, t)


def _row(e):
    """A class III group's row of the continuation state as its kernel's
    argument: np.int64, not a literal (numba would compile the kernel once per
    row: once for each class III group of a mechanism, and again for a
    mechanism whose group has another row than the one the library warm-up
    compiled, pipeline.compiler.warmup)."""
    return f"np.int64({e.triad_row})"


class ClassIIISliderEmitter(_Triad):
    """The class III group with a block on a guide in place of lead 5-7: the
    continuation state, the watch and the lane form (``lanes.walk_lines``)
    like ``ClassIIIEmitter``'s."""
    code = G_CLASS3_SLIDER
    force_lanes = TO_ROUNDING
    guide_col = 6
    slider = True

    def derived(self):
        # (and the lane form's guide direction)
        return super().derived() + hoisted_cos_sin(self, "guide_angle")

    def careful(self):
        i2, i6, i7, i3, i4, i5 = (self.p(j) for j in range(6))
        ga, gb = guide_link(self, 6)
        k = self.k
        return [f"# {self.title()}: ternary link {self.pname(3)}-{self.pname(4)}-"
                f"{self.pname(5)}",
                f"# on leads from {self.pname(0)}, {self.pname(1)} and a block at {self.pname(5)} "
                f"on the guide {guide_words(self, 2, 6, 'guide_angle')}",
                "# (P5 at guide_offset from it); Newton on |P4 - P6| = L46, n.(P5 - G) = offset",
                f"# from the continuation state row {self.triad_row}",
                wrap_line(f"st, m = class3_slider(pos, d1, d2, {i2}, {i6}, {i7}, {i3}, {i4}, "
                           f"{i5}, {ga}, {gb}, {k('L23')}, {k('L34')}, {k('U435')}, "
                           f"{k('L35')}, {k('L46')}, {k('guide_angle')}, {k('guide_offset')}, "
                           f"state, {_row(self)}, order, tols, {k('U435')}_cos, "
                           f"{k('U435')}_sin)")]

    def force_lines(self, c, t):
        return slider_force_lines(self, c, t)


EMITTERS = (ClassIIIEmitter, ClassIIISliderEmitter)


def warmup(tip):
    """Its groups in the library's warm-up mechanism (``pipeline.compiler.warmup``),
    on points of its own and the crank's ``tip``, either kind: (fixed points,
    groups)."""
    deg = math.radians
    triad = dict(L23=272.5, L34=81.0, L45=104.5, L35=174.0, L46=104.5, a0=deg(44.0),
                 b0=deg(128.7))
    return {"C3_P6": (195.0, 226.0), "C3_P7": (46.0, 533.0)}, (
        ClassIII(input=tip, pivot_4="C3_P6", pivot_5="C3_P7", joints=("C3_P3", "C3_P4", "C3_P5"),
                 L57=261.0, **triad),
        ClassIIISlider(input=tip, pivot_4="C3_P6", guide_point="C3_P7",
                       joints=("C3_S3", "C3_S4", "C3_S5"), guide_angle=deg(171.0),
                       guide_offset=261.0, **triad))
