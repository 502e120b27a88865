"""A scene's results file: its layout in HDF5 (the mechanism, the table and
dense curves, the forces and the dynamics cases), written through the plain
array-and-attribute layer of ``pipeline.storage``."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np

from .kernels import config as kc
from .files import replacing
from .scene import real_motion
from .storage import put, status_table, write_root_attrs


def _curves(g, res, curves, study):
    plan = res.plan
    crank = study.mechanism.crank
    v, a, om, ep = real_motion(curves, crank.omega1, crank.eps1)
    nv = plan.n_visible
    put(g, "phi1", np.rad2deg(curves.phi), "deg", "crank angle phi1")
    put(g, "status", curves.status, "1", "position status", codes=status_table())
    put(g, "position", curves.pos[:, :nv], "mm", "point position")
    put(g, "position_analog", curves.d1[:, :nv], "mm/rad", "velocity analog dr/dphi1")
    put(g, "acceleration_analog", curves.d2[:, :nv], "mm/rad^2",
        "acceleration analog d2r/dphi1^2")
    put(g, "velocity", v[:, :nv], "m/s", "point velocity")
    put(g, "acceleration", a[:, :nv], "m/s^2", "point acceleration")
    put(g, "link_angle", np.rad2deg(curves.links[:, :, 0]), "deg", "link angle")
    put(g, "link_omega", om, "1/s", "link angular velocity")
    put(g, "link_eps", ep, "1/s^2", "link angular acceleration")
    put(g, "margin", curves.margin, "1", "distance from a toggle position per group")
    put(g, "newton_iterations", curves.iterations, "1", "Newton iterations (class III groups)")
    if curves.forces is not None:
        curves.forces.write(g)


def write_scene(res, path):
    """Write a scene result; returns the path."""
    study = res.study
    path = Path(path)
    plan = res.plan
    with replacing(path) as tmp, h5py.File(tmp, "w") as f:
        write_root_attrs(f, "scene", study, status=kc.STATUS_NAMES[res.status])
        m = f.create_group("mechanism")
        m.attrs["point_names"] = list(plan.point_names[:plan.n_visible])
        m.attrs["link_labels"] = list(study.output.link_labels)
        m.attrs["working_point"] = study.output.working_point
        m.attrs["omega1"] = study.mechanism.crank.omega1
        m.attrs["eps1"] = study.mechanism.crank.eps1
        put(m, "parameters", plan.par, "mixed", "compiled parameter vector",
            names=list(plan.par_names))
        put(m, "tolerances", res.tolerances, "mixed", "solver tolerances")
        for name, curves in (("table", res.table), ("dense", res.dense)):
            _curves(f.create_group(name), res, curves, study)
        if res.dynamics:
            for case in res.dynamics:
                case.write(f.require_group("dynamics"))
    return path
