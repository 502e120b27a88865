"""Everything a scene study asks for, in memory: the scene's curves (and
forces), refined peaks, the crank's counterweight, the output rocker's dwell
and stroke, the machine's cyclogram (phases and phase errors), and the
dynamics cases with the forces along their motion, the reduced dynamics and
the flywheel.

One place for it: ``pipeline run`` (``runner``) writes it to a results file,
and a sweep's design re-run as a scene (``analysis.candidate.candidate_scene``,
which ``pipeline compare --candidate`` and the report's comparison use) is
solved by the same function.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor


def solve_scene(study):
    """The scene study ``study`` solved: a ``solve.scene.SceneResult`` with its
    peaks, counterweight, motion and (if the study asks) dynamics."""
    from .scene import run_scene
    if study.dynamics is None:
        res = run_scene(study)
        _kinematics(res)
        return res
    from ..compiler import plan_path
    from ..compiler.notice import INSTALLATION, compile_notice
    from .crank_motion import load_integrators
    # the dynamics (compiled integrations that release the GIL) run on a thread of
    # their own meanwhile: the same numbers, the cores shared with the scene.  On
    # the plan path their kernels are the installation's: loaded here, they start
    # at once; otherwise after the scene, which compiles the mechanism's module
    # (and says so)
    plan = study.mechanism.compile()
    early = plan_path.covers(plan)
    if early:   # (on a new installation, before the library is: a compile, said as one)
        with compile_notice(INSTALLATION):
            load_integrators(plan, study.mechanism, study.dynamics.method)
    with ThreadPoolExecutor(1) as pool:
        dynamics = pool.submit(_dynamics, study, plan) if early else None
        res = run_scene(study)
        if dynamics is None:
            dynamics = pool.submit(_dynamics, study, res.plan)
        _kinematics(res)
        res.dynamics, res.reduced, res.motion_forces, res.flywheel = dynamics.result()
    return res


def _dynamics(study, plan):
    """The study's dynamics cases, the reduced dynamics, the kinetostatics along
    each case's motion (with mass data) and the flywheel (where asked)."""
    from .crank_motion import run_dynamics
    from .reduced_dynamics import reduced_dynamics
    with ThreadPoolExecutor(1) as beside:
        # the flywheel's sizing reads its case's definition, not the motion (which says
        # only whether it is sized): beside the integrations, not after them
        sizing = None
        if study.dynamics.flywheel is not None:
            from .flywheel import flywheel_of, size_study_flywheel
            sizing = beside.submit(size_study_flywheel, study, plan)
        cases = run_dynamics(study, plan)
        reduced = reduced_dynamics(study, plan)
        along = None
        if study.mechanism.bodies:   # the kinetostatics along each case's motion
            from .motion_forces import case_forces
            along = {c.name: case_forces(study.mechanism, plan, c) for c in cases}
        flywheel = None
        if sizing is not None:      # not on a refused case (its reason)
            flywheel = flywheel_of(study, plan, cases, sizing)
    return cases, reduced, along, flywheel


def _kinematics(res):
    """The scene ``res``'s refined peaks, counterweight, output motion and cyclogram."""
    from .cyclogram import scene_cyclogram
    from .peaks import scene_motion, scene_peaks, split_bearing_peaks
    from .shaking import scene_counterweight
    res.peaks, bearings = split_bearing_peaks(scene_peaks(res))
    if bearings:        # [mechanism.friction]: the plain bearings' refined p, v and p*v
        res.dense.forces.friction.peaks = bearings
    res.counterweight = scene_counterweight(res)
    res.motion = scene_motion(res)
    res.cyclogram = scene_cyclogram(res)
