"""RPP (the Scotch yoke) and PPR (the same chain read from its other end,
solved as one).

Its folder's modules, by layer: ``pipeline.group_types``."""

G_RPP = 7

CODES = {G_RPP: "RPP"}
