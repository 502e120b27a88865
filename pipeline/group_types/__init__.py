"""The structural group types, one folder each, and the registry that finds them.

A folder here holds everything about its type, by layer (each module imports
only from its own layer and below, as the package's layers do):

* ``__init__.py`` (base): a line on the type, its plan codes,
  ``G_<NAME> = code``, and ``CODES``, each code's name (and ``CONTINUED``:
  its codes solved by continuation);
* ``model.py`` (model): its ``GroupType`` classes, the study fields and their
  errors, the plan row, the transmission angles, the drawing, the sliding
  pairs; ``STUDY_TYPES`` (and ``BUILT``: classes its parsers build instead);
* ``kernels.py`` (kernels): its library kernels, positions, analogs and
  failure checks, compiled once per installation; ``__all__``, the names the
  generated module calls;
* ``emitter.py`` (compiler): its emitters (``EMITTERS``), each writing its
  lines of the generated module: careful path, lane form, force-lane lines,
  and ``warmup``, its instances in the library's warm-up mechanism.

Nothing else in ``pipeline/`` names a type: the tables (codes and their names,
the study types, the emitters, the force lanes' kinds, the warm-up, the
generated module's imports) are derived from the folders here, and a new type
is a new folder.  The crank, a point attached to a link and the inputs are the
mechanism's own elements, not group types (``pipeline.model.groups``).
"""

from __future__ import annotations

import importlib
import importlib.util
import pkgutil
from functools import cache

# the plan codes of the mechanism's own elements (``pipeline.model``): the crank every
# mechanism starts with, a point attached to a link, an input moved by a law; a folder
# takes another
G_CRANK = 0
G_ATTACH = 5
G_INPUT = 8
CORE_CODES = {G_CRANK: "crank", G_ATTACH: "attach", G_INPUT: "input"}


@cache
def _inits() -> dict:
    """{folder: its ``__init__`` module}, in the order of their first plan code; a
    code taken twice (by two folders, or a folder and the mechanism's own
    elements) is an error naming both."""
    names = sorted(m.name for m in pkgutil.iter_modules(__path__) if m.ispkg)
    mods = {n: importlib.import_module(f"{__name__}.{n}") for n in names}
    taken = {code: f"the mechanism's own {name}" for code, name in CORE_CODES.items()}
    for n in names:
        for code in mods[n].CODES:
            if code in taken:
                raise ValueError(f"group type folder {n!r}: plan code {code} is already "
                                 f"{taken[code]}'s")
            taken[code] = f"folder {n!r}"
    return {n: mods[n] for n in sorted(names, key=lambda n: min(mods[n].CODES))}


def folders() -> tuple[str, ...]:
    """The group-type folders, in the order of their first plan code."""
    return tuple(_inits())


@cache
def part(module: str) -> tuple:
    """Each folder's module ``module`` ('model', 'kernels', 'emitter'), where the
    folder has one, in the order of ``folders``.  A layer asks for its own."""
    out = []
    for f in folders():
        name = f"{__name__}.{f}.{module}"
        if importlib.util.find_spec(name) is not None:
            out.append(importlib.import_module(name))
    return tuple(out)


@cache
def code_names() -> dict[int, str]:
    """Every plan code -> its name: the mechanism's own elements' and each folder's."""
    out = dict(CORE_CODES)
    for init in _inits().values():
        out.update(init.CODES)
    return dict(sorted(out.items()))


def folder_codes(module) -> tuple[int, ...]:
    """The plan codes of the folder a module of it (``module.__name__``) is in."""
    return tuple(_inits()[module.__name__.split(".")[2]].CODES)


@cache
def continued_codes() -> tuple[int, ...]:
    """The plan codes of the groups solved by continuation (a row of the
    continuation state, the singularity margin |det J| the sweep bounds): each
    folder's ``CONTINUED``."""
    return tuple(c for init in _inits().values() for c in getattr(init, "CONTINUED", ()))
