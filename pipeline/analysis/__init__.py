"""The analysis layer: what a sweep's results mean.  ``fronts``: Pareto
fronts of the feasible candidates, which design variables drive each
objective, representative trade-off designs (the group /analysis of a results
file); ``ranking``: the designs ranked for a reader; ``candidate``: one stored
design, re-run as a scene.

The names of the flat package's ``pipeline.analysis`` stay importable from
here for one release, with a warning (``from pipeline.analysis import analyze``); inside the
package, import each from the module that defines it.
"""

import importlib as _importlib
import warnings as _warnings

# the flat package's names, kept for one release: the module that defines them -> names
_OLD_NAMES = {name: module for module, names in {
    "pipeline.analysis.fronts": "DEFAULT_OBJECTIVES GROUP KMEANS_N_INIT MAX_MODEL_SAMPLES"
                                " MAX_PERMUTATION_ROWS MIN_MODEL_SAMPLES N_BOOST N_REPEATS"
                                " TEST_FRACTION Analysis SweepData analyze compute"
                                " fit_importance has_analysis read_analysis read_sweep"
                                " reference_standing representatives summary sweep_objectives"
                                " variable_units write",
}.items() for name in names.split()}


def __getattr__(name):
    """A name of the flat package's ``pipeline.analysis``: it warns (``DeprecationWarning``,
    naming the module that defines it) and gives the very object."""
    if name not in _OLD_NAMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    _warnings.warn(f"{__name__}.{name} is an old import path, kept for one release: import "
                   f"{name} from {_OLD_NAMES[name]} (the next release removes the old "
                   "path; docs/guide/architecture.md)", DeprecationWarning, stacklevel=2)
    return getattr(_importlib.import_module(_OLD_NAMES[name]), name)
