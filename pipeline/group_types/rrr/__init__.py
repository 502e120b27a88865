"""RRR: B joined to two known points by two links (circle intersection).

Its folder's modules, by layer: ``pipeline.group_types``."""

G_RRR = 1

CODES = {G_RRR: "RRR"}
