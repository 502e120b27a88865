"""The sweep's stages, as the generated kernels (``pipeline.compiler``) write
them: the layout of a candidate's metric row and of the settings vector.

Stages, cheapest first:
  1. positions only: assembly over the revolution (triangle, Newton, branch,
     closure), singularity margin, rocker swing -> stroke, dwell error;
  2. only for candidates still feasible (status OK, stroke and margin within
     their limits) and only if a force metric is asked for: second analogs,
     kinetostatics at every position -> peak reaction, its joint and angle,
     peak balancing moment.
"""

import numpy as np

# metric columns of a candidate's row
M_STROKE = 0
M_DWELL = 1
M_DWELL_START = 2
M_MARGIN = 3
M_PEAK_R = 4
M_PEAK_JOINT = 5
M_PEAK_PHI = 6
M_PEAK_MBAL = 7
M_FAIL_PHI = 8
M_NEWTON_MEAN = 9
M_FORCES_DONE = 10
M_FAIL_GROUP = 11   # index of the group that failed (NaN: none)
N_METRICS = 12

# slots of the settings vector of a sweep (one float array: the kernels'
# signatures stay short, and the numba cache is not tied to a study)
SET_STROKE_RADIUS = 0   # mm: stroke = radius x rocker swing
SET_DWELL_W = 1         # intervals spanned by the dwell window
SET_WANT_FORCES = 2     # 1.0: run the force stage
SET_STROKE_LO = 3       # mm
SET_STROKE_HI = 4       # mm
SET_MARGIN_MIN = 5      # singularity margin constraint
SET_OMEGA1 = 6          # rad/s
SET_EPS1 = 7            # rad/s^2
SET_MARGIN_SAFE = 8     # below this margin a lane is redone on the careful path
N_SETTINGS = 9

MARGIN_SAFE = 1e-3


def settings(stroke_radius, dwell_w, want_forces, stroke_lo, stroke_hi, margin_min, omega1,
             eps1, margin_safe=MARGIN_SAFE):
    """The settings vector of a sweep, in slot order."""
    s = np.empty(N_SETTINGS)
    s[SET_STROKE_RADIUS] = stroke_radius
    s[SET_DWELL_W] = dwell_w
    s[SET_WANT_FORCES] = 1.0 if want_forces else 0.0
    s[SET_STROKE_LO] = stroke_lo
    s[SET_STROKE_HI] = stroke_hi
    s[SET_MARGIN_MIN] = margin_min
    s[SET_OMEGA1] = omega1
    s[SET_EPS1] = eps1
    s[SET_MARGIN_SAFE] = margin_safe
    return s
