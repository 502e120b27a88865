"""The analysis layer: what a sweep's results mean.  ``fronts``: Pareto
fronts of the feasible candidates, which design variables drive each
objective, representative trade-off designs (the group /analysis of a results
file); ``ranking``: the designs ranked for a reader; ``candidate``: one stored
design, re-run as a scene.

The names of the flat package's ``pipeline.analysis`` stay importable from
here for one release (``from pipeline.analysis import analyze``); inside the
package, import them from ``pipeline.analysis.fronts``.
"""

from .fronts import (DEFAULT_OBJECTIVES, GROUP, KMEANS_N_INIT, MAX_MODEL_SAMPLES,  # noqa: F401
                     MAX_PERMUTATION_ROWS, MIN_MODEL_SAMPLES, N_BOOST, N_REPEATS, TEST_FRACTION,
                     Analysis, SweepData, analyze, compute, fit_importance, has_analysis,
                     read_analysis, read_sweep, reference_standing, representatives, summary,
                     sweep_objectives, variable_units, write)
