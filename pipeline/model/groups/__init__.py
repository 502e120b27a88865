"""The group types of ``[[mechanism.groups]]``: one module per type, each
holding everything about it (its study fields and their errors, its plan row
and emitter, its transmission angles, how it is drawn, its sliding pairs: the
hooks of ``base.GroupType``), and this table, the one place a type is
registered.  The study reader, the model, the peaks and the plots look a type
up here and call its hooks.

Adding a type: a module with its ``GroupType`` subclass, one line in
``GROUP_TYPES``, a README row and its tests.
"""

from __future__ import annotations

from .attach import Attach
from .base import GroupType
from .class3 import ClassIII
from .class3_slider import ClassIIISlider
from .law import LAW_TYPES, Law, parse_law
from .ppr import PPR
from .prp import PRP
from .rotary_input import RotaryInput
from .rpp import RPP
from .rpr import RPR
from .rrp import RRP
from .rrr import RRR
from .slider_input import SliderInput

# the study's `type` -> its class (the order is that of the study's error message)
GROUP_TYPES: dict[str, type[GroupType]] = {
    "RRR": RRR,
    "RRP": RRP,
    "RPR": RPR,
    "PRP": PRP,
    "RPP": RPP,
    "class3": ClassIII,             # with a `slider` table: ClassIIISlider
    "attach": Attach,
    "rotary_input": RotaryInput,
    "slider_input": SliderInput,
    "PPR": PPR,
}

# every class a declared group can be (a type's parser may build another: class3)
GROUP_CLASSES = tuple(dict.fromkeys(list(GROUP_TYPES.values()) + [ClassIIISlider]))

# the study keys that name (list) points some group solves (the parser's "solved later")
SOLVED_KEYS = tuple(dict.fromkeys(k for t in GROUP_CLASSES for k in t.SOLVES))
SOLVED_LISTS = tuple(dict.fromkeys(k for t in GROUP_CLASSES for k in t.SOLVES_LISTS))

__all__ = ["GROUP_TYPES", "GROUP_CLASSES", "SOLVED_KEYS", "SOLVED_LISTS", "GroupType", "Law", "LAW_TYPES",
           "parse_law", "Attach", "ClassIII", "ClassIIISlider", "PPR", "PRP", "RotaryInput",
           "RPP", "RPR", "RRP", "RRR", "SliderInput"]
