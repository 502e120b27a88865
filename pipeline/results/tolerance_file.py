"""The results file of a tolerance analysis (kind "tolerance"): self-describing
like a sweep's, every dataset with units and a long name, the dimensions and
the metrics as named coordinates (xarray, h5dump, HDFView, MATLAB).

    /                      attrs: design, source, candidate, samples, seed, iso_class,
                           yield, study_toml, ...
    coordinates (in each group that uses them): dimension (every toleranced
    dimension, by parameter name), drawn (those with a tolerance), metric,
    build (0 .. samples - 1), side (-tolerance, +tolerance)
    /dimensions/{kind, nominal, tolerance, sigma, units, distribution, source}
    /builds/deviation      (build, drawn)  mm or deg
    /builds/status         (build)  enum: OK, NO_ASSEMBLY, ...
    /builds/meets          (build)  1: assembles and meets the constraints
    /builds/<metric>       (build)  the metric of each build
    /nominal/<metric>      the design's own value
    /sensitivity/<metric>  (dimension)  d metric / d dimension, per mm or per deg
    /sensitivity/checked   (metric, dimension)  1: the step check held
    /one_at_a_time/<metric> (dimension, side)  the metric at -tolerance, +tolerance
    /summary/{nominal, mean, std, std_linear, p05, p50, p95}  (metric)
    /constraints/{metric, min, max}
"""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np

from ..base.files import replacing, safe_name
from ..kernels import config as kc
from ..model.metric_catalogue import BY_NAME
from .storage import (STATUS_ENUM, attr_text, coordinate, hdf5_image, open_results, put,
                      read_units, write_root_attrs)

QUANTILES = (("p05", 0.05), ("p50", 0.50), ("p95", 0.95))


def tolerance_output(source, origin):
    """Where ``pipeline tolerance`` writes a design's file by default:
    results/<study>_tolerance.h5 for a study file; next to a results file
    <name>[_candidate<ID>]_tolerance.h5 (``origin``: its ``candidate``, if any)."""
    source = Path(source)
    tag = f"_candidate{safe_name(origin['candidate'])}" if "candidate" in origin else ""
    if source.suffix.lower() == ".toml":
        return Path("results") / f"{safe_name(source.stem, 'study')}_tolerance.h5"
    return source.with_name(f"{source.stem}{tag}_tolerance.h5")


