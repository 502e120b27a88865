"""The study layer: study files (TOML) read into frozen specs, checked, with
errors that name the file, the field and the reason.  ``reader``: the file and
its scene sections; ``section``: the reader of one table; ``slide_check``;
``sweep_spec`` and ``search_spec``: the [sweep] and [search] sections;
``sampling``: drawing a sweep's candidates; ``objectives``: objectives and
constraints from the kernels' metric rows.

The names of the flat package's ``pipeline.study`` stay importable from here
for one release, with a warning (``from pipeline.study import load_study``); inside the
package, import each from the module that defines it.
"""

import importlib as _importlib
import warnings as _warnings

# the flat package's names, kept for one release: the module that defines them -> names
_OLD_NAMES = {name: module for module, names in {
    "pipeline.base.errors": "StudyError",
    "pipeline.study.reader": "ANALYSES GROUP_TYPES KINDS Fields OutputSpec Study load_study"
                             " parse_link parse_mechanism parse_output parse_study stored_study",
    "pipeline.study.dynamics_spec": "DynamicsCase DynamicsSpec parse_dynamics",
    "pipeline.study.section": "Section name_problem",
}.items() for name in names.split()}


def __getattr__(name):
    """A name of the flat package's ``pipeline.study``: it warns (``DeprecationWarning``,
    naming the module that defines it) and gives the very object."""
    if name not in _OLD_NAMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    _warnings.warn(f"{__name__}.{name} is an old import path, kept for one release: import "
                   f"{name} from {_OLD_NAMES[name]} (the next release removes the old "
                   "path; docs/guide/architecture.md)", DeprecationWarning, stacklevel=2)
    return getattr(_importlib.import_module(_OLD_NAMES[name]), name)
