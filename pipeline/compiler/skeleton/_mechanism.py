"""The names a generated module defines from its mechanism's plan, declared for
linters and readers of the skeleton files (which import them from here above
their marker line).  Nothing imports this at run time: each generated module
writes its own (``pipeline.compiler.generate``, ``lanes``, ``forces``).
"""

# the plan's constants (generate)
N_POINTS = N_GROUPS = N_TRIADS = N_BODIES = N_JOINTS = N_SLIDES = N_INPUTS = 0
N_PARAMS = 0        # a candidate's parameters
CRANK_PIVOT = 0     # point index of the crank's pivot (the shaking moment's reference)
GRAVITY = 0.0
BODY_COM = BODY_TURN = BODY_MASS_OFF = LOAD_BODY = LOAD_POINT = None     # index arrays
WATCH_G = None      # the groups the walks watch between positions
N_WATCH = 0

# the lane path's constants (lanes: a sweep's output rocker and lane rows)
ROCKER_PIVOT = ROCKER_POINT = LANES = NEWTON_STEPS = N_LANE_ROWS = THETA_COLS = 0
THETA_IN = TRAIL_COLS = MARGIN_COL = 0
LANE_STEP_MAX = 0.0
R_margin = R_flag = R_first_flag = R_last_flag = 0

# kernels written from the plan
constants = position = start = transmission = None     # generate
advance = None              # generate: skeleton advance_closed or advance_newton
forces_at = None            # forces
setup_lane = block_walk = lanes_apply = None    # lanes (or skeleton no_lanes)
HAS_LANES = False           # lanes: every kinematic group has a lane form
walk = None                 # lanes: the lock-step walk (none without them)

# the force lanes' constants and kernels (lane_forces, or skeleton no_lane_forces)
HAS_LANE_FORCES = False
SAME_BITS = False
N_FROWS = FT_COLS = N_RCOLS = F_pm = F_pe = F_bad = 0
# RB's columns of the working point's acceleration; the transmission items, their first
ACC_COL = N_TRANS = TR_COL = 0
force_lanes = force_lane_in = None
