"""The group types of ``[[mechanism.groups]]``: the structural groups, a folder
each in ``pipeline.group_types`` (their study fields and plan rows, kernels
and emitters together), and the mechanism's own elements here (a point
attached to a link, a rotary or slider input moved by a law).  Each holds
everything about it as the hooks of ``group_base.GroupType``; this table, derived
from the folders, is where the study reader, the model, the peaks and the
plots look a type up.

Adding a structural group type: a folder in ``pipeline.group_types``
(``docs/guide/architecture.md`` walks through one); nothing here changes.
"""

from __future__ import annotations

from ... import group_types
from ...base.old_names import group_type_names, old_names
from .attach import Attach
from ..group_base import GroupType
from .law import LAW_TYPES, Law, parse_law
from .rotary_input import RotaryInput
from .slider_input import SliderInput


def _structural():
    """(study types, classes their parsers build) of the group-type folders, in the
    order of their first plan code."""
    declared, built = [], []
    for mod in group_types.part("model"):
        declared += mod.STUDY_TYPES
        built += getattr(mod, "BUILT", ())
    return declared, built


_DECLARED, _BUILT = _structural()

# the study's `type` -> its class, in the order of the study's error message: the
# folders' (by their first plan code), then the mechanism's own elements
GROUP_TYPES: dict[str, type[GroupType]] = {}
for _t in _DECLARED + [Attach, RotaryInput, SliderInput]:
    if _t.TYPE in GROUP_TYPES:
        raise ValueError(f"{_t.__module__}.{_t.__name__}: the study type {_t.TYPE!r} is "
                         f"already {GROUP_TYPES[_t.TYPE].__module__}'s")
    GROUP_TYPES[_t.TYPE] = _t
del _t

# every class a declared group can be (a type's parser may build another)
GROUP_CLASSES = tuple(dict.fromkeys(list(GROUP_TYPES.values()) + _BUILT))

# the study keys that name (list) points some group solves (the parser's "solved later")
SOLVED_KEYS = tuple(dict.fromkeys(k for t in GROUP_CLASSES for k in t.SOLVES))
SOLVED_LISTS = tuple(dict.fromkeys(k for t in GROUP_CLASSES for k in t.SOLVES_LISTS))

__all__ = ["GROUP_TYPES", "GROUP_CLASSES", "SOLVED_KEYS", "SOLVED_LISTS", "GroupType", "Law",
           "LAW_TYPES", "parse_law", "Attach", "RotaryInput", "SliderInput"]

# the group types' classes, once importable from here: in their folders now (one release)
__getattr__ = old_names(__name__, group_type_names)
