"""FROZEN COPY of the pre-compiler interpreter kernels (agreement check and
benchmarks only).

Batch evaluation of candidates: one row of parameters in, status and
metrics out, in one pass over the revolution per stage (no per-position
arrays kept beyond the rocker angle the dwell window needs).

Stages, cheapest first:
  1. positions only: assembly over the revolution (triangle, Newton, branch,
     closure), singularity margin, rocker swing -> stroke, dwell error;
  2. only for candidates still feasible (status OK, stroke and margin within
     their limits) and only if a force metric is asked for: second analogs,
     kinetostatics at every position -> peak reaction, its joint and angle,
     peak balancing moment.

``evaluate_candidate`` does one row; the parallel and serial batch functions
are separate compiled functions (numba's cache does not tell a parallel and a
serial compile of one function apart).
"""

import math

import numpy as np
from numba import njit, prange

from .assembly import advance, closes, has_newton, init_state, kinematic_work, start_angle
from pipeline.group_types.class3 import G_CLASS3
from pipeline.kernels.config import BRANCH_JUMP, JIT_ALLOC as JIT, OK, S_ITERS
from pipeline.kernels.forces import force_work, kinetostatics
from pipeline.kernels.metrics import dwell_error, relative_angle

JIT_PARALLEL = dict(JIT, parallel=True)   # the interpreter's parfor batches

# metric columns
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
N_METRICS = 11


@njit(**JIT)
def evaluate_candidate(par, codes, n_kinematic, gidx, goff, fixed_idx, fixed_off, n_points, phis,
                       phi_close,
                       tols, rocker_a, rocker_b, stroke_radius, dwell_w, want_forces,
                       stroke_lo, stroke_hi, margin_min, omega1, eps1, gravity, body_com,
                       body_turn, body_mass_off, joint_point, joint_bodies, slide_bodies,
                       slide_dir, slide_angle, crank_body, load_body, load_point, loads, out):
    """Evaluate one candidate (parameter row ``par``); writes ``out`` (N_METRICS)
    and returns its status.  The positions stage solves only the first
    ``n_kinematic`` groups (the centres of mass that follow serve forces)."""
    for k in range(N_METRICS):
        out[k] = math.nan
    out[M_FORCES_DONE] = 0.0
    n = phis.shape[0]
    ng = codes.shape[0]
    pos, d1, d2, margins, state, start_state = kinematic_work(n_points, ng)
    theta = np.empty(n)
    newton = has_newton(codes)

    # ---- stage 1: positions over the revolution, without the centres of mass
    kin = codes[:n_kinematic]
    init_state(codes, goff, par, state)
    phi_prev = start_angle(codes, goff, par) if newton else phis[0]
    margin = math.inf
    iters = 0.0
    x0 = 0.0
    y0 = 0.0
    for k in range(n):
        st = advance(kin, gidx, goff, par, fixed_idx, fixed_off, phi_prev, phis[k], 0, tols,
                     state, newton, pos, d1, d2, margins)
        phi_prev = phis[k]
        if st != OK:
            out[M_FAIL_PHI] = phis[k]
            return st
        if k == 0:
            start_state[:, :] = state
            x0 = pos[rocker_b, 0] - pos[rocker_a, 0]
            y0 = pos[rocker_b, 1] - pos[rocker_a, 1]
        for g in range(ng):
            if codes[g] == G_CLASS3:
                margin = min(margin, margins[g])
                iters += state[g, S_ITERS]
        theta[k] = relative_angle(x0, y0, pos[rocker_b, 0] - pos[rocker_a, 0],
                                  pos[rocker_b, 1] - pos[rocker_a, 1])
    if newton and math.isfinite(phi_close):
        st = advance(kin, gidx, goff, par, fixed_idx, fixed_off, phi_prev, phi_close, 0, tols,
                     state, newton, pos, d1, d2, margins)
        if st != OK or not closes(codes, state, start_state, tols):
            out[M_FAIL_PHI] = phi_close
            return st if st != OK else BRANCH_JUMP
    qmax = np.empty(n + dwell_w + 1, np.int64)
    qmin = np.empty(n + dwell_w + 1, np.int64)
    err, start, full = dwell_error(theta, dwell_w, qmax, qmin)
    out[M_STROKE] = stroke_radius * full
    out[M_DWELL] = err
    out[M_DWELL_START] = phis[start] if start >= 0 else math.nan
    out[M_MARGIN] = margin if newton else math.nan
    out[M_NEWTON_MEAN] = iters / n

    # ---- stage 2: forces, only where they can still matter
    if not want_forces:
        return OK
    if not (out[M_STROKE] >= stroke_lo and out[M_STROKE] <= stroke_hi):
        return OK
    if newton and not (margin >= margin_min):
        return OK
    nj = joint_point.shape[0]
    work_a, work_b, loads_out, r_out, slide_out = force_work(
        body_com.shape[0], nj, slide_bodies.shape[0])
    init_state(codes, goff, par, state)
    phi_prev = start_angle(codes, goff, par) if newton else phis[0]
    peak = -1.0
    peak_j = -1
    peak_phi = math.nan
    peak_m = 0.0
    for k in range(n):
        st = advance(codes, gidx, goff, par, fixed_idx, fixed_off, phi_prev, phis[k], 2, tols,
                     state, newton, pos, d1, d2, margins)
        phi_prev = phis[k]
        if st != OK:  # cannot happen after stage 1 unless the solver is not deterministic
            out[M_FAIL_PHI] = phis[k]
            return st
        mb = kinetostatics(pos, d1, d2, omega1, eps1, gravity, par, body_com, body_turn,
                           body_mass_off, joint_point, joint_bodies, slide_bodies, slide_dir,
                           slide_angle, crank_body, load_body, load_point, loads[k], work_a,
                           work_b, loads_out, r_out, slide_out)
        if abs(mb) > abs(peak_m) or not math.isfinite(mb):
            peak_m = mb
        for j in range(nj):
            r = math.hypot(r_out[j, 0], r_out[j, 1])
            if r > peak or not math.isfinite(r):
                peak = r
                peak_j = j
                peak_phi = phis[k]
    out[M_PEAK_R] = peak
    out[M_PEAK_JOINT] = peak_j
    out[M_PEAK_PHI] = peak_phi
    out[M_PEAK_MBAL] = abs(peak_m)
    out[M_FORCES_DONE] = 1.0
    return OK


