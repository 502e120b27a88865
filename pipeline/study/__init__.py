"""The study layer: study files (TOML) read into frozen specs, checked, with
errors that name the file, the field and the reason.  ``reader``: the file and
its scene sections; ``section``: the reader of one table; ``slide_check``;
``sweep_spec`` and ``search_spec``: the [sweep] and [search] sections;
``sampling``: drawing a sweep's candidates; ``objectives``: objectives and
constraints from the kernels' metric rows.

The names of the flat package's ``pipeline.study`` stay importable from here
for one release (``from pipeline.study import load_study``); inside the
package, import them from ``pipeline.study.reader``.
"""

from ..base.errors import StudyError  # noqa: F401
from .reader import (ANALYSES, GROUP_TYPES, KINDS, DynamicsCase, DynamicsSpec,  # noqa: F401
                     Fields, OutputSpec, Section, Study, load_study, name_problem,
                     parse_dynamics, parse_link, parse_mechanism, parse_output, parse_study,
                     stored_study)