def write_tolerance(a, study, path, **attrs):
    """Write tolerance analysis ``a`` (``pipeline.runs.tolerance.ToleranceAnalysis``)
    of a design of ``study``; ``attrs``: where the design comes from (source,
    candidate).  Returns the path."""
    path = Path(path)
    dims, drawn = a.dimensions, a.drawn
    units = a.units
    with replacing(path) as tmp, hdf5_image(tmp) as f:
        write_root_attrs(f, "tolerance", study, design=a.label, samples=len(a.status),
                         seed=a.spec.seed, iso_class=a.spec.iso_class,
                         nominal_status=kc.STATUS_NAMES[a.nominal_status],
                         wall_time_s=a.wall_s, complete=True, **{"yield": a.yield_}, **attrs)
        # each group holds the coordinates of its datasets (netCDF readers such as
        # xarray name a group's dimensions from the scales in that group)
        g = f.create_group("dimensions")
        _dimension(g, dims)
        du = [d.units for d in dims]
        put(g, "kind", _text([d.kind for d in dims]), "1", "length | coordinate | angle",
            dims=("dimension",))
        put(g, "nominal", [d.nominal for d in dims], du, "the design's value",
            dims=("dimension",))
        put(g, "tolerance", [d.tolerance for d in dims], du, "+- tolerance (0: exact)",
            dims=("dimension",))
        put(g, "sigma", [d.sigma for d in dims], du, "standard deviation of the deviation",
            dims=("dimension",))
        put(g, "distribution", _text([d.distribution for d in dims]), "1",
            "normal (the tolerance is 3 sigma) | uniform (within +- the tolerance)",
            dims=("dimension",))
        put(g, "source", _text([d.source for d in dims]), "1", "where the tolerance comes from",
            dims=("dimension",))
        b = f.create_group("builds")
        coordinate(b, "build", np.arange(len(a.status)), "1", "build (scrambled Sobol draw)")
        coordinate(b, "drawn", _text(d.param for d in drawn), "1", "dimension with a "
                   "tolerance (drawn for every build)")
        coordinate(b, "metric", _text(a.metrics), "1", "metric of a build")
        put(b, "deviation", a.deltas, [d.units for d in drawn], "deviation of each drawn "
            "dimension from the design", dims=("build", "drawn"))
        s = b.create_dataset("status", data=a.status.astype(np.int8), dtype=STATUS_ENUM)
        s.attrs["long_name"] = "status of the build over the revolution"
        s.attrs["units"] = "1"
        s.dims[0].attach_scale(b["build"])
        put(b, "meets", a.meets.astype(np.int8), "1", "1: the build assembles and meets the "
            "constraints", dims=("build",))
        n = f.create_group("nominal")
        sens = f.create_group("sensitivity")
        _dimension(sens, dims)
        coordinate(sens, "metric", _text(a.metrics), "1", "metric of a build")
        oat = f.create_group("one_at_a_time")
        _dimension(oat, dims)
        coordinate(oat, "side", _text(["-tolerance", "+tolerance"]), "1", "side of the "
                   "tolerance")
        for k, m in enumerate(a.metrics):
            meta = BY_NAME[m]
            put(b, m, a.values[:, k], meta.units, meta.long_name, dims=("build",))
            put(n, m, np.float64(a.nominal[k]), meta.units, meta.long_name)
            put(sens, m, a.sensitivity[k], [f"{meta.units}/{u}" for u in du],
                f"d {m} / d dimension at the design (central differences, Richardson)",
                dims=("dimension",))
            put(oat, m, a.one_at_a_time[k], meta.units,
                f"{m} with one dimension at -tolerance and at +tolerance, the others at the "
                "design", dims=("dimension", "side"))
        put(sens, "checked", a.checked.astype(np.int8), "1", "1: the two steps of the central "
            "difference agree (the metric is smooth there)", dims=("metric", "dimension"))
        sm = f.create_group("summary")
        coordinate(sm, "metric", _text(a.metrics), "1", "metric of a build")
        put(sm, "nominal", a.nominal, units, "the design's value", dims=("metric",))
        ok = (a.status == kc.OK)
        put(sm, "mean", [_stat(np.mean, a.values[ok, k]) for k in range(len(a.metrics))],
            units, "mean over the builds that assemble", dims=("metric",))
        put(sm, "std", a.sigma_sampled(), units, "standard deviation over the builds that "
            "assemble", dims=("metric",))
        put(sm, "std_linear", a.sigma_linear(), units, "linear prediction: sqrt(sum "
            "(d metric/d x_i sigma_i)^2)", dims=("metric",))
        for key, q in QUANTILES:
            put(sm, key, a.quantiles(q), units, f"{round(100 * q)}th percentile over the "
                "builds that assemble", dims=("metric",))
        c = f.create_group("constraints")
        c.attrs["long_name"] = "what a build must meet to count towards the yield"
        put(c, "metric", _text([m for m, _, _ in a.constraints] or [""]), "1", "bounded metric")
        put(c, "min", [lo for _, lo, _ in a.constraints] or [np.nan], "1", "lower bound "
            "(the metric's units)")
        put(c, "max", [hi for _, _, hi in a.constraints] or [np.nan], "1", "upper bound "
            "(the metric's units)")
    return path


def _dimension(group, dims):
    coordinate(group, "dimension", _text(d.param for d in dims), "1",
               "toleranced dimension (mechanism parameter)")


def _text(values):
    return np.array(list(values), dtype=h5py.string_dtype())


def _stat(fn, v):
    v = v[np.isfinite(v)]
    return float(fn(v)) if len(v) else np.nan


def read_tolerance(path):
    """The summary of a tolerance results file as a dict (for the report, show
    and tests): besides the summary, each dimension's sigma, the candidate it
    is of ('' for a scene's), every build's metrics (``values``, (build, metric))
    and the constraints as (metric, min, max)."""
    with open_results(path, "tolerance") as f:
        metrics = [attr_text(x) for x in f["summary/metric"][()]]
        out = {"design": attr_text(f.attrs["design"]), "yield": float(f.attrs["yield"]),
               "samples": int(f.attrs["samples"]), "metrics": metrics,
               "candidate": attr_text(f.attrs.get("candidate", "")),
               "dimensions": [attr_text(x) for x in f["dimensions/dimension"][()]],
               "sigma": f["dimensions/sigma"][()],
               "units": read_units(f["summary/nominal"], len(metrics))}
        for key in ("nominal", "mean", "std", "std_linear", "p05", "p50", "p95"):
            out[key] = f[f"summary/{key}"][()]
        out["sensitivity"] = np.stack([f[f"sensitivity/{m}"][()] for m in metrics])
        out["status"] = f["builds/status"][()]
        out["values"] = np.stack([f[f"builds/{m}"][()] for m in metrics], axis=1)
        c = f["constraints"]
        out["constraints"] = tuple((attr_text(m), float(lo), float(hi)) for m, lo, hi in zip(
            c["metric"][()], c["min"][()], c["max"][()]) if attr_text(m))
    return out
