"""Numbers as people read them: never ``-0``.

A computed zero may carry a sign (``-0.0``, the product of a zero and a
negative number) and a small negative rounds to ``-0.0`` in a fixed format;
neither means anything to a reader.  Every text the package prints or writes
(the console, CSV tables, summaries) passes through ``unsigned_zero``; tables
of numbers through ``signless_zeros`` before they are formatted."""

from __future__ import annotations

import re

# a minus before a zero that is a whole number token: -0, -0.0, -0.000 (not
# -0.5, -0.01, 1e-05, a name like "lead 2-0" or a range "10-0")
_NEGATIVE_ZERO = re.compile(r"(?<![\w.])-(0(?:\.0*)?)(?![\w.])")


def unsigned_zero(text: str) -> str:
    """``text`` with every ``-0`` (``-0.0``, ``-0.00``, ...) written unsigned."""
    return _NEGATIVE_ZERO.sub(r"\1", text) if "-0" in text else text


def signless_zeros(df):
    """A copy of DataFrame ``df`` whose float columns hold +0.0 where they held
    -0.0 (adding +0.0 does that and changes no other number, NaN included)."""
    out = df.copy()
    for c in out.columns:
        if out[c].dtype.kind == "f":
            out[c] = out[c].to_numpy() + 0.0
    return out
