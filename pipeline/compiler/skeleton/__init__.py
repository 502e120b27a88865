"""The fixed parts of every generated module, as Python files linters and readers
see (``pipeline.compiler.generate`` pastes them around the emitters' lines).

Each file has, above its marker line, the imports that declare the names the
generated module gives its text (``header``: the module's own imports;
``_mechanism``: what the mechanism's plan defines); from the marker on, the text
is the generated module's, verbatim (``header`` ends at its end marker).
"""

from __future__ import annotations

import functools
from importlib import resources

MARKER = "# ---- the skeleton: from here on, pasted into the generated module ----\n"
END = "# ---- end of the skeleton ----\n"


@functools.cache
def part(name: str, package: str = __name__) -> str:
    """The text of skeleton file ``name``.py after its marker line (up to its end
    marker, if it has one); of a library module of ``package`` that the
    generated modules also hold (``pipeline.kernels.walk``)."""
    text = resources.files(package).joinpath(name + ".py").read_text(encoding="ascii")
    head, found, body = text.partition(MARKER)
    if not found:
        raise ValueError(f"{package}.{name} has no marker line")
    return body.partition(END)[0]
