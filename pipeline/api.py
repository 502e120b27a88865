"""The Python API (re-exported by ``pipeline``): load a study, run it, open a
results file as tables.

    import pipeline
    study = pipeline.load_study("studies/ov7_synthesis.toml")
    res = pipeline.run(study, "results/s.h5", candidates=20000)
    df = pipeline.open(res.results)          # one row per candidate
    df[df.feasible].sort_values("peak_reaction").head()

Arrays and tables are in the units of the results file (mm, deg, N, m/s, ...);
``df.attrs["units"]`` names them per column.
"""

from __future__ import annotations

from .study.reader import Study, load_study as _load_study
from .views.tables import candidates, scene_tables, with_units

__all__ = ["load_study", "run", "solve_scene", "open", "tolerance", "compare", "candidates",
           "scene_tables", "with_units"]


def load_study(path) -> Study:
    """Read and check a study file (errors name the file, the field and the reason)."""
    return _load_study(path)


def run(study, output=None, *, candidates=None, resume=False, overwrite=False, n_jobs=None,
        scheduler=None, progress=False, pictures=True, seed_from=None):
    """Run a study (a path or a loaded ``Study``): a scene (with its dynamics
    cases), a sweep, or a sweep study's [search] (``seed_from``: a results file
    whose front starts it).  Returns the outcome: ``.results`` (the HDF5 file),
    ``.pictures``, ``.summary``."""
    from .runner import run_study
    return run_study(study, output, candidates=candidates, resume=resume, overwrite=overwrite,
                     scheduler=scheduler, n_jobs=n_jobs, progress=progress, pictures=pictures,
                     seed_from=seed_from)


def solve_scene(study):
    """Solve a scene study in memory, writing nothing: its table and dense
    curves (positions, analogs, forces), refined peaks, dwell and stroke, and
    its dynamics cases with the reduced dynamics.  Draw it with
    ``pipeline.views.plots.scene_figure(result)``, ``forces_figure``, and
    ``pipeline.views.dynamics_plots.dynamics_figure(case)``."""
    from .solve.scene_study import solve_scene as solve
    if not isinstance(study, Study):
        study = _load_study(study)
    if study.kind != "scene":
        raise ValueError(f"{study.path}: pipeline.solve_scene solves a scene; this study is a "
                         f"{study.kind} (use pipeline.run)")
    from .solve.scene import check_centres_of_mass
    check_centres_of_mass(study)
    return solve(study)


def tolerance(source, candidate=None, *, samples=None, metrics=None):
    """How a design holds up when it is made, in memory (writes nothing): the
    design of a scene's results file or study file, or a sweep's candidate
    (a number, 'knee' or 'reference'), built ``samples`` times within its
    study's [tolerance] (ISO 2768-f without one).  Returns the analysis
    (``pipeline.runs.tolerance.ToleranceAnalysis``): ``.table()`` (a
    DataFrame per metric: design value, mean, std, linear std, percentiles),
    ``.yield_``, ``.values`` and ``.status`` per build, ``.sensitivity``;
    draw it with ``pipeline.views.tolerance_plots``.  ``pipeline tolerance``
    writes the same to a results file with its pictures."""
    from .runner import tolerance_setup
    from .runs.tolerance import analyse
    study, mech, label, sweep, _, spec = tolerance_setup(source, candidate, samples=samples,
                                                         metrics=metrics)
    return analyse(study, mech, spec, label=label, sweep_spec=sweep, samples=samples)


def compare(*results, candidate=None):
    """Designs side by side, in memory (writes nothing): scene results files
    (the first is the base), or with ``candidate`` (a number or 'knee') one
    sweep's design against the sweep's reference design, both re-run as
    scenes.  Returns ``pipeline.analysis.compare.Comparison``: ``.table()`` (a
    DataFrame: every quantity with its unit, each design's value, crank angle
    and item, the change against the first), ``.rows``, ``.notes`` (what is
    not compared, and why); draw it with
    ``pipeline.views.compare.comparison_figure``.  ``pipeline compare`` prints
    the same table and writes the picture."""
    from .runner import comparison
    return comparison(results, candidate)


def open(path):  # noqa: A001 - pipeline.open, as the users asked for it
    """A results file as tables: a sweep's candidates as one DataFrame
    (``candidates``), a scene's tables as {name: DataFrame} (``scene_tables``)."""
    from .results.storage import attr_text, open_results
    from .base.errors import ResultsError
    with open_results(path) as f:
        kind = attr_text(f.attrs["kind"])
    try:
        return candidates(path) if kind == "sweep" else scene_tables(path)
    except (OSError, RuntimeError, KeyError, IndexError) as e:
        # bytes damaged past the header: HDF5 fails inside a read
        raise ResultsError(path, "damaged or incomplete results file ("
                           + " ".join(str(e).split()) + ")") from None
