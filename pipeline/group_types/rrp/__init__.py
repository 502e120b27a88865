"""RRP: a slider on a guide joined by a link to a known point.

This folder holds everything about the type, by layer: ``model`` (its study
fields and plan row), ``kernels`` (its library kernels), ``emitter`` (its lines
of the generated module: careful path, lane form, force lanes, warm-up).
``CODES`` gives each plan code it adds its name (``pipeline.group_types``
derives every table from it)."""

G_RRP = 2

CODES = {G_RRP: "RRP"}
