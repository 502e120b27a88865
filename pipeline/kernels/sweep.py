"""The sweep's stages, as the generated kernels (``pipeline.compiler``) write
them: the layout of a candidate's metric row and of the settings vector.

Stages, cheapest first:
  1. positions only: assembly over the revolution (triangle, Newton, branch,
     closure), singularity margin, rocker swing -> stroke, dwell error;
  2. only for candidates still feasible (status OK, stroke and margin within
     their limits) and only if one of its metrics is asked for: second analogs,
     kinetostatics at every position -> peak reaction, its joint and angle,
     peak balancing moment, worst equilibrium residual, peak shaking force
     and moment on the frame; the working point's
     peak |a| and the output rocker's peak |eps| (SET_WANT_PEAKS); the
     smallest transmission angle (SET_WANT_TRANSMISSION).  Each is a maximum
     (minimum) over the grid's positions, not refined between them
     (``pipeline.solve.peaks`` refines a scene's).

The law error (SET_WANT_LAW) is part of stage 1: the rocker angles the
positions stage has, against the required motion law sampled at the grid
(``settings[SET_LAW0:]``, see ``settings``).
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
M_PEAK_ACC = 12     # m/s^2: largest |a| of the working point over the positions
M_PEAK_EPS = 13     # 1/s^2: largest |eps| of the output rocker over the positions
M_MIN_TRANS = 14    # rad: smallest transmission angle (pipeline.solve.peaks.transmission_items)
M_LAW_RMS = 15      # RMS deviation of the normalised rocker angle from the motion law
M_LAW_MAX = 16      # largest |deviation| (the same alignment and orientation)
M_LAW_SHIFT = 17    # rad: cycle-angle shift of the law that fits best (0: align fixed)
M_EQUILIBRIUM = 18  # largest relative virtual-power residual of the kinetostatics
M_SHAKING_F = 19    # N: largest |shaking force| on the frame (kernels.forces.shaking)
M_SHAKING_M = 20    # N*m: largest |shaking moment| about the crank's pivot
N_METRICS = 21

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
SET_WANT_PEAKS = 9      # 1.0: the working point's peak |a| and the rocker's peak |eps|
SET_WORK_POINT = 10     # point index of the working point (for SET_WANT_PEAKS)
SET_WANT_TRANSMISSION = 11   # 1.0: the smallest transmission angle
SET_WANT_LAW = 12       # 0: no law error; 1: law at a fixed alignment; 2: best alignment
SET_WANT_EQUILIBRIUM = 13   # 1.0: the worst equilibrium residual (with SET_WANT_FORCES)
SET_WANT_SHAKING = 14   # 1.0: the peak shaking force and moment (with SET_WANT_FORCES)
SET_SCALAR_FORCES = 15  # 1.0: the scalar force stage for every candidate, never the force
                        # lanes (the baseline of their tests and benchmark; never for results)
N_SETTINGS = 16
SET_LAW0 = N_SETTINGS   # with SET_WANT_LAW: the law at positions 0 .. 2n - 1 (two turns)

LAW_FIXED = 1.0
LAW_BEST = 2.0

MARGIN_SAFE = 1e-3


def settings(stroke_radius, dwell_w, want_forces, stroke_lo, stroke_hi, margin_min, omega1,
             eps1, margin_safe=MARGIN_SAFE, want_peaks=False, work_point=-1,
             want_transmission=False, law=None, law_best=False, want_equilibrium=False,
             want_shaking=False, scalar_forces=False):
    """The settings vector of a sweep, in slot order.  ``law``: the motion
    law's normalised displacement at the n positions of the grid (None: no
    law error); it is stored twice over (2n values), so a shifted law reads
    law[k + s] without a modulo."""
    law = None if law is None else np.asarray(law, float)
    s = np.empty(N_SETTINGS + (0 if law is None else 2 * law.shape[0]))
    s[SET_STROKE_RADIUS] = stroke_radius
    s[SET_DWELL_W] = dwell_w
    s[SET_WANT_FORCES] = 1.0 if want_forces else 0.0
    s[SET_STROKE_LO] = stroke_lo
    s[SET_STROKE_HI] = stroke_hi
    s[SET_MARGIN_MIN] = margin_min
    s[SET_OMEGA1] = omega1
    s[SET_EPS1] = eps1
    s[SET_MARGIN_SAFE] = margin_safe
    s[SET_WANT_PEAKS] = 1.0 if want_peaks else 0.0
    s[SET_WORK_POINT] = work_point
    s[SET_WANT_TRANSMISSION] = 1.0 if want_transmission else 0.0
    s[SET_WANT_LAW] = 0.0 if law is None else (LAW_BEST if law_best else LAW_FIXED)
    s[SET_WANT_EQUILIBRIUM] = 1.0 if want_equilibrium else 0.0
    s[SET_WANT_SHAKING] = 1.0 if want_shaking else 0.0
    s[SET_SCALAR_FORCES] = 1.0 if scalar_forces else 0.0
    if law is not None:
        n = law.shape[0]
        s[SET_LAW0:SET_LAW0 + n] = law
        s[SET_LAW0 + n:] = law
    return s
