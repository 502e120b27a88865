"""One style for units in everything the package writes: text, files (HDF5
``units`` attributes, CSV headers) and pictures use the Unicode forms N·m,
m/s², rad/s², kg·m², N·m·s (issue 55).

``unit_text`` turns a unit written the ASCII way (a study's comment, a file
written before this style, the catalogue of metrics) into that form; it is
for unit strings only, never free text.  Readers never compare unit strings
(a file written with 'N*m' opens and reads as one written with 'N·m')."""

from __future__ import annotations

# the ASCII spellings the package and its older files used, and what they read as
_UNIT_WORDS = (("kg m^2", "kg·m²"), ("N m s", "N·m·s"), ("N m", "N·m"), ("s$^2$", "s²"),
               ("*", "·"), ("^2", "²"), ("^3", "³"))

# the ASCII forms that must not appear where units are written (tests read this)
ASCII_FORMS = ("N*m", "m/s^2", "rad/s^2", "kg*m^2", "N*m*s", "s^2", "m^2", "*m/s")


def unit_text(unit) -> str:
    """A unit in the package's one style: 'm/s^2' -> 'm/s²', 'N*m' -> 'N·m',
    'kg m^2' -> 'kg·m²', 'MPa*m/s' -> 'MPa·m/s'; anything else unchanged."""
    unit = str(unit)
    for ascii_, shown in _UNIT_WORDS:
        unit = unit.replace(ascii_, shown)
    return unit
