"""Every tolerance of the tests in one place (explicit, never loosened to make a
test pass), and every accuracy figure the guide states (docs/guide/accuracy.md).

The guide's figures (its table "Accuracy figures", once the README's) are the
first block: ``README_FIGURES`` says which constants each row of that table
states, in the order written, and tests/test_accuracy_figures.py fails when the
page and this file disagree.  Each figure is asserted at its value by the test named
beside it; the measurement it rests on (this checkout, the CI machine kind) is
in the comment.
"""

# ------------------------------------- the guide's figures (docs/guide/accuracy.md)
# reference position tables (both OV-7 designs): the tables' 6 decimals round to
# 5e-7 mm; measured 4.97e-7 (A) and 4.98e-7 (B).  test_kinematics
REFERENCE_MM = 5e-7
# exact analogs vs the independent 8th-order finite-difference solver of
# naive.py, relative to each quantity's scale; measured 4.9e-10 (A), 5.0e-10 (B):
# the figure is the oracle's own accuracy, not the kernels'.  test_kinematics
ANALOG_REL = 1e-7
# virtual-power identity, relative to the largest power term.  test_forces, test_inputs
VIRTUAL_POWER_REL = 1e-9
# finite-difference analogs of mechanism B's eyelet at their best step (what the
# exact analogs spare): measured 6.25e-10 (h = 1e-5) and 3.02e-7 (h = 1e-3).  The
# figures are these measurements to one significant digit.  test_bench
FD_VELOCITY_REL = 6e-10
FD_ACCELERATION_REL = 3e-7
# Newton's tolerance (relative to the lead lengths) and the looser one it is
# compared with; at 1e-12, mechanism B's scene takes NEWTON_ITERATIONS per
# position on average (measured 2.0).  test_bench, test_kinematics
NEWTON_TOL = 1e-12
NEWTON_TOL_LOOSE = 1e-6
NEWTON_ITERATIONS = 2.0
# positions per revolution, mechanism B at the operating speed against the
# converged value: peak reaction at 12 positions measured 5.074e-5 (the peak
# lies between samples at every count up to 360); dwell error at 360 and 720
# positions measured 1.67e-3 and 7.49e-4 against 36,000 positions (1.63e-3 and
# 7.15e-4 against the quick benchmark's 7,200).  test_bench
PEAK_12_REL = 5.1e-5
DWELL_360_ABS = 2e-3
DWELL_720_ABS = 7.5e-4
# RK4, mechanism C's run-up against DOP853 (rtol = atol = 1e-12) at 10 s with
# dt = 1e-4 s: measured 7.79e-8 rad at 10 s, 7.90e-8 the largest on the way;
# energy drift of T + V over 10 s without damping or drive, relative to the
# largest T: measured 4.6e-13 (oscillation) and 3.3e-13 (rotation).  test_dynamics
RK4_VS_DOP853_RAD = 8e-8
RK4_DT_S = 1e-4
ENERGY_DRIFT_REL = 5e-13
# a failure's reported crank angle against the exact boundary (mpmath, brentq or
# a closed form): measured 5.6e-11 rad at most over the dyads, parallelograms,
# slider groups and inputs of the four test files; a class III group's fold
# 4.0e-9 rad (22 of 24 constructed folds within 7e-11: the walk accepts a
# position within Newton's tolerance of the fold, or calls it singular where
# the margin falls to 1e-6, just short of it).  test_between_samples,
# test_class3_slider, test_inputs, test_new_dyads
FAIL_ANGLE_RAD = 1e-10
FAIL_ANGLE_TRIAD_RAD = 5e-9
# the sweep's lock-step lanes against the careful path, relative, on the 20,000
# draws of the default study: stroke 3.1e-14, dwell 3.2e-13, peak reaction
# 3.1e-14, M_bal 6.9e-15; the singularity margin (a small difference of large
# products) 7.18e-12.  Statuses, failing groups, dwell starts, peak angles
# identical; failure angles (a lane that flags itself is walked from two positions
# before its flag) within 2 FAIL_ANGLE_TRIAD_RAD of the walk from the start:
# measured 1e-10 rad, and 2.1e-9 once, over 250,000 draws.  test_compiler
LANE_AGREEMENT_REL = 1e-12
LANE_MARGIN_REL = 7.2e-12
# a lane that flagged itself and met no failure is spliced: its careful window
# solved to near rounding, the lane's own numbers elsewhere.  The careful walk at
# the product's closure (1e-12) is itself off the exact numbers there by up to
# 1.1e-10 (stroke, dwell) and 1.3e-8 (margin) relative on 80,000 draws of the
# default study (672 spliced); the spliced ones by 3.3e-11 and 1.7e-11.  The
# reference: the careful walk at Newton's closure 1e-14 (as a located boundary's,
# LOCATE_NEWTON_TOL).  test_compiler and the group types' lane tests
SPLICED_REFERENCE_TOL = 1e-14
# the GPU kernels (numba's CUDA simulator) against the CPU.  test_gpu
GPU_AGREEMENT_REL = 1e-12
# on a real GPU, the near-singular candidates' failure angles are counted apart by
# each of these steps (rad) and held to the CPU's own counts under one-ulp input changes
GPU_FAIL_PHI_STEPS = (1e-9, 1e-6, 1e-3)

