"""A sweep's peak metrics refined between the positions, as a scene refines them.

A sweep's peaks (/metrics/peak_reaction, peak_M_bal, ...) are the largest of
the grid's positions: up to a few 1e-3 below the peak between two positions.
The design re-run as a scene (``candidate.design_scene``: the sweep's study
with the design's mechanism, at the sweep's positions and operating speed)
refines each peak between the positions (``solve.peaks.scene_peaks``).
``design_peaks`` gives a design's peak metrics from those refined peaks, by
the same functions in the same order as the scene, so `pipeline show
--candidate`, the scene of an exported design and `pipeline analyze` (which
refines fronts 1-3 and ranks them on these values) print the same numbers.

A refined maximum is never below the grid's (the refinement starts from the
largest sample and keeps only a larger one), so a peak objective's refined
value is the grid's or larger.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..kernels import config as kc

# a sweep's peak metric -> (the scene's peak quantity it is the extreme of, its items:
# None every item, "working point" the study's working point only); the refined value is
# the largest of those peaks (the smallest for min_transmission_angle)
PEAK_METRICS = {
    "peak_reaction": ("reaction", None),
    "peak_M_bal": ("M_bal", None),
    "peak_acceleration": ("acceleration", "working point"),
    "peak_shaking_force": ("shaking_force", None),
    "peak_shaking_moment": ("shaking_moment", None),
    "transmission_deviation": ("min_transmission_angle", None),
    "min_transmission_angle": ("min_transmission_angle", None),
    "peak_pv": ("bearing_pv", None),
}
# where the refined peak reaction is: its joint (index into the force analysis' joints,
# as the sweep's peak_joint) and crank angle (deg, as the sweep's peak_phi)
LOCATIONS = ("peak_joint", "peak_phi")
# the scene's peak quantities as scene_peaks' filter names them (a transmission angle is
# refined as its deviation from 90 deg)
_SCENE_KEY = {"min_transmission_angle": "transmission_deviation"}


def peak_metrics_of(names) -> tuple:
    """The metrics among ``names`` that are peaks a scene refines."""
    return tuple(m for m in names if m in PEAK_METRICS)


@dataclass
class RefinedPeaks:
    """A design's peak metrics refined between positions (``values``), the
    largest samples of the scene's own grid (``grid``), and the status of its
    scene (a design that does not assemble over the revolution has none)."""
    status: int
    values: dict = field(default_factory=dict)    # metric -> value (with LOCATIONS)
    grid: dict = field(default_factory=dict)      # metric -> the grid's value


def design_peaks(scene_study, metrics) -> RefinedPeaks:
    """The peak metrics ``metrics`` (of PEAK_METRICS) of the scene study
    ``scene_study`` (``candidate.design_scene``), refined between positions
    as its scene refines them (``solve.scene.run_scene``, ``scene_peaks``)."""
    from ..solve.peaks import scene_peaks
    from ..solve.scene import run_scene
    res = run_scene(scene_study)
    if res.dense.overall != kc.OK:
        return RefinedPeaks(int(res.dense.overall))
    wp = scene_study.output.working_point
    wanted = {}
    for m in metrics:
        quantity, items = PEAK_METRICS[m]
        wanted.setdefault(_SCENE_KEY.get(quantity, quantity), set()).add(items)

    def keep(quantity, item):
        which = wanted.get(quantity)
        return which is not None and (None in which or item == wp)
    peaks = scene_peaks(res, keep)
    out = RefinedPeaks(kc.OK)
    for m in metrics:
        quantity, items = PEAK_METRICS[m]
        of = [p for p in peaks if p.quantity == quantity and (items is None or p.item == wp)]
        if not of:          # not computed for this design (no forces, no friction, ...)
            continue
        if quantity == "min_transmission_angle":
            p = min(of, key=lambda q: q.value)
            value, grid = p.value, min(q.grid_value for q in of)
            if m == "transmission_deviation":
                value, grid = 90.0 - value, 90.0 - grid
        else:
            p = max(of, key=lambda q: q.value)
            value, grid = p.value, max(q.grid_value for q in of)
        out.values[m], out.grid[m] = value, grid
        if m == "peak_reaction":
            out.values["peak_joint"] = float(res.dense.forces.joint_names.index(p.item))
            out.values["peak_phi"] = p.phi1
    return out


def refine_designs(study, params, metrics, progress=None) -> tuple[np.ndarray, np.ndarray]:
    """The refined peak metrics of the designs ``params`` (rows of design
    variables) of the sweep study ``study``: (values (n, len(metrics) + 2),
    the last two columns LOCATIONS; NaN where a design's scene fails), status
    (n,) int8 of each design's scene.  ``progress(k)`` after each design."""
    from ..study.sweep_spec import apply_design
    cols = tuple(metrics) + LOCATIONS
    values = np.full((len(params), len(cols)), math.nan)
    status = np.zeros(len(params), np.int8)
    for k, x in enumerate(params):
        r = design_peaks(design_scene(study, apply_design(study.mechanism, study.sweep, x)),
                         metrics)
        status[k] = r.status
        for j, m in enumerate(cols):
            values[k, j] = r.values.get(m, math.nan)
        if progress is not None:
            progress(k + 1)
    return values, status


def design_scene(study, mech):
    """The sweep study ``study`` with the design's mechanism ``mech`` as a scene
    study, at the sweep's positions per revolution and operating speed (with
    the force analysis where the mechanism has mass data): what
    ``candidate_scene`` gives and ``analysis.refined`` refines the peaks of."""
    output = replace(study.output, dense_positions=int(study.sweep.positions),
                     analysis="forces" if mech.bodies else "accelerations")
    return replace(study, kind="scene", mechanism=mech, output=output, sweep=None, search=None)
