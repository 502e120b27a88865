"""The analysis layer: what a sweep's results mean.  ``fronts``: Pareto
fronts of the feasible candidates, which design variables drive each
objective, representative trade-off designs (the group /analysis of a results
file); ``ranking``: the designs ranked for a reader; ``candidate``: one stored
design, re-run as a scene.

The names of the flat package's ``pipeline.analysis`` stay importable from
here for one release, with a warning (``from pipeline.analysis import analyze``); inside the
package, import each from the module that defines it.
"""

from ..base.old_names import by_name as _by_name
from ..base.old_names import old_names as _old_names

# the flat package's names, kept for one release: the module that defines them -> names
_OLD_NAMES = _by_name({
    "pipeline.analysis.fronts": "DEFAULT_OBJECTIVES GROUP KMEANS_N_INIT MAX_MODEL_SAMPLES"
                                " MAX_PERMUTATION_ROWS MIN_MODEL_SAMPLES N_BOOST N_REPEATS"
                                " TEST_FRACTION Analysis SweepData analyze compute"
                                " fit_importance has_analysis read_analysis read_sweep"
                                " reference_standing representatives summary sweep_objectives"
                                " variable_units write",
})
__getattr__ = _old_names(__name__, _OLD_NAMES)


