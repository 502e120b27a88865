"""The model layer: a mechanism declared once (frozen dataclasses,
``mechanism``) and compiled once into the arrays the kernels read (``Plan``);
the group types' base (``group_base``), the mechanism's own elements and the
table ``GROUP_TYPES`` derived from the group-type folders (``groups/``); the
required motion law (``motion_law``); the catalogue of a sweep's metrics
(``metrics``).

The names of the flat package's ``pipeline.model`` stay importable from here
for one release, with a warning (``from pipeline.model import Mechanism``); inside the package,
import each from the module that defines it.
"""

from ..base.old_names import by_name as _by_name
from ..base.old_names import group_type_names as _group_type_names
from ..base.old_names import old_names as _old_names

# the flat package's names, kept for one release: the module that defines them -> names
_OLD_NAMES = _by_name({
    "pipeline.model.mechanism": "GIDX_WIDTH Body CentreOfMass Crank Group Load Mechanism Plan"
                                " Slide compile_mechanism group_label natural_key",
    "pipeline.model.groups.attach": "Attach",
    "pipeline.model.group_base": "GroupType",
    "pipeline.model.groups.law": "Law",
    "pipeline.model.groups.rotary_input": "RotaryInput",
    "pipeline.model.groups.slider_input": "SliderInput",
})
# (and the group types' classes, now in their folders of pipeline.group_types)
__getattr__ = _old_names(__name__, lambda: {**_OLD_NAMES, **_group_type_names()})


