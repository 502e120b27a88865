"""The kernel library compiled once per installation, for every group type.

The plan path's kernels (``pipeline.compiler.plan_path``: a scene's positions,
forces and crank dynamics for any mechanism, the plan read as data) have one
kernel per form of a group, each calling its group type's library kernel
(``pipeline.kernels.groups``, ``inputs``, each group type's
``pipeline.group_types.*.kernels``) with the types a generated module's
``position`` passes it too (points and constants are int64 and float64 values,
pipeline.compiler.generate).  The forms are those of one mechanism that has
every group type and every input law: ``mechanism()``.  It is a structure, not
a design (it is compiled, never solved); compiling the plan path compiles every
group kernel into numba's cache, for every later mechanism, scene or sweep.
The process beside the first sweep does it
(``pipeline.compiler.beside.compile_library``), at the lowest priority.  By hand:

    pipeline compile --library
"""

from __future__ import annotations


def mechanism():
    """Every group type and input law, each on points of its own: the
    mechanism's own elements (attached points, inputs) and each group-type
    folder's ``emitter.warmup`` (``pipeline.group_types``); no bodies (the force
    kernels compile in a scene's process beside)."""
    import math

    from .. import group_types
    from ..model.groups.attach import Attach
    from ..model.groups.law import Law
    from ..model.groups.rotary_input import RotaryInput
    from ..model.groups.slider_input import SliderInput
    from ..model.mechanism import Crank, Mechanism
    deg = math.radians
    fixed = {"P1": (0.0, 0.0), "P4": (38.0, 0.0), "P25": (-30.0, 0.0), "P27": (0.0, -40.0),
             "P29": (30.0, -30.0)}
    groups = [
        Attach(point="P7", base="P1", along=("P1", "P2"), angle=0.0, length=55.0),
        Attach(point="P8", base="P2", along=None, angle=deg(30.0), length=5.0),
        RotaryInput(pivot="P4", tip="P23", length=35.0,
                    law=Law("cycloidal", start=deg(30.0), travel=deg(40.0), rise=deg(150.0))),
        RotaryInput(pivot="P25", tip="P24", length=20.0,
                    law=Law("linear", ratio=1.0, phase=deg(90.0))),
        SliderInput(guide_point="P27", block="P26", guide_angle=0.0,
                    law=Law("table", table=tuple((deg(c), v) for c, v in
                                                 ((0, 0.0), (90, 3.0), (180, 5.0), (270, 1.0))))),
        SliderInput(guide_point="P29", block="P28", guide_angle=deg(45.0),
                    law=Law("harmonic", start=0.0, travel=10.0, rise=deg(120.0))),
    ]
    for mod in group_types.part("emitter"):
        points, more = mod.warmup("P2")
        fixed.update(points)
        groups += more
    return Mechanism("library_warmup", fixed, Crank(pivot="P1", tip="P2", length=15.0,
                                                    omega1=60.0), tuple(groups))


def compile_group_kernels() -> None:
    """Compile (or load from numba's cache) the library kernels a scene calls
    from Python (pipeline.solve.scene, .reactions, .peaks, .cyclogram, .flywheel,
    .friction), by calling them as it does, on zeros (``plan_path.compile_plan_path``
    calls this after the plan path's own, which compile the kernels of every group
    type and input law)."""
    import numpy as np

    from ..kernels.dynamics import energy_orbit
    from ..kernels.forces import equilibrium_residual, shaking
    from ..kernels.geometry import link_angles
    from ..kernels.metrics import dwell_error, relative_angle
    # the output rocker's angle and the dwell (solve.peaks, .cyclogram), the
    # flywheel's orbit (solve.flywheel)
    relative_angle(1.0, 0.0, 0.0, 1.0)
    q = np.zeros(6, np.int64)
    dwell_error(np.zeros(4), 1, q, q.copy())
    energy_orbit(np.ones(5), np.zeros(5), 0.1, 0.0, np.ones(3))
    plan = mechanism().compile()
    _compile_friction_forces(plan)
    curve = np.zeros((1, plan.n_points, 2))
    link_angles(curve, curve, curve, plan.link_a, plan.link_b, 2,
                np.zeros((1, len(plan.link_a), 3)))
    pos = curve[0]
    equilibrium_residual(pos, pos, pos, np.zeros(1)[0], np.zeros((0, 3)), plan.body_com,
                         plan.body_turn)
    shaking(pos, pos, pos, 0.0, 0.0, plan.par, plan.body_com, plan.body_turn,
            plan.body_mass_off, plan.crank_pivot)


def _compile_friction_forces(plan) -> None:
    """``kernels.friction.friction_forces`` compiled (not run) for the types of
    the arguments ``solve.friction.solve_positions`` passes it (the plan's arrays
    as they are, every other array and number as that function makes it): 6 s,
    which a scene with friction waited otherwise."""
    import numpy as np
    from numba import typeof

    from ..kernels.friction import friction_forces
    if not getattr(friction_forces, "compile", None):
        return          # numba's JIT disabled
    xy, v, m = np.zeros((plan.n_points, 2)), np.zeros(1), np.zeros((1, 1))
    args = (xy, xy, xy, 0.0, 0.0, plan.gravity, plan.par, plan.body_com, plan.body_turn,
            plan.body_mass_off, plan.joint_point, plan.joint_bodies, plan.slide_bodies,
            plan.slide_dir, plan.slide_angle, int(plan.crank_body), plan.load_body,
            plan.load_point, np.zeros((1, 3)), 0.0, v, 0.0, v, 1e-12, 50, m, v, m, v, v, v,
            np.zeros((1, 3)), np.zeros((1, 2)), np.zeros((1, 2)), v, v, np.zeros(4), False)
    friction_forces.compile(tuple(typeof(a) for a in args))
