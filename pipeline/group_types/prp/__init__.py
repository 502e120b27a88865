"""PRP: two blocks joined by a revolute, each sliding on a known guide.

Its folder's modules, by layer: ``pipeline.group_types``."""

G_PRP = 6

CODES = {G_PRP: "PRP"}
