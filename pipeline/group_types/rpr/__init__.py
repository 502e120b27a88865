"""RPR: the coulisse, a block pinned at a known point sliding on a guide that turns about a
fixed pivot.

This folder holds everything about the type, by layer: ``model`` (its study
fields and plan row), ``kernels`` (its library kernels), ``emitter`` (its lines
of the generated module: careful path, lane form, force lanes, warm-up).
``CODES`` gives each plan code it adds its name (``pipeline.group_types``
derives every table from it)."""

G_RPR = 3

CODES = {G_RPR: "RPR"}
