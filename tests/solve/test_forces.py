"""Kinetostatics: virtual power, equilibrium against an independent dense solve,
the DOMAIN.md peak of mechanism B, pin sizing."""

import dataclasses
import math

import numpy as np
import pytest

from support import naive
from support.power import virtual_power
from pipeline.solve.reactions import pin_diameter, scene_forces
from pipeline.kernels import config as kc
from pipeline.solve.scene import revolution_angles, run_scene, solve_curves
from pipeline.study.reader import load_study
from support.tolerances import REACTION_FD_REL, VIRTUAL_POWER_REL


@pytest.mark.parametrize("name", ["ov7_class3", "warp_feed_fourbar"])
def test_virtual_power_identity_scenes(studies, name):
    study = load_study(studies / f"{name}.toml")
    res = run_scene(study)
    for curves in (res.table, res.dense):
        total, scale = virtual_power(study, res.plan, curves, curves.forces)
        assert np.isfinite(total).all()
        rel = np.abs(total) / scale
        assert rel.max() <= VIRTUAL_POWER_REL, f"{name}: {rel.max():.2e}"


def _perturbed_b(study, rng, spread=0.08):
    """Mechanism B with dimensions changed by up to +-spread and the DOMAIN.md
    section 9 mass model (m ~ L, J ~ L^3, lS ~ L)."""
    m = study.mechanism
    tri = m.groups[0]
    f = lambda: 1.0 + rng.uniform(-spread, spread)
    new = {k: getattr(tri, k) * f() for k in ("L23", "L34", "L45", "L35", "L46", "L57")}
    crank = dataclasses.replace(m.crank, length=m.crank.length * f(),
                                omega1=-97.2, eps1=rng.uniform(-500, 500))
    tri2 = dataclasses.replace(tri, **new)
    ratio = {"crank 1-2": crank.length / m.crank.length, "lead 2-3": new["L23"] / tri.L23,
             "ternary 3-4-5": new["L35"] / tri.L35, "lead 4-6": new["L46"] / tri.L46,
             "rocker 5-7-8": new["L57"] / tri.L57}
    bodies = tuple(dataclasses.replace(
        b, mass=b.mass * ratio[b.name], J_S=b.J_S * ratio[b.name] ** 3,
        com=dataclasses.replace(b.com, lS=b.com.lS * ratio[b.name])) for b in m.bodies)
    fixed = dict(m.fixed)
    fixed["P6"] = (fixed["P6"][0] * f(), fixed["P6"][1] * f())
    mech = dataclasses.replace(m, crank=crank, groups=(tri2,) + m.groups[1:], bodies=bodies,
                               fixed=fixed)
    return dataclasses.replace(study, mechanism=mech)


def test_virtual_power_identity_random_candidates(studies):
    base = load_study(studies / "ov7_class3.toml")
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(12):
        study = _perturbed_b(base, rng)
        plan = study.mechanism.compile()
        crank = study.mechanism.crank
        curves = solve_curves(plan, revolution_angles(crank, 72), kc.ACCELERATIONS,
                              close_at=crank.phi0 + crank.rot * 2 * math.pi)
        if curves.overall != kc.OK:
            continue
        fr = scene_forces(study.mechanism, plan, curves)
        total, scale = virtual_power(study, plan, curves, fr)
        assert (np.abs(total) / scale).max() <= VIRTUAL_POWER_REL
        checked += 1
    assert checked >= 8


def test_reactions_match_naive_dense_solve_b(studies):
    study = load_study(studies / "ov7_class3.toml")
    res = run_scene(study)
    t = res.table
    names = t.forces.joint_names
    assert names == ("R1", "R2", "R3", "R4", "R5", "R6", "R7")
    for k in (0, 2, 4, 7, 10):
        ref = naive.naive_forces_b(t.phi[k])
        scale = max(np.abs(ref[n]).max() for n in names)
        for j, n in enumerate(names):
            err = np.abs(t.forces.R[k, j] - ref[n]).max()
            assert err <= REACTION_FD_REL * scale, (k, n, err)
        assert abs(t.forces.M_bal[k] - ref["M_bal"]) <= REACTION_FD_REL * max(abs(ref["M_bal"]), 1)


