"""Kinematics of the two OV-7 scenes: reference tables, exact analogs against the
independent slow solver, closure residuals and link lengths."""

import math

import numpy as np
import pandas as pd
import pytest

from support import naive
from pipeline.kernels import config as kc
from pipeline.solve.scene import revolution_angles, run_scene, solve_curves
from pipeline.study.reader import load_study
from support.tolerances import (ANALOG_REL, CLOSURE_MM, NAIVE_POSITION_MM, NEWTON_ITERATIONS,
                                NEWTON_TOL,
                                REFERENCE_MM, SELF_FD_REL)

SCENES = {"ov7_base": "ov7_base_positions.csv", "ov7_class3": "ov7_class3_positions.csv"}


@pytest.fixture(scope="module", params=list(SCENES))
def scene(request, studies):
    study = load_study(studies / f"{request.param}.toml")
    return request.param, study, run_scene(study)


def test_reproduces_reference_tables(scene, reference_dir):
    name, study, res = scene
    ref = pd.read_csv(reference_dir / SCENES[name])
    np.testing.assert_allclose(np.rad2deg(res.table.phi), ref.phi1_deg.values, atol=1e-12)
    assert res.status == kc.OK
    assert (res.table.status == kc.OK).all()
    for col in ref.columns[1:]:
        point, axis = col.split("_")
        got = res.table.pos[:, res.plan.point(point), "xy".index(axis)]
        err = np.abs(got - ref[col].values)
        assert err.max() <= REFERENCE_MM, f"{name} {col}: max error {err.max():.2e} mm"


def _naive_analogs(name, phi):
    if name == "ov7_base":
        return naive.mech_a_analogs(phi)
    return naive.mech_b_analogs(phi)


def test_analogs_match_independent_solver(scene):
    """Exact first and second analogs against 8th-order finite differences of
    the fsolve solver (tests/support/naive.py), relative to each quantity's scale."""
    name, study, res = scene
    t = res.table
    worst = 0.0
    for k in range(0, len(t.phi) - 1, 2):
        ref = _naive_analogs(name, t.phi[k])
        for p, xy in ref["pos"].items():
            i = res.plan.point(p)
            np.testing.assert_allclose(t.pos[k, i], xy, rtol=0, atol=NAIVE_POSITION_MM)
            for mine, theirs in ((t.d1[k, i], ref["d1"][p]), (t.d2[k, i], ref["d2"][p])):
                scale = max(np.abs(theirs).max(), 1.0)
                err = np.abs(mine - theirs).max() / scale
                worst = max(worst, err)
                assert err <= ANALOG_REL, f"{name} {p} at {np.rad2deg(t.phi[k]):g} deg: {err:.2e}"
    assert worst > 0.0  # the comparison really ran on non-identical numbers


def test_link_angle_analogs_match_independent_solver(scene):
    name, study, res = scene
    t = res.table
    labels = study.output.link_labels
    for k in (0, 3, 7):
        if name == "ov7_base":
            ref = naive.fd_analogs(naive.mech_a_positions, t.phi[k], links=labels)
        else:
            ref = naive.mech_b_analogs(t.phi[k], links=labels)
        for j, lab in enumerate(labels):
            key = lab
            ang = ref["ang"][key]
            assert abs(math.remainder(t.links[k, j, 0] - ang, 2 * math.pi)) < 1e-9, lab
            for col, r in ((1, ref["ang_d1"][key]), (2, ref["ang_d2"][key])):
                assert abs(t.links[k, j, col] - r) <= ANALOG_REL * max(abs(r), 1.0), (lab, col)


def _link_lengths(study):
    from pipeline.group_types.rrr.model import RRR
    from pipeline.group_types.class3.model import ClassIII
    from pipeline.model.groups.attach import Attach
    out = [(study.mechanism.crank.pivot, study.mechanism.crank.tip, study.mechanism.crank.length)]
    for g in study.mechanism.groups:
        if isinstance(g, RRR):
            out += [(g.A, g.B, g.L_AB), (g.C, g.B, g.L_CB)]
        elif isinstance(g, ClassIII):
            p3, p4, p5 = g.joints
            out += [(g.input, p3, g.L23), (p3, p4, g.L34), (p4, p5, g.L45), (p3, p5, g.L35),
                    (g.pivot_4, p4, g.L46), (g.pivot_5, p5, g.L57)]
        elif isinstance(g, Attach):
            out += [(g.base, g.point, g.length)]
    return out


def test_closure_residuals_and_link_lengths(scene):
    name, study, res = scene
    d = res.dense
    for a, b, length in _link_lengths(study):
        ia, ib = res.plan.point(a), res.plan.point(b)
        dist = np.hypot(*(d.pos[:, ib] - d.pos[:, ia]).T)
        assert np.abs(dist - length).max() <= CLOSURE_MM, f"{name} {a}-{b}"