# the guide's table: the start of each row's first cell -> the constants its
# figure states, in the order written (numbers written as 1e-7, 5.1e-5, ...)
README_FIGURES = {
    "reference position tables": ("REFERENCE_MM",),
    "exact analogs": ("ANALOG_REL",),
    "virtual-power identity": ("VIRTUAL_POWER_REL",),
    "finite-difference analogs": ("FD_VELOCITY_REL", "FD_ACCELERATION_REL"),
    "Newton tolerance": ("NEWTON_TOL", "NEWTON_TOL_LOOSE"),
    "positions per revolution": ("PEAK_12_REL", "DWELL_360_ABS", "DWELL_720_ABS"),
    "RK4, mechanism C": ("RK4_VS_DOP853_RAD", "RK4_DT_S", "ENERGY_DRIFT_REL"),
    "failure angle": ("FAIL_ANGLE_RAD", "FAIL_ANGLE_TRIAD_RAD"),
    "sweep lanes": ("LANE_AGREEMENT_REL", "LANE_MARGIN_REL", "SPLICED_REFERENCE_TOL",
                    "LANE_AGREEMENT_REL"),
    "GPU kernels": ("GPU_AGREEMENT_REL",),
    "floating-point flags": (),
}

# ---------------------------------------------------------------- the tests' own
CLOSURE_MM = 1e-9            # closure residuals and preserved link lengths
# kernel positions against naive.py's fsolve positions (the oracle polishes its
# roots to rounding): measured 8.5e-14 (A), 1.3e-12 mm (B)
NAIVE_POSITION_MM = 1e-11
# reactions, slide forces and M_bal against naive.py's dense solve on its
# finite-difference kinematics, relative to the largest reaction (a couple to it
# at 1 mm): measured 2.0e-11 (B, D) and 7.7e-11 (the take-up C, its slides'
# couples)
REACTION_FD_REL = 2e-10
# reactions, slide forces, drives and M_bal against naive.py's dense solve on its
# 30- and 60-digit kinematics (PRP, RPP, class III slider, inputs): measured
# 3.9e-14 at most
REACTION_MP_REL = 1e-13
SELF_FD_REL = 1e-6           # kernel analog vs a plain finite difference of kernel positions
SWEEP_VS_SCENE_REL = 1e-9    # sweep metrics recomputed through the scene path
# the dwell error of mechanism B at 360 positions, package against naive.py's
# fsolve revolution: both exact positions (measured 8.7e-15 relative)
DWELL_VS_NAIVE_REL = 1e-12
# its law error against the OV-7 law: naive.py's rocker angles, every shift by brute force
LAW_VS_NAIVE_REL = 1e-12

# the sweep metric equilibrium_residual (the worst relative virtual-power residual
# of the force stage), every candidate whose forces ran: measured 7.0e-14 (600 draws
# of ov7_synthesis), 6.8e-14 (ov7_class3_slider_sweep), 1.8e-14
# (cam_rocker_input_sweep), 9.0e-15 (ppr_cross_slide_sweep), 5.0e-14
# (slotted_rocker_prp_sweep).  test_equilibrium_residual
EQUILIBRIUM_REL = 1e-12
# with M_bal 1 % off, the kernels' residual against naive.py's (its own kinematics
# and dense solve) on mechanism B: measured 2.9e-10 relative
EQUILIBRIUM_VS_NAIVE_REL = 1e-8

# the shaking force and moment of a scene (kernels.forces.shaking) against minus the
# rates of change of the momentum and angular momentum about the crank's pivot, by
# 8th-order central differences in time of the centres' velocities, relative to
# the revolution's peak (the moment's, or the peak force times the centres' reach
# where the moment is 0): measured 1.7e-11 at most (ov7_class3's moment; the class III
# groups' Newton tolerance shows through the differences), the other shipped force
# scenes 2.3e-13.  tests/solve/test_shaking
SHAKING_FD_REL = 1e-9
# the scene re-run with the reported counterweight on the crank against the
# reported shaking force and peak after it: measured 1.1e-15 (mechanisms B and D).
# test_shaking
COUNTERWEIGHT_REL = 1e-9

# property tests of the group kernels (tests/kernels/test_kernel_properties.py)
LENGTH_REL = 1e-9            # link lengths / guide constraints kept by a group, relative
KERNEL_EXACT_REL = 1e-9      # differentiated closure equations hold to rounding (relative,
                             # further divided by the group's singularity margin)
WELL_INSIDE_REL = 1e-6       # this far (relative) from a toggle a group must be OK or NO_ASSEMBLY

MP_REFERENCE_REL = 1e-12     # slider dyads (PRP, RPP) vs the 30-digit solve of
                             # tests/support/naive.py: positions and analogs, relative to
                             # each one's largest value over the revolution (the issue's
                             # acceptance figure)