@njit(**JIT_PARALLEL)
def evaluate_batch_parallel(pars, codes, n_kinematic, gidx, goff, fixed_idx, fixed_off, n_points,
                            phis, phi_close, tols, rocker_a, rocker_b, stroke_radius, dwell_w,
                            want_forces, stroke_lo, stroke_hi, margin_min, omega1, eps1, gravity,
                            body_com, body_turn, body_mass_off, joint_point, joint_bodies,
                            slide_bodies, slide_dir, slide_angle, crank_body, load_body,
                            load_point, loads, status, metrics):
    """evaluate_candidate over the rows of ``pars``, in parallel over candidates."""
    for i in prange(pars.shape[0]):
        status[i] = evaluate_candidate(
            pars[i], codes, n_kinematic, gidx, goff, fixed_idx, fixed_off, n_points, phis,
            phi_close, tols, rocker_a, rocker_b, stroke_radius, dwell_w, want_forces, stroke_lo,
            stroke_hi, margin_min, omega1, eps1, gravity, body_com, body_turn, body_mass_off, joint_point,
            joint_bodies, slide_bodies, slide_dir, slide_angle, crank_body, load_body,
            load_point, loads, metrics[i])


@njit(**JIT)
def evaluate_batch_serial(pars, codes, n_kinematic, gidx, goff, fixed_idx, fixed_off, n_points,
                          phis, phi_close, tols, rocker_a, rocker_b, stroke_radius, dwell_w,
                          want_forces, stroke_lo, stroke_hi, margin_min, omega1, eps1, gravity,
                          body_com, body_turn, body_mass_off, joint_point, joint_bodies,
                          slide_bodies, slide_dir, slide_angle, crank_body, load_body,
                          load_point, loads, status, metrics):
    """The same, on one thread (Dask workers: one task per core)."""
    for i in range(pars.shape[0]):
        status[i] = evaluate_candidate(
            pars[i], codes, n_kinematic, gidx, goff, fixed_idx, fixed_off, n_points, phis,
            phi_close, tols, rocker_a, rocker_b, stroke_radius, dwell_w, want_forces, stroke_lo,
            stroke_hi, margin_min, omega1, eps1, gravity, body_com, body_turn, body_mass_off, joint_point,
            joint_bodies, slide_bodies, slide_dir, slide_angle, crank_body, load_body,
            load_point, loads, metrics[i])