def test_reactions_match_naive_dense_solve_d(studies):
    study = load_study(studies / "warp_feed_fourbar.toml")
    res = run_scene(study)
    t = res.table
    for k in range(0, 12, 3):
        ref = naive.naive_forces_d(t.phi[k])
        scale = max(np.abs(ref[n]).max() for n in ("R1", "R2", "R3", "R4"))
        for j, n in enumerate(t.forces.joint_names):
            assert np.abs(t.forces.R[k, j] - ref[n]).max() <= REACTION_FD_REL * scale, (k, n)
        assert abs(t.forces.M_bal[k] - ref["M_bal"]) <= REACTION_FD_REL * max(abs(ref["M_bal"]), 1)


def test_reactions_and_slide_forces_match_naive_dense_solve_c(studies):
    """The take-up (mechanism C, two slides: the needle bar on the frame, the
    block in the coulisse) at its scene speed and with eps1 != 0: every
    reaction, both slides' normal force and couple, and M_bal against
    naive.py's dense solve on its finite-difference kinematics."""
    base = load_study(studies / "takeup_dynamics.toml")
    for eps1 in (0.0, 300.0):
        mech = dataclasses.replace(base.mechanism, crank=dataclasses.replace(
            base.mechanism.crank, eps1=eps1))
        plan = mech.compile()
        c = solve_curves(plan, revolution_angles(mech.crank, 12), kc.ACCELERATIONS)
        fr = scene_forces(mech, plan, c)
        assert fr.joint_names == ("R1", "R2", "R3", "R4", "R5")
        assert fr.slide_names == ("slide[needle bar]", "slide[block]")
        for k in range(12):
            ref = naive.naive_forces_c(c.phi[k], omega1=mech.crank.omega1, eps1=eps1)
            scale = max(np.abs(ref[n]).max() for n in fr.joint_names + fr.slide_names)
            for j, n in enumerate(fr.joint_names):
                assert np.abs(fr.R[k, j] - ref[n]).max() <= REACTION_FD_REL * scale, (k, n)
            for j, n in enumerate(fr.slide_names):
                assert abs(fr.slide[k, j, 0] - ref[n][0]) <= REACTION_FD_REL * scale, (k, n)
                # a couple is a force times a lever: N*m against N at 1 mm
                assert abs(fr.slide[k, j, 1] - ref[n][1]) <= REACTION_FD_REL * scale * 1e-3, (k, n)
            assert abs(fr.M_bal[k] - ref["M_bal"]) <= REACTION_FD_REL * max(abs(ref["M_bal"]), 1)


def test_mechanism_b_peak_reaction(studies):
    """DOMAIN.md section 9: 1011.6 N in joint R1 at phi1 = -120 deg (omega1 = -94.4)."""
    res = run_scene(load_study(studies / "ov7_class3.toml"))
    peaks = res.dense.forces.peaks()
    name, rmax, phi, dmin = max(peaks, key=lambda r: r[1])
    assert (name, round(rmax, 1), round(phi, 9)) == ("R1", 1011.6, -120.0)
    assert dmin == pytest.approx((32 * rmax * 10 / (math.pi * 200)) ** (1 / 3), rel=1e-12)


def test_pin_diameter_formula():
    # 200 MPa, 10 mm: R = pi*200*d^3/320 gives back d
    for d in (3.0, 8.0, 12.5):
        assert pin_diameter(math.pi * 200 * d ** 3 / 320) == pytest.approx(d, rel=1e-12)


def test_gravity_only_static_balance(studies):
    """At omega1 -> 0 only gravity acts: M_bal equals minus the virtual work of
    gravity per radian, sum(m g dy_S/dphi) (an independent scalar check)."""
    study = load_study(studies / "warp_feed_fourbar.toml")
    mech = dataclasses.replace(study.mechanism, loads=(),
                               crank=dataclasses.replace(study.mechanism.crank, omega1=1e-9))
    plan = mech.compile()
    c = solve_curves(plan, np.linspace(0, 2 * math.pi, 13), kc.ACCELERATIONS)
    fr = scene_forces(mech, plan, c)
    expect = np.zeros(len(c.phi))
    for i in range(len(plan.body_names)):
        m = plan.par[plan.body_mass_off[i]]
        expect += m * 9.81 * c.d1[:, plan.body_com[i], 1] / 1000.0
    np.testing.assert_allclose(fr.M_bal, expect, rtol=1e-9, atol=1e-12)
