"""The users' tables from a results file (`pipeline export OUT.h5 --csv DIR`).

A scene gives points.csv, links.csv (and reactions.csv, friction.csv, peaks.csv,
motion_<case>.csv) at every computed position (``every``: every N-th); a sweep
gives candidates.csv (all candidates), candidates_feasible.csv (the feasible
ones) or candidates_front1.csv, candidates_fronts1-N.csv (the first Pareto
fronts): each file names what it holds, so two selections never overwrite
each other.  CSV headers carry their units (``V8_x [m/s]``); Parquet keeps plain
column names with the units in the file's metadata.  Every file is written
atomically.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..base.files import check_output, check_output_folder, replacing, write_text
from ..base.numbers import signless_zeros
from ..results.storage import attr_text, open_results
from .tables import candidates, scene_tables, with_units


def export(path, outdir, *, every=1, feasible=False, front=None, parquet=False) -> list[Path]:
    """Write the tables of the results file ``path`` into ``outdir``; returns
    the files written."""
    outdir = check_output_folder(outdir)
    with open_results(path) as f:
        kind = attr_text(f.attrs["kind"])
    if kind == "scene":
        if feasible or front is not None:
            raise ValueError("--feasible and --front select sweep candidates; this is a scene")
        frames = scene_tables(path, every)
    else:
        if every != 1:
            raise ValueError("--every thins the positions of a scene; this is a sweep")
        frames = {candidates_name(feasible, front): candidates(path, feasible=feasible,
                                                               front=front)}
    outdir = Path(outdir)
    names = [outdir / f"{name}.csv" for name in frames]
    names = [p.with_suffix(".parquet") for p in names] if parquet else names
    names = [check_output(p, inputs=(path,)) for p in names]   # all before the first write
    outdir.mkdir(parents=True, exist_ok=True)
    return [_write(df, p, parquet) for df, p in zip(frames.values(), names)]


def candidates_name(feasible=False, front=None) -> str:
    """The name of a sweep's candidates table for a selection."""
    if front is not None:
        return "candidates_front1" if front == 1 else f"candidates_fronts1-{front}"
    return "candidates_feasible" if feasible else "candidates"


def _write(df, path, parquet):
    if parquet:
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise ValueError("--parquet needs pyarrow: pip install pyarrow") from None
        with replacing(path) as tmp:
            df.to_parquet(tmp, index=False)
        return path
    with replacing(path) as tmp:
        with_units(signless_zeros(df)).to_csv(tmp, index=False, float_format="%.12g")
    return path


# ----------------------------------------------------------------- one design out
def _design_of(results, candidate):
    """The results file's kind: a scene's design needs no --candidate, a
    sweep's (or a search's) needs one."""
    with open_results(results) as f:
        kind = attr_text(f.attrs["kind"])
    if kind == "scene" and candidate is not None:
        raise ValueError(f"{results} is a scene result: it has one design, no --candidate")
    if kind != "scene" and candidate is None:
        raise ValueError(f"{results} is a {kind}: say which design with --candidate ID (a "
                         "number, 'knee' or 'reference')")
    return kind


def export_drawing(results, outdir, *, candidate=None, phis=None, paths=False,
                   svg=False) -> list[Path]:
    """`pipeline export RESULTS [--candidate ID] --dxf DIR`: the design as a
    DXF drawing (and SVG) in ``outdir`` (``views.drawing_dxf``); a sweep's
    design is re-run as a scene first (``candidate_scene``, as `pipeline show
    --candidate` and `pipeline compare` do).  Returns the files written."""
    from .drawing_dxf import geometry_of, read_geometry, write_drawing
    check_output_folder(outdir)         # before the design is solved
    if _design_of(results, candidate) == "scene":
        return write_drawing(read_geometry(results), outdir, phis=phis, paths=paths, svg=svg,
                             inputs=(results,))
    from ..analysis.candidate import candidate_scene
    from ..results.scene_file import scene_in_memory
    from ..solve.scene_study import solve_scene
    study, label, number = candidate_scene(results, candidate)
    tag = "reference" if number == "reference" else f"candidate{number}"
    with scene_in_memory(solve_scene(study)) as f:
        geo = geometry_of(f, f"{results} ({label})")
    return write_drawing(geo, outdir, phis=phis, paths=paths, svg=svg, inputs=(results,),
                         stem=f"{study.name or Path(results).stem}_{tag}",
                         origin_lines=[f"From: {results}, {label}"])


def export_study(results, candidate, out) -> Path:
    """`pipeline export RESULTS --candidate ID --study OUT.toml`: the sweep's
    design as a scene study of its own (``study.writer``)."""
    from ..analysis.candidate import load_study_from_results, resolve_candidate
    from ..results.storage import candidate_ids
    from ..study.writer import design_study_text
    if _design_of(results, candidate) == "scene":
        raise ValueError(f"{results} is a scene result: its study is stored in it already; "
                         "--study writes a sweep's design (--candidate ID) as a scene study")
    out = check_output(out, inputs=(results,))
    with open_results(results) as f:
        i = resolve_candidate(f, candidate)
        study = load_study_from_results(f)
        x = f["reference/params"][()] if i == "reference" else f["candidates/params"][i]
        number = "reference" if i == "reference" else int(candidate_ids(f)[i])
    if not np.isfinite(x).all():
        raise ValueError(f"{results}: candidate {number} was never evaluated (unfinished sweep)")
    label = "the reference design" if number == "reference" else f"candidate #{number}"
    tag = "reference" if number == "reference" else f"candidate{number}"
    text = design_study_text(study, x, label=label, origin=f"{label} of {results}",
                             name=f"{study.name or 'design'}_{tag}")
    return write_text(out, text)


def export_design(results, *, dxf=None, study=None, candidate=None, phis=None, paths=False,
                  svg=False) -> list[Path]:
    """`pipeline export RESULTS [--candidate ID] --dxf DIR | --study OUT.toml`."""
    if study is not None:
        if phis or paths or svg:
            raise ValueError("--phi, --paths and --svg go with --dxf, not --study")
        return [export_study(results, candidate, study)]
    return export_drawing(results, dxf, candidate=candidate, phis=phis, paths=paths, svg=svg)
