"""Kinetostatics along a crank motion (issue 29, item 1;
``pipeline.solve.motion_forces``): along the take-up's dynamics solution the
reactions and M_bal satisfy virtual power at every step and the balancing
moment is the one the equation of motion implies (M1 - b omega1); held at a
constant speed they are the scene's kinetostatics; against naive.py's dense
solve at the actual omega1 and eps1 (the take-up, and mechanism B under a
prescribed non-uniform motion).  The scene file and CSV: tests/solve/test_dynamics.py
(its `pipeline run` of the take-up)."""

import math

import numpy as np
import pytest

from support import naive
from support.tolerances import REACTION_FD_REL
from pipeline.kernels import config as kc
from pipeline.solve import crank_motion as dy
from pipeline.solve.motion_forces import along, case_forces, steady_slice
from pipeline.solve.reactions import load_time, scene_forces
from pipeline.solve.scene import revolution_angles, solve_curves
from pipeline.study.reader import load_study

VIRTUAL_POWER_REL = 1e-9     # issue 29: virtual power at every step of the solution
CONSTANT_SPEED_REL = 1e-12   # issue 29: equal to the constant-speed kinetostatics
M_BAL_EOM_REL = 1e-12        # M_bal = M1 - b omega1 (rounding of J, Q and eps1 only)


@pytest.fixture(scope="module")
def takeup(studies):
    study = load_study(studies / "takeup_dynamics.toml")
    plan = study.mechanism.compile()
    cases = {c.name: dy.integrate(plan, study.mechanism, c, "rk4") for c in study.dynamics.cases}
    forces = {name: case_forces(study.mechanism, plan, c) for name, c in cases.items()}
    return study, plan, cases, forces


def test_records_cover_every_output_step(takeup):
    _, _, cases, forces = takeup
    run, free = cases["runup"], cases["free"]
    assert set(forces["runup"]) == {"samples", "steady"} and set(forces["free"]) == {"samples"}
    np.testing.assert_array_equal(forces["runup"]["samples"].t, run.t)
    s = steady_slice(run)
    steady = forces["runup"]["steady"]
    np.testing.assert_array_equal(steady.t, run.tail_t[s])
    # the steady record spans the last whole revolutions steady() averages
    assert abs(steady.phi1[-1] - steady.phi1[0]) >= 2.0 * math.pi * run.steady()["revolutions"]
    np.testing.assert_array_equal(forces["free"]["samples"].omega1, free.omega1)
    for rec in (*forces["runup"].values(), forces["free"]["samples"]):
        assert (rec.status == kc.OK).all()
        assert np.isfinite(rec.forces.R).all() and np.isfinite(rec.forces.M_bal).all()


def test_virtual_power_and_the_equation_of_motion_at_every_step(takeup):
    """Virtual power to 1e-9 at every step; and the physics that cannot be
    faked: the moment the shaft must deliver for the integrated motion is the
    moment the equation of motion was driven with, M1 - b omega1 (the
    kinetostatics never sees M1 or b)."""
    _, _, cases, forces = takeup
    for name, recs in forces.items():
        c = cases[name].case
        for rec in recs.values():
            assert np.max(rec.forces.residual) <= VIRTUAL_POWER_REL, (name, rec.record)
            m1 = float(c.M1.evaluate(0.0))
            expect = m1 - c.damping * rec.omega1
            # relative to the inertia moments the motion carries (the constant-speed M_bal)
            scale = 0.5
            assert np.max(np.abs(rec.forces.M_bal - expect)) <= M_BAL_EOM_REL * scale, name


def test_at_constant_speed_it_is_the_scene_kinetostatics(takeup):
    study, plan, _, _ = takeup
    crank = study.mechanism.crank
    phi = revolution_angles(crank, 72)
    curves = solve_curves(plan, phi, kc.ACCELERATIONS)
    const = scene_forces(study.mechanism, plan, curves)
    n = phi.size
    rec = along(study.mechanism, plan, "held", "samples", load_time(phi, crank), phi,
                np.full(n, crank.omega1), np.full(n, crank.eps1))
    scale = np.abs(const.R).max()
    assert np.max(np.abs(rec.forces.R - const.R)) <= CONSTANT_SPEED_REL * scale
    assert np.max(np.abs(rec.forces.M_bal - const.M_bal)) <= (
        CONSTANT_SPEED_REL * np.abs(const.M_bal).max())
    assert np.max(np.abs(rec.forces.slide - const.slide)) <= CONSTANT_SPEED_REL * scale
    assert np.max(np.abs(rec.forces.shaking - const.shaking)) <= (
        CONSTANT_SPEED_REL * np.abs(const.shaking).max())


def test_takeup_against_naive_at_the_actual_speed(takeup):
    """Every reaction, both slides and M_bal at steps of the steady rotation
    against naive.py's dense solve fed that step's omega1 and eps1."""
    _, _, _, forces = takeup
    rec = forces["runup"]["steady"]
    fr = rec.forces
    for k in np.linspace(0, rec.t.size - 1, 5).astype(int):
        ref = naive.naive_forces_c(rec.phi1[k], omega1=rec.omega1[k], eps1=rec.eps1[k])
        scale = max(np.abs(ref[n]).max() for n in fr.joint_names + fr.slide_names)
        for j, n in enumerate(fr.joint_names):
            assert np.abs(fr.R[k, j] - ref[n]).max() <= REACTION_FD_REL * scale, (k, n)
        for j, n in enumerate(fr.slide_names):
            assert abs(fr.slide[k, j, 0] - ref[n][0]) <= REACTION_FD_REL * scale, (k, n)
        assert abs(fr.M_bal[k] - ref["M_bal"]) <= REACTION_FD_REL * max(abs(ref["M_bal"]), 1)


def test_mechanism_b_under_a_non_uniform_motion(studies):
    """A class III mechanism along a prescribed motion phi1(t) = w t + a sin(w t)
    (omega1 and eps1 exact): virtual power at every step and naive.py's forces
    at the step's own speed."""
    study = load_study(studies / "ov7_class3.toml")
    plan = study.mechanism.compile()
    w, a = study.mechanism.crank.omega1, 0.05
    t = np.linspace(0.0, 2.0 * math.pi / abs(w), 37)
    phi = w * t + a * np.sin(w * t)
    omega = w * (1.0 + a * np.cos(w * t))
    eps = -a * w * w * np.sin(w * t)
    rec = along(study.mechanism, plan, "prescribed", "samples", t, phi, omega, eps)
    assert np.max(rec.forces.residual) <= VIRTUAL_POWER_REL
    fr = rec.forces
    for k in (3, 11, 20, 29):
        ref = naive.naive_forces_b(phi[k], omega1=omega[k], eps1=eps[k])
        scale = max(np.abs(ref[n]).max() for n in fr.joint_names)
        for j, n in enumerate(fr.joint_names):
            assert np.abs(fr.R[k, j] - ref[n]).max() <= REACTION_FD_REL * scale, (k, n)
        assert abs(fr.M_bal[k] - ref["M_bal"]) <= REACTION_FD_REL * max(abs(ref["M_bal"]), 1)
