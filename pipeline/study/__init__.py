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

from ..base.old_names import by_name as _by_name
from ..base.old_names import old_names as _old_names

# the flat package's names, kept for one release: the module that defines them -> names
_OLD_NAMES = _by_name({
    "pipeline.base.errors": "StudyError",
    "pipeline.study.reader": "ANALYSES GROUP_TYPES KINDS Fields OutputSpec Study load_study"
                             " parse_link parse_mechanism parse_output parse_study stored_study",
    "pipeline.study.dynamics_spec": "DynamicsCase DynamicsSpec parse_dynamics",
    "pipeline.study.section": "Section name_problem",
})
__getattr__ = _old_names(__name__, _OLD_NAMES)


