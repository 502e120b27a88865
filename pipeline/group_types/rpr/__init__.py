"""RPR: the coulisse, a block pinned at a known point sliding on a guide that
turns about a fixed pivot.

Its folder's modules, by layer: ``pipeline.group_types``."""

G_RPR = 3

CODES = {G_RPR: "RPR"}
