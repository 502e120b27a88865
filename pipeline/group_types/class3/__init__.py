"""The class III group (triad) of DOMAIN.md section 5, and its variant with a
block on a guide in place of lead 5-7: solved by Newton and continued along
the revolution.

Its folder's modules, by layer: ``pipeline.group_types``."""

G_CLASS3 = 4
G_CLASS3_SLIDER = 9

CODES = {G_CLASS3: "class3", G_CLASS3_SLIDER: "class3_slider"}

# solved by continuation (``pipeline.group_types.continued_codes``)
CONTINUED = (G_CLASS3, G_CLASS3_SLIDER)
