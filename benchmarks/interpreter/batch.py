"""FROZEN COPY of the pre-compiler interpreter kernels (agreement check and
benchmarks only).

One revolution of every candidate, with full kinematics (and optionally the
force analysis), reduced per candidate to its peaks: the batch form of a
scene, used for throughput measurements and quick screening."""

import math

import numpy as np
from numba import njit, prange

from .assembly import advance, has_newton, init_state, kinematic_work, start_angle
from pipeline.kernels.config import JIT_ALLOC as JIT, OK

JIT_PARALLEL = dict(JIT, parallel=True)   # the interpreter's parfor batches
from pipeline.kernels.forces import force_work, kinetostatics


@njit(**JIT_PARALLEL)
def revolutions_batch(pars, codes, gidx, goff, fixed_idx, fixed_off, n_points, phis, order, tols,
                      point, with_forces, omega1, eps1, gravity, body_com, body_turn,
                      body_mass_off, joint_point, joint_bodies, slide_bodies, slide_dir,
                      slide_angle, crank_body, load_body, load_point, loads, status, peak_acc,
                      peak_reaction):
    """For each parameter row: status over the revolution, the peak
    acceleration analog |r''| of ``point`` (mm/rad^2) and, with_forces, the
    peak joint reaction (N).  NaN peaks with an OK status would be an
    unflagged failure (the stress suite checks there are none)."""
    ng = codes.shape[0]
    nb = body_com.shape[0]
    nj = joint_point.shape[0]
    newton = has_newton(codes)
    for i in prange(pars.shape[0]):
        par = pars[i]
        pos, d1, d2, margins, state, _ = kinematic_work(n_points, ng)
        work_a, work_b, loads_out, r_out, slide_out = force_work(nb, nj, slide_bodies.shape[0])
        init_state(codes, goff, par, state)
        phi_prev = start_angle(codes, goff, par) if newton else phis[0]
        st = OK
        acc = 0.0
        peak = 0.0
        finite = True
        for k in range(phis.shape[0]):
            s = advance(codes, gidx, goff, par, fixed_idx, fixed_off, phi_prev, phis[k], order,
                        tols, state, newton, pos, d1, d2, margins)
            phi_prev = phis[k]
            if s != OK:
                st = s
                break
            a = math.hypot(d2[point, 0], d2[point, 1])
            finite = finite and math.isfinite(a)
            acc = max(acc, a)
            if with_forces:
                kinetostatics(pos, d1, d2, omega1, eps1, gravity, par, body_com, body_turn,
                              body_mass_off, joint_point, joint_bodies, slide_bodies, slide_dir,
                              slide_angle, crank_body, load_body, load_point, loads[k], work_a,
                              work_b, loads_out, r_out, slide_out)
                for j in range(nj):
                    r = math.hypot(r_out[j, 0], r_out[j, 1])
                    finite = finite and math.isfinite(r)
                    peak = max(peak, r)
        status[i] = st
        # a NaN under an OK status must stay visible: NaN then, with status OK
        peak_acc[i] = acc if (st == OK and finite) else math.nan
        peak_reaction[i] = peak if (st == OK and with_forces) else math.nan
