"""Self-describing HDF5 files: root attributes name the format and its
version, the software and its version, the date and the study verbatim;
every dataset carries ``units`` and ``long_name``."""

from __future__ import annotations

import datetime as _dt
from pathlib import Path

import h5py
import numpy as np

from . import __version__
from .kernels import config as kc

FORMAT = "pipeline-results"
FORMAT_VERSION = "1.0"


class ResultsError(ValueError):
    """A results file cannot be used: names the file and the reason."""

    def __init__(self, path, reason):
        self.path = str(path)
        super().__init__(f"{path}: {reason}")


def attr_text(v):
    """An HDF5 string attribute as str (h5py may hand back bytes)."""
    return v.decode() if isinstance(v, bytes) else v


def stored_study(attrs, default_path="<stored study>"):
    """The study rebuilt from the TOML stored verbatim in a results file's root
    attributes; None if the file has none."""
    text = attrs.get("study_toml")
    if not text:
        return None
    from .study import parse_study
    return parse_study(attr_text(text), attr_text(attrs.get("study_file", default_path)))


def status_table():
    return "; ".join(f"{k}={v}" for k, v in kc.STATUS_NAMES.items())


def write_root_attrs(f, kind, study, **extra):
    f.attrs["format"] = FORMAT
    f.attrs["format_version"] = FORMAT_VERSION
    f.attrs["kind"] = kind
    f.attrs["software"] = "pipeline"
    f.attrs["software_version"] = __version__
    f.attrs["created"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    f.attrs["study_name"] = study.name
    f.attrs["study_title"] = study.title
    f.attrs["study_file"] = str(study.path)
    f.attrs["study_toml"] = study.text
    for k, v in extra.items():
        f.attrs[k] = v


def put(group, name, data, units, long_name, **attrs):
    """Write one dataset with its units and long name."""
    data = np.asarray(data)
    kw = {}
    if data.ndim >= 1 and data.size > 4096:
        kw = dict(compression="lzf", chunks=True)
    d = group.create_dataset(name, data=data, **kw)
    d.attrs["units"] = units
    d.attrs["long_name"] = long_name
    for k, v in attrs.items():
        d.attrs[k] = v
    return d


def open_results(path, kind=None):
    """Open a results file read-only, checking that it is ours (and of ``kind``)."""
    path = Path(path)
    if not path.exists():
        raise ResultsError(path, "file not found")
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise ResultsError(path, f"not a readable HDF5 file ({e})") from None
    if f.attrs.get("format") != FORMAT:
        f.close()
        raise ResultsError(path, "not a pipeline results file (no format attribute "
                                 f"{FORMAT!r}); was it written by `pipeline run`?")
    if kind is not None and f.attrs.get("kind") != kind:
        got = f.attrs.get("kind")
        f.close()
        raise ResultsError(path, f"is a {got} result, this command needs a {kind} result")
    return f


def _curves(g, res, curves, study):
    plan = res.plan
    crank = study.mechanism.crank
    from .scene import real_motion
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
    path.parent.mkdir(parents=True, exist_ok=True)
    plan = res.plan
    with h5py.File(path, "w") as f:
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
