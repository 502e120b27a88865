"""Everything a scene study asks for, in memory: the scene's curves (and
forces), refined peaks, the crank's counterweight, the output rocker's dwell
and stroke, the machine's cyclogram (phases and phase errors), and the dynamics cases with the forces along their motion, the reduced dynamics
and the flywheel.

One place for it: ``pipeline run`` (``runner``) writes it to a results file,
and a sweep's design re-run as a scene (``analysis.candidate.candidate_scene``,
which ``pipeline compare --candidate`` and the report's comparison use) is
solved by the same function.
"""

from __future__ import annotations


def solve_scene(study):
    """The scene study ``study`` solved: a ``solve.scene.SceneResult`` with its
    peaks, counterweight, motion and (if the study asks) dynamics."""
    from .peaks import scene_motion, scene_peaks, split_bearing_peaks
    from .scene import run_scene
    from .shaking import scene_counterweight
    res = run_scene(study)
    res.peaks, bearings = split_bearing_peaks(scene_peaks(res))
    if bearings:        # [mechanism.friction]: the plain bearings' refined p, v and p*v
        res.dense.forces.friction.peaks = bearings
    res.counterweight = scene_counterweight(res)
    res.motion = scene_motion(res)
    from .cyclogram import scene_cyclogram
    res.cyclogram = scene_cyclogram(res)
    if study.dynamics is not None:
        from .crank_motion import reduced_dynamics, run_dynamics
        res.dynamics = run_dynamics(study, res.plan)
        res.reduced = reduced_dynamics(study, res.plan)
        if study.mechanism.bodies:   # the kinetostatics along each case's motion
            from .motion_forces import case_forces
            res.motion_forces = {c.name: case_forces(study.mechanism, res.plan, c)
                                 for c in res.dynamics}
        if study.dynamics.flywheel is not None:   # not on a refused case (its reason)
            from .flywheel import flywheel_of
            res.flywheel = flywheel_of(study, res.plan, res.dynamics)
    return res
