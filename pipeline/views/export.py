"""The users' tables from a results file (`pipeline export OUT.h5 --csv DIR`).

A scene gives points.csv, links.csv (and reactions.csv, peaks.csv,
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

from ..base.files import check_output, check_output_folder, replacing
from ..base.numbers import signless_zeros
from ..results.storage import attr_text, open_results
from .tables import candidates, scene_tables, with_units


def export(path, outdir, *, every=1, feasible=False, front=None, parquet=False) -> list[Path]:
    """Write the tables of the results file ``path`` into ``outdir``; returns
    the files written."""
    check_output_folder(outdir)
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
    for p in names:         # all checked before the first is written
        check_output(p, inputs=(path,))
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
