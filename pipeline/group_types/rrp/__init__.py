"""RRP: a slider on a guide joined by a link to a known point.

Its folder's modules, by layer: ``pipeline.group_types``."""

G_RRP = 2

CODES = {G_RRP: "RRP"}
