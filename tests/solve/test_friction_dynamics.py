"""The crank's motion and the flywheel with friction in the joints (issue 52).

* The take-up's run-up with friction at its pins and both slides (the block
  wedged in the coulisse at times): RK4 with the friction implicit in each
  step's omega1 and eps1 (``kernels.dynamics_friction``) passes the motion's
  own error estimate (no INACCURATE: the switches of the friction's direction
  and of a slide's normal force's sign or branch are located, RK4 keeps its
  order between them), and
  along the motion the kinetostatics with friction asks of the shaft exactly
  what drives it, M_bal = M1 - b omega1 at every sample (implicit, not lagged);
  its speed stays below the frictionless run's.
* The flywheel with the friction-inclusive moment at constant speed: the
  steady rotation's mean speed over the revolution falls by exactly the
  friction's work per revolution over 2 pi b (the energy balance of the
  periodic rotation), and the flywheel that brings it to the same delta is
  larger.
* The slopes the integrator reads a double switch from are the speeds'
  derivatives."""

import math

import numpy as np
import pytest

from pipeline.kernels import config as kc
from pipeline.solve import crank_motion as dy
from pipeline.solve.flywheel import _Orbit, size_flywheel
from pipeline.solve.motion_forces import case_forces
from pipeline.study.reader import parse_study
from support.friction_sections import TAKEUP_FRICTION_EDGES

ENERGY_REL = 1e-6       # issue 52: the steady speed and flywheel against the energy balance
IMPLICIT_REL = 1e-9     # M_bal with friction against M1 - b omega1 along the motion


def _takeup(studies, section=None):
    text = (studies / "takeup_dynamics.toml").read_text()
    if section is not None:
        text = text.replace("[output]", section + "\n[output]", 1)
    study = parse_study(text, "takeup.toml")
    case = next(c for c in study.dynamics.cases if c.name == "runup")
    return study, study.mechanism.compile(), case


@pytest.fixture(scope="module")
def runs(studies):
    out = {}
    for key, section in (("without", None), ("with", TAKEUP_FRICTION_EDGES)):
        study, plan, case = _takeup(studies, section)
        case = dy.with_changes(case, t_end=2.0)
        out[key] = (study, plan, case, dy.integrate(plan, study.mechanism, case))
    return out


def test_the_run_up_with_friction_is_accurate_and_implicit(runs):
    study, plan, case, res = runs["with"]
    assert res.status == kc.OK, res.summary()
    assert res.error_phi1 <= dy.ACCEPTED_ERROR_RAD
    forces = case_forces(study.mechanism, plan, res)["samples"]
    m1 = float(case.M1.evaluate(0.0, 0.0))
    drive = m1 - case.damping * res.omega1
    fr = forces.forces.friction
    assert fr is not None and (fr.status == kc.OK).all()
    moving = np.abs(res.omega1) > 0.0
    scale = np.abs(forces.forces.M_bal) + np.abs(drive) + np.abs(fr.M_bal_frictionless)
    gap = np.abs(forces.forces.M_bal - drive)[moving]
    assert (gap <= IMPLICIT_REL * scale[moving]).all(), gap.max()
    # the friction is there: without it the same motion asks less of the shaft
    assert (forces.forces.M_bal[moving] > fr.M_bal_frictionless[moving]).mean() > 0.9
    _, _, _, plain = runs["without"]
    assert (res.omega1[1:] < plain.omega1[1:]).all()


def _space_mean(orbit):
    w = orbit.periodic(0.0)
    y, h = w, orbit.h
    return h / 3 * (y[0] + y[-1] + 4 * y[1:-1:2].sum() + 2 * y[2:-1:2].sum()) / (2 * math.pi)


def test_steady_speed_and_flywheel_against_the_energy_balance(studies):
    """b 2 pi mean_theta |omega| = the drive's work per revolution, so the mean
    falls by the friction's work per revolution (Simpson on the orbit's own
    samples, as its RK4 integrates them) over 2 pi b."""
    plain, plan0, case0 = _takeup(studies)
    fric, plan1, case1 = _takeup(studies, TAKEUP_FRICTION_EDGES)
    o0 = _Orbit(plan0, plain.mechanism, case0)
    o1 = _Orbit(plan1, fric.mechanism, case1)
    assert (o1.friction >= 0).all() and o1.friction.max() > 0
    h = o1.h / 2
    work = h / 3 * (o1.friction[0] + o1.friction[-1] + 4 * o1.friction[1:-1:2].sum()
                    + 2 * o1.friction[2:-1:2].sum())
    drop = _space_mean(o0) - _space_mean(o1)
    assert drop > 0
    assert drop == pytest.approx(work / (2 * math.pi * case1.damping), rel=ENERGY_REL)
    # the friction is taken at the steady rotation's own mean speed
    assert _space_mean(o1) == pytest.approx(o1.friction_speed, rel=ENERGY_REL)
    f0 = size_flywheel(plan0, plain.mechanism, case0, 0.02)
    f1 = size_flywheel(plan1, fric.mechanism, case1, 0.02)
    assert f1.delta == pytest.approx(0.02, rel=1e-9) and f0.delta == pytest.approx(0.02, rel=1e-9)
    assert f1.J_add > f0.J_add and abs(f1.omega_mean) < abs(f0.omega_mean)


def test_relative_speed_slopes_are_the_derivatives_of_the_speeds(studies):
    """The slopes the integrator reads a relative speed's double switch from
    (``relative_speed_slopes``, from the second analogs) against a central
    difference of the relative speed analogs (the take-up: joints, the needle
    bar on the frame and the block in the turning coulisse)."""
    from pipeline.kernels.friction import relative_speed_slopes, relative_speeds
    from pipeline.solve.scene import solve_curves
    _, plan, _ = _takeup(studies)
    step = 1e-5
    phi = np.linspace(0.1, 2 * math.pi, 40)
    ne = len(plan.joint_names) + len(plan.slide_names)
    args = (plan.body_com, plan.body_turn, plan.joint_bodies, plan.slide_bodies, plan.slide_dir,
            plan.slide_angle)
    for p in phi:
        c = solve_curves(plan, np.array([p - step, p, p + step]), kc.ACCELERATIONS)
        v = np.empty((3, ne))
        for k in range(3):
            relative_speeds(c.pos[k], c.d1[k], c.d2[k], *args, v[k])
        slope = np.empty(ne)
        relative_speed_slopes(c.pos[1], c.d1[1], c.d2[1], *args, slope)
        fd = (v[2] - v[0]) / (2 * step)
        np.testing.assert_allclose(slope, fd, rtol=1e-6, atol=1e-6 * np.abs(v).max())
