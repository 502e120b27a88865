"""The take-up study's [mechanism.friction] section, written once for the tests
that add friction to it (scenes, crank dynamics, the tables)."""

# pins and both slides (DOMAIN.md: mu, pin and block sizes in mm)
TAKEUP_FRICTION = """[mechanism.friction]
revolute = 0.06
slide = 0.12
pin_diameter = 6.0
pin_length = 8.0
block_length = 12.0
"""

# the same with the needle bar's block bearing on its edges (30 mm apart)
TAKEUP_FRICTION_EDGES = TAKEUP_FRICTION + 'blocks = { "needle bar" = 30.0 }\n'
