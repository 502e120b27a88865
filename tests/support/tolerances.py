"""Every test tolerance in one place (explicit, never loosened to make a test pass)."""

REFERENCE_MM = 1e-6          # reference position tables (DOMAIN.md: the contract)
ANALOG_REL = 1e-7            # exact analogs vs the independent finite-difference solver
CLOSURE_MM = 1e-9            # closure residuals and preserved link lengths
VIRTUAL_POWER_REL = 1e-9     # virtual-power identity, relative to the largest power term
REACTION_REL = 1e-7          # reactions vs the naive dense solve (its kinematics are FD)
SELF_FD_REL = 1e-6           # kernel analog vs a plain finite difference of kernel positions
SWEEP_VS_SCENE_REL = 1e-9    # sweep metrics recomputed through the scene path

# property tests of the group kernels (tests/test_kernel_properties.py)
LENGTH_REL = 1e-9            # link lengths / guide constraints kept by a group, relative
KERNEL_EXACT_REL = 1e-9      # differentiated closure equations hold to rounding (relative,
                             # further divided by the group's singularity margin)
WELL_INSIDE_REL = 1e-6       # this far (relative) from a toggle a group must be OK or NO_ASSEMBLY

# generated kernels: the lock-step lane path against the careful path.  Both stop
# Newton at 1e-12 of the lead lengths, so their solutions may differ by that much;
# a metric that is a small difference of large products (the singularity margin)
# magnifies it a few times (measured: 5.5e-12 worst of 10^4; 5e-13 when both
# paths are pushed to 1e-15).  Statuses must be identical.
KERNEL_AGREEMENT = 2e-11
MP_REFERENCE_REL = 1e-12     # slider dyads (PRP, RPP) vs the 30-digit solve of tests/support/naive.py:
                             # positions and analogs, relative to each one's largest value over
                             # the revolution (the acceptance figure)
