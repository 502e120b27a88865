"""The study file's tables as the study reader sees them: ``Section`` tracks
a table's location and the keys used (unknown keys are reported), and reads
its fields with errors that name the file, the field and the reason; names
are checked data (``name_problem``)."""

from __future__ import annotations

import math
import unicodedata

from ..base.errors import StudyError
from ..base.limits import MAX_NAME_LENGTH, NAME_WHY


_MISSING = object()


class Section:
    """A table of the study being read: tracks its location and the keys used,
    so that unknown keys are reported."""

    def __init__(self, file, where, data):
        self.file = file
        self.where = where
        if not isinstance(data, dict):
            raise StudyError(file, where, f"expected a table, got {type(data).__name__}")
        self.data = data
        self.used = set()

    def path(self, key):
        key = _key(key)
        return f"{self.where}.{key}" if self.where else key

    def error(self, key, reason):
        return StudyError(self.file, self.path(key) if key else self.where, reason)

    def has(self, key):
        return key in self.data

    def raw(self, key, default=_MISSING):
        self.used.add(key)
        if key not in self.data:
            if default is _MISSING:
                near = _closest(key, [k for k in self.data if k not in self.used])
                raise self.error(key, "required field is missing" + (
                    f" ({_quote(near)} is given: a misspelling of {_quote(key)}?)" if near
                    else ""))
            return default
        return self.data[key]

    def number(self, key, default=_MISSING, positive=False, nonzero=False, within=None):
        """A finite number; ``within``: its ``limits.Range`` (plausible values)."""
        v = self.raw(key, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.error(key, f"expected a number, got {_show(v)}")
        try:
            v = float(v)
        except OverflowError:
            raise self.error(key, "beyond the range of a 64-bit float (about 1.8e308)") from None
        if not math.isfinite(v):
            raise self.error(key, f"must be finite, got {v}")
        if positive and not v > 0:
            raise self.error(key, f"must be positive, got {v:g}")
        if nonzero and v == 0:
            raise self.error(key, "must not be zero")
        if within is not None:
            self.check_range(key, v, within)
        return v

    def check_range(self, key, v, within, what=""):
        """Refuse ``v`` outside ``within`` (a ``limits.Range``), naming the field
        and the range."""
        if not within.holds(v):
            unit = f" {within.unit}" if within.unit else ""
            raise self.error(key, f"{what}{v:g}{unit} is out of range: {within.words()}")

    def integer(self, key, default=_MISSING, minimum=None, choices=None, maximum=None,
                why=""):
        """An integer; ``maximum`` with ``why``: a limit and the reason for it."""
        v = self.raw(key, default)
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.error(key, f"expected an integer, got {_show(v)}")
        if not -2**63 <= v < 2**63:
            raise self.error(key, f"{v} is beyond the range of a 64-bit integer")
        if minimum is not None and v < minimum:
            raise self.error(key, f"must be at least {minimum}, got {v}")
        if maximum is not None and v > maximum:
            raise self.error(key, f"at most {maximum:,} ({why}), got {v:,}")
        if choices is not None and v not in choices:
            raise self.error(key, f"must be one of {', '.join(map(str, choices))}, got {v}")
        return v

    def string(self, key, default=_MISSING, choices=None):
        v = self.raw(key, default)
        if not isinstance(v, str):
            raise self.error(key, f"expected a string, got {_show(v)}")
        if choices is not None and v not in choices:
            raise self.error(key, f"must be one of {', '.join(choices)}, got {_quote(v)}")
        return v

    def name(self, key, default=_MISSING, maximum=MAX_NAME_LENGTH, why=NAME_WHY,
             empty=False):
        """A name (of a point, a group, a body, ...): a string of printable
        characters, at most ``maximum`` long (``name_problem``); the empty
        default of an optional name passes, and ``empty`` lets an empty name
        pass (a label that may be blank: the study's name and title)."""
        v = self.string(key, default)
        if v == "" and (empty or default == ""):
            return v
        problem = name_problem(v, maximum, why)
        if problem:
            raise self.error(key, problem)
        return v

    def names(self, key, n=None, default=_MISSING, maximum=MAX_NAME_LENGTH, why=NAME_WHY):
        """A list of names (``name``), or None where the default is None."""
        v = self.strings(key, n, default)
        for k, x in enumerate(v or ()):
            problem = name_problem(x, maximum, why)
            if problem:
                raise self.error(key, f"name {k + 1}: {problem}")
        return v

    def key_name(self, key, maximum=MAX_NAME_LENGTH, why=NAME_WHY):
        """A key of this table that is a name (a fixed point, a sweep variable)."""
        problem = name_problem(key, maximum, why)
        if problem:     # (an empty key too: its path shows it quoted, '')
            raise StudyError(self.file, self.path(key), problem)
        return key

    def strings(self, key, n=None, default=_MISSING):
        v = self.raw(key, default)
        if v is None:
            return None
        if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
            raise self.error(key, f"expected a list of strings, got {_show(v)}")
        if n is not None and len(v) != n:
            raise self.error(key, f"expected {n} names, got {len(v)}")
        return tuple(v)

    def numbers(self, key, n=None, default=_MISSING, within=None):
        v = self.raw(key, default)
        if not isinstance(v, list) or not all(
                isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):
            raise self.error(key, f"expected a list of numbers, got {_show(v)}")
        if n is not None and len(v) != n:
            raise self.error(key, f"expected {n} numbers, got {len(v)}")
        try:
            out = tuple(float(x) for x in v)
        except OverflowError:
            raise self.error(key, "a number is beyond the range of a 64-bit float "
                                  "(about 1.8e308)") from None
        if not all(math.isfinite(x) for x in out):
            raise self.error(key, "numbers must be finite")
        if within is not None:
            for k, x in enumerate(out):
                self.check_range(key, x, within, f"number {k + 1}: ")
        return out

    def table(self, key, default=_MISSING):
        v = self.raw(key, default)
        if v is None:
            return None
        return Section(self.file, self.path(key), v)

    def tables(self, key, default=_MISSING):
        v = self.raw(key, default)
        if not isinstance(v, list):
            raise self.error(key, f"expected an array of tables ([[{self.path(key)}]]), got {_show(v)}")
        return [Section(self.file, f"{self.path(key)}[{i}]", x) for i, x in enumerate(v)]

    def done(self):
        """Reject keys nobody asked for (typos must not be silently ignored)."""
        extra = sorted(set(self.data) - self.used)
        if extra:
            near = _closest(extra[0], self.used)
            raise self.error(extra[0], f"unknown key {_quote(extra[0])}"
                             + (f"; did you mean {_quote(near)}?" if near else "")
                             + (f" (known here: {', '.join(sorted(self.used))})" if self.used else ""))


def _closest(name, candidates):
    """The candidate that ``name`` most likely misspells (difflib), or None."""
    import difflib
    found = difflib.get_close_matches(str(name), [str(c) for c in candidates], n=1,
                                      cutoff=0.75)
    return found[0] if found else None


def _show(v):
    s = repr(v)
    return f"{type(v).__name__} {s[:40]}"


def _quote(v, limit=40):
    """A user's text in a message: repr() (one line: every character that is
    not printable escaped), cut after ``limit`` characters."""
    v = str(v)
    return repr(v) if len(v) <= limit else f"{v[:limit]!r}... ({len(v):,} characters)"


def _key(key):
    """A table key in a field's path: bare where it is a plain word, else quoted."""
    k = str(key)
    if k and len(k) <= MAX_NAME_LENGTH and all(c.isascii() and (c.isalnum() or c in "_-")
                                               for c in k):
        return k
    return _quote(k)


_CATEGORIES = {"Cc": "a control character", "Cf": "a format character",
               "Zl": "a line separator", "Zp": "a paragraph separator",
               "Zs": "a space other than U+0020", "Co": "a private-use character",
               "Cn": "an unassigned code point", "Cs": "a surrogate"}


def name_problem(v: str, maximum=MAX_NAME_LENGTH, why=NAME_WHY):
    """Why ``v`` cannot be a name, or None.  A name is data (a label in tables,
    pictures and messages; in generated kernels only inside comments written by
    ascii()), so any printable character is allowed (quotes, backslashes, #,
    slashes, letters of any script); refused: the empty name, more than
    ``maximum`` characters, a character that is not printable (control and
    format characters such as NUL, tab, CR, LF, U+0085, U+200B, line and
    paragraph separators U+2028/U+2029, spaces other than U+0020) and
    surrounding spaces."""
    if not v:
        return "a name must not be empty"
    if len(v) > maximum:
        return f"a name is at most {maximum} characters ({why}), got {len(v):,}"
    for i, c in enumerate(v):
        if not c.isprintable():
            cat = unicodedata.category(c)
            return (f"a name holds printable characters only: character {i + 1} is "
                    f"U+{ord(c):04X}, {_CATEGORIES.get(cat, cat)}")
    if v != v.strip():
        return "a name must not begin or end with a space"
    return None
