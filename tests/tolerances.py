"""Every test tolerance in one place (explicit, never loosened to make a test pass)."""

REFERENCE_MM = 1e-6          # reference position tables (DOMAIN.md: the contract)
ANALOG_REL = 1e-7            # exact analogs vs the independent finite-difference solver
CLOSURE_MM = 1e-9            # closure residuals and preserved link lengths
VIRTUAL_POWER_REL = 1e-9     # virtual-power identity, relative to the largest power term
REACTION_REL = 1e-7          # reactions vs the naive dense solve (its kinematics are FD)
SELF_FD_REL = 1e-6           # kernel analog vs a plain finite difference of kernel positions
SWEEP_VS_SCENE_REL = 1e-9    # sweep metrics recomputed through the scene path