def test_velocity_is_derivative_of_position(scene):
    """In-product check independent of tests/support/naive.py: a central difference of
    the kernel's own positions reproduces its analogs."""
    name, study, res = scene
    plan = res.plan
    h = 1e-5
    phis = np.deg2rad([-17.0, -133.0, -251.0])
    for phi in phis:
        c = solve_curves(plan, np.array([phi - h, phi, phi + h]), kc.ACCELERATIONS)
        fd1 = (c.pos[2] - c.pos[0]) / (2 * h)
        fd2 = (c.pos[2] - 2 * c.pos[1] + c.pos[0]) / h ** 2
        nv = plan.n_visible
        s1 = np.abs(c.d1[1, :nv]).max()
        s2 = np.abs(c.d2[1, :nv]).max()
        assert np.abs(fd1[:nv] - c.d1[1, :nv]).max() <= SELF_FD_REL * s1
        assert np.abs(fd2[:nv] - c.d2[1, :nv]).max() <= 1e-4 * s2  # 2nd difference: rounding ~eps/h^2


def test_revolution_closes_and_positions_only_plan(scene):
    name, study, res = scene
    plan = res.plan
    crank = study.mechanism.crank
    phis = revolution_angles(crank, 72)
    c = solve_curves(plan, phis, kc.POSITIONS, close_at=crank.phi0 + crank.rot * 2 * math.pi)
    assert c.overall == kc.OK
    np.testing.assert_allclose(c.pos, res.dense.pos[::5], atol=1e-9)
    assert np.isnan(c.d1).all() and np.isnan(c.d2).all()  # positions only: nothing else computed


def test_class3_margin_and_iterations(studies):
    res = run_scene(load_study(studies / "ov7_class3.toml"))
    g = res.plan.group_names.index("triad")
    margin = res.dense.margin[:, g].min()
    assert abs(margin - naive.naive_mech_b_margin(360)[0]) < 1e-9
    assert round(margin, 2) == 0.93
    assert res.dense.iterations.max() <= 6


# mechanisms C and D (DOMAIN.md sections 7 and 8): naive.py's names -> the studies'
NAIVE_CD = {
    "takeup_dynamics": (naive.mech_c_analogs, {p: p for p in ("P2", "P3", "P4", "P7")},
                        {"S1": "S[crank]", "S2": "S[rod]", "S3": "S[needle bar]",
                         "S4": "S[block]", "S5": "S[coulisse]"}),
    "warp_feed_fourbar": (naive.mech_d_analogs, {p: p for p in ("P2", "P3", "P5")}, {}),
}


@pytest.mark.parametrize("name", list(NAIVE_CD))
def test_mechanisms_c_and_d_match_the_independent_solver(studies, name):
    """The take-up (C) and the four-bar (D) at their table positions: every
    moving point (and C's centres of mass) and every tabulated link's angle,
    with both analogs, against naive.py's closed forms differentiated by
    8th-order finite differences."""
    study = load_study(studies / f"{name}.toml")
    res = run_scene(study)
    analogs, points, coms = NAIVE_CD[name]
    t = res.table
    labels = study.output.link_labels
    assert len(t.phi) == 13 and len(labels) == 3
    for k in range(len(t.phi) - 1):
        ref = analogs(t.phi[k], links=labels)
        for theirs, mine in list(points.items()) + list(coms.items()):
            i = res.plan.point(mine)
            np.testing.assert_allclose(t.pos[k, i], ref["pos"][theirs], rtol=0,
                                       atol=NAIVE_POSITION_MM, err_msg=mine)
            for got, want in ((t.d1[k, i], ref["d1"][theirs]), (t.d2[k, i], ref["d2"][theirs])):
                err = np.abs(got - want).max() / max(np.abs(want).max(), 1.0)
                assert err <= ANALOG_REL, (name, mine, np.rad2deg(t.phi[k]), err)
        for j, lab in enumerate(labels):
            assert abs(math.remainder(t.links[k, j, 0] - ref["ang"][lab], 2 * math.pi)) < 1e-12, lab
            for col, r in ((1, ref["ang_d1"][lab]), (2, ref["ang_d2"][lab])):
                assert abs(t.links[k, j, col] - r) <= ANALOG_REL * max(abs(r), 1.0), (lab, col)


def test_newton_takes_two_steps_per_position(studies):
    """The README's Newton figure: at the default tolerance (1e-12 of the lead
    lengths) mechanism B's continuation takes 2 Newton steps per position."""
    res = run_scene(load_study(studies / "ov7_class3.toml"))
    assert res.tolerances[kc.T_NEWTON_TOL] == NEWTON_TOL
    assert res.dense.iterations.mean() == pytest.approx(NEWTON_ITERATIONS, abs=0.01)
