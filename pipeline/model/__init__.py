"""The model layer: a mechanism declared once (frozen dataclasses,
``mechanism``) and compiled once into the arrays the kernels read (``Plan``);
one module per group type (``groups/``, with its table ``GROUP_TYPES``); the
required motion law (``motion_law``); the catalogue of a sweep's metrics
(``metrics``).

The names of the flat package's ``pipeline.model`` stay importable from here
for one release, with a warning (``from pipeline.model import Mechanism``); inside the package,
import each from the module that defines it.
"""

import importlib as _importlib
import warnings as _warnings

# the flat package's names, kept for one release: the module that defines them -> names
_OLD_NAMES = {name: module for module, names in {
    "pipeline.model.mechanism": "GIDX_WIDTH Body CentreOfMass Crank Group Load Mechanism Plan"
                                " Slide compile_mechanism group_label natural_key",
    "pipeline.model.groups.ppr": "PPR",
    "pipeline.model.groups.prp": "PRP",
    "pipeline.model.groups.rpp": "RPP",
    "pipeline.model.groups.rpr": "RPR",
    "pipeline.model.groups.rrp": "RRP",
    "pipeline.model.groups.rrr": "RRR",
    "pipeline.model.groups.attach": "Attach",
    "pipeline.model.groups.class3": "ClassIII",
    "pipeline.model.groups.class3_slider": "ClassIIISlider",
    "pipeline.model.groups.base": "GroupType",
    "pipeline.model.groups.law": "Law",
    "pipeline.model.groups.rotary_input": "RotaryInput",
    "pipeline.model.groups.slider_input": "SliderInput",
}.items() for name in names.split()}


def __getattr__(name):
    """A name of the flat package's ``pipeline.model``: it warns (``DeprecationWarning``,
    naming the module that defines it) and gives the very object."""
    if name not in _OLD_NAMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    _warnings.warn(f"{__name__}.{name} is an old import path, kept for one release: import "
                   f"{name} from {_OLD_NAMES[name]} (the next release removes the old "
                   "path; docs/guide/architecture.md)", DeprecationWarning, stacklevel=2)
    return getattr(_importlib.import_module(_OLD_NAMES[name]), name)
