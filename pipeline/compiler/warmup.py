"""The kernel library compiled once per installation, for every group type.

A generated module's ``position`` calls a library kernel per group type and
input law (``pipeline.kernels.groups``, ``triad``, ``inputs``), and numba
compiles each for the types the call passes the first time a mechanism with
that group is compiled: about half a second a type, added to the first scene
that has it.  The call's types do not depend on the mechanism (points and
constants are int64 and float64 values, pipeline.compiler.generate), so one
mechanism that has every group type and every input law compiles them all,
into numba's cache, for every later mechanism: ``mechanism()``.  It is a
structure, not a design (it is compiled, never solved), and the process beside
the first sweep compiles it (``pipeline.compiler.beside.compile_library``), at
the lowest priority.  By hand:

    python -m pipeline.compiler.warmup
"""

from __future__ import annotations


def mechanism():
    """Every group type (pipeline.model.groups) and input law, each on points of
    its own; no bodies (the force kernels compile in a scene's process beside)."""
    import math

    from ..model.groups.ppr import PPR
    from ..model.groups.prp import PRP
    from ..model.groups.rpp import RPP
    from ..model.groups.rpr import RPR
    from ..model.groups.rrp import RRP
    from ..model.groups.rrr import RRR
    from ..model.groups.attach import Attach
    from ..model.groups.class3 import ClassIII
    from ..model.groups.class3_slider import ClassIIISlider
    from ..model.groups.law import Law
    from ..model.groups.rotary_input import RotaryInput
    from ..model.groups.slider_input import SliderInput
    from ..model.mechanism import Crank, Mechanism
    deg = math.radians
    fixed = {"P1": (0.0, 0.0), "P4": (38.0, 0.0), "P6": (38.0, 50.0), "P9": (0.0, 60.0),
             "P15": (195.0, 226.0), "P16": (46.0, 533.0), "P25": (-30.0, 0.0),
             "P27": (0.0, -40.0), "P29": (30.0, -30.0)}
    triad = dict(L23=272.5, L34=81.0, L45=104.5, L35=174.0, L46=104.5, a0=deg(44.0),
                 b0=deg(128.7))
    groups = (
        RRR(A="P2", C="P4", B="P3", L_AB=41.0, L_CB=40.0, W=1),
        Attach(point="P7", base="P4", along=("P4", "P3"), angle=0.0, length=55.0),
        Attach(point="P8", base="P2", along=None, angle=deg(30.0), length=5.0),
        RRP(A="P2", B="P10", guide_point="P1", guide_angle=deg(90.0), L_AB=44.2, W=-1),
        RRP(A="P3", B="P11", guide_point="P4", guide_angle=deg(10.0), L_AB=30.0, W=1,
            guide_link=("P4", "P3")),
        RPR(block="P2", pivot="P6", guide_end="P12", guide_length=60.0),
        PRP(B="P5", guide1_point="P4", guide1_angle=0.0, guide2_point="P6", guide2_angle=0.0,
            guide1_link=("P4", "P3")),
        RPP(A="P2", B="P13", guide_point="P1", guide_angle=0.0, slot_angle=deg(90.0)),
        PPR(pin="P7", B="P14", guide_point="P9", guide_angle=0.0, slot_angle=deg(60.0)),
        ClassIII(input="P2", pivot_4="P15", pivot_5="P16", joints=("P17", "P18", "P19"),
                 L57=261.0, **triad),
        ClassIIISlider(input="P2", pivot_4="P15", guide_point="P16",
                       joints=("P20", "P21", "P22"), guide_angle=deg(171.0),
                       guide_offset=261.0, **triad),
        RotaryInput(pivot="P4", tip="P23", length=35.0,
                    law=Law("cycloidal", start=deg(30.0), travel=deg(40.0), rise=deg(150.0))),
        RotaryInput(pivot="P25", tip="P24", length=20.0,
                    law=Law("linear", ratio=1.0, phase=deg(90.0))),
        SliderInput(guide_point="P27", block="P26", guide_angle=0.0,
                    law=Law("table", table=tuple((deg(c), v) for c, v in
                                                 ((0, 0.0), (90, 3.0), (180, 5.0), (270, 1.0))))),
        SliderInput(guide_point="P29", block="P28", guide_angle=deg(45.0),
                    law=Law("harmonic", start=0.0, travel=10.0, rise=deg(120.0))),
    )
    return Mechanism("library_warmup", fixed, Crank(pivot="P1", tip="P2", length=15.0,
                                                    omega1=60.0), groups)


def compile_group_kernels() -> None:
    """Compile (or load from numba's cache) the library kernels of every group
    type and input law, for the types a scene's generated ``position`` passes
    them: by compiling the warm-up mechanism's first-class ``advance`` and
    ``start`` (which call ``position``) for the scene's types.  And the library
    kernels a scene calls from Python (pipeline.solve.scene, .reactions), by
    calling them as it does, on zeros."""
    import numpy as np

    from ..kernels.forces import equilibrium_residual, shaking
    from ..kernels.geometry import link_angles
    from . import kernels_for
    plan = mechanism().compile()
    if not compile_first_class(kernels_for(plan)):
        return          # numba's JIT disabled (NUMBA_DISABLE_JIT)
    curve = np.zeros((1, plan.n_points, 2))
    link_angles(curve, curve, curve, plan.link_a, plan.link_b, 2,
                np.zeros((1, len(plan.link_a), 3)))
    pos = curve[0]
    equilibrium_residual(pos, pos, pos, np.zeros(1)[0], np.zeros((0, 3)), plan.body_com,
                         plan.body_turn)
    shaking(pos, pos, pos, 0.0, 0.0, plan.par, plan.body_com, plan.body_turn,
            plan.body_mass_off, plan.crank_pivot)


def compile_first_class(mod) -> bool:
    """Compile (or load) the generated module ``mod``'s first-class ``advance``
    and ``start`` for the types the scene's walk and the crank dynamics call
    them with (``pipeline.kernels.walk``: ADVANCE, START), and with them its
    ``position`` and the library kernels it calls.  False where numba's JIT is
    disabled (NUMBA_DISABLE_JIT: nothing to compile)."""
    from ..kernels.walk import ADVANCE, START
    if not getattr(mod.advance_first_class, "compile", None):
        return False
    mod.advance_first_class.compile(ADVANCE.signature)
    mod.start_first_class.compile(START.signature)
    return True


if __name__ == "__main__":
    compile_group_kernels()
