"""The shaking force and moment on the frame (kernels.forces.shaking, computed
with a scene's reactions) and the crank's counterweight (solve.shaking).

* The shaking force is minus the rate of change of the moving links' total
  momentum and the moment minus that of their angular momentum about the
  crank's pivot, both by finite differences in time of the centres'
  velocities (tests/support/momentum.py), on every shipped force scene; and,
  for mechanism B, against naive.py's own kinematics.
* The counterweight lowers the peak |shaking force| to the value it reports:
  the scene re-run with the counterweight fixed to the crank (its body) has
  that peak, position by position the reported force; and no small change
  of the counterweight lowers the peak (the problem is convex: a local
  minimum is the minimum).
* The results file, the summary, the peaks and reactions.csv carry it, with
  units and long names."""

import cmath

import h5py
import numpy as np
import pandas as pd
import pytest

import pipeline
from pipeline.cli import main
from support import naive
from support.momentum import momentum_rates, with_counterweight
from support.tolerances import ANALOG_REL, COUNTERWEIGHT_REL, SHAKING_FD_REL
from pipeline.runner import peak_summary
from pipeline.solve.scene import run_scene
from pipeline.solve.shaking import minimax_weight, scene_counterweight
from pipeline.study.reader import load_study

FORCE_SCENES = ("ov7_class3", "warp_feed_fourbar", "ov7_class3_slider", "feed_fivebar",
                "cam_rocker_input", "actuator_slider_input", "scotch_yoke_rpp",
                "ppr_cross_slide", "slotted_rocker_prp")
# dense positions checked: away from the inputs' law breakpoints (a table's knots every
# 30 deg, a cam law's ends at 0 and 150 deg), where the jerk jumps and no finite
# difference converges (7e-4 at phi1 = 0)
AT = (41, 133, 197, 287)


@pytest.fixture(scope="module")
def scenes(studies):
    return {}


def _scene(scenes, studies, name):
    if name not in scenes:
        scenes[name] = run_scene(load_study(studies / f"{name}.toml"))
    return scenes[name]


@pytest.mark.parametrize("name", FORCE_SCENES)
def test_shaking_is_minus_the_rate_of_change_of_momentum(scenes, studies, name):
    res = _scene(scenes, studies, name)
    fr = res.dense.forces
    F, M = fr.shaking[:, :2], fr.shaking[:, 2]
    assert fr.shaking_about == res.study.mechanism.crank.pivot
    # the moment relative to its peak, or where that is 0 (the Scotch yoke's, about
    # its pivot: 9e-18 N*m) to the peak force times the centres' reach from the pivot
    com = res.dense.pos[:, res.plan.body_com] - res.dense.pos[:, None, res.plan.crank_pivot]
    reach = np.hypot(com[..., 0], com[..., 1]).max() / 1000.0
    f_scale, m_scale = np.hypot(F[:, 0], F[:, 1]).max(), np.abs(M).max()
    if m_scale < 1e-9 * f_scale * reach:
        m_scale = f_scale * reach
    assert f_scale > 0 and m_scale > 0
    worst_f = worst_m = 0.0
    for k in AT:
        dp, dh = momentum_rates(res.study, res.plan, res.dense.phi, k)
        worst_f = max(worst_f, np.hypot(*(F[k] - dp)) / f_scale)
        worst_m = max(worst_m, abs(M[k] - dh) / m_scale)
    print(f"\n{name}: shaking force {worst_f:.2g}, moment {worst_m:.2g} (relative to the "
          f"peaks {f_scale:.6g} N, {m_scale:.6g} N*m)")
    assert worst_f <= SHAKING_FD_REL and worst_m <= SHAKING_FD_REL, (worst_f, worst_m)


def test_shaking_force_of_mechanism_b_against_naive(scenes, studies):
    """naive.py's own positions (fsolve) and 8th-order finite-difference second
    analogs of the centres of mass: F = -sum m S'' omega1^2 / 1000."""
    res = _scene(scenes, studies, "ov7_class3")
    w1 = res.study.mechanism.crank.omega1
    F = res.dense.forces.shaking[:, :2]
    scale = np.hypot(F[:, 0], F[:, 1]).max()
    for k in (0, 100, 250):
        ref = naive.mech_b_analogs(res.dense.phi[k], with_S=True)
        want = -sum(m * ref["d2"]["S_" + name] for name, (*_, m, _J) in naive.B_MASS.items())
        want = want * w1 ** 2 / 1000.0
        assert np.hypot(*(F[k] - want)) / scale <= ANALOG_REL


@pytest.mark.parametrize("name", ["ov7_class3", "warp_feed_fourbar"])
def test_the_counterweight_gives_the_peak_it_reports(scenes, studies, name):
    res = _scene(scenes, studies, name)
    cw = scene_counterweight(res)
    mag = res.dense.forces.shaking_magnitude
    assert cw.before == mag.max() and cw.after < cw.before
    after = np.hypot(cw.force_after[:, 0], cw.force_after[:, 1])
    assert cw.after == after.max()
    print(f"\n{name}: counterweight {cw.mass_radius:.6g} kg*mm at {cw.angle:.4f} deg: peak "
          f"{cw.before:.6g} N (phi1 = {cw.before_phi1:g}) -> {cw.after:.6g} N "
          f"(phi1 = {cw.after_phi1:g})")
    # the scene with the counterweight on the crank: its shaking force is the reported one
    for radius in (None, 100.0):      # only m_c r_c matters (a uniform crank)
        study = with_counterweight(res.study, cw.mass_radius, cw.angle, radius)
        balanced = run_scene(study)
        got = balanced.dense.forces
        np.testing.assert_allclose(got.shaking[:, :2], cw.force_after, rtol=0,
                                   atol=COUNTERWEIGHT_REL * cw.after)
        assert got.shaking_magnitude.max() == pytest.approx(cw.after, rel=COUNTERWEIGHT_REL)
        # the moment about the crank's pivot is the same: pulled along the radius
        np.testing.assert_allclose(got.shaking[:, 2], res.dense.forces.shaking[:, 2], rtol=0,
                                   atol=COUNTERWEIGHT_REL * np.abs(got.shaking[:, 2]).max())
        again = scene_counterweight(balanced)
        assert again.before == pytest.approx(cw.after, rel=COUNTERWEIGHT_REL)
        assert again.mass_radius <= 1e-6 * cw.mass_radius     # nothing more to balance
    # no small change of the counterweight lowers the peak (convex: the minimum)
    crank = res.study.mechanism.crank
    ip, it = res.plan.point(crank.pivot), res.plan.point(crank.tip)
    a = (res.dense.d2[:, it] - res.dense.d2[:, ip]) * crank.omega1 ** 2 / 1000.0
    A = a[:, 0] + 1j * a[:, 1]
    Fc = res.dense.forces.shaking[:, 0] + 1j * res.dense.forces.shaking[:, 1]
    w = cw.mass_radius / crank.length * cmath.exp(1j * np.radians(cw.angle))
    for step in (1e-3, 1e-6):
        for t in np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False):
            moved = w * (1.0 + step * cmath.exp(1j * t))
            assert np.abs(Fc - moved * A).max() >= cw.after * (1.0 - 1e-12), (step, t)


def test_minimax_weight_of_a_known_problem():
    """F_k = c + e^(i theta_k) (a constant plus a rotating vector), A_k = e^(i
    theta_k): the rotating part is cancelled exactly by w = 1 and |c| is left;
    with a second harmonic on top, max |F - w A| can only fall to the second
    harmonic's amplitude plus |c|, reached at w = 1."""
    th = np.linspace(0.0, 2.0 * np.pi, 360, endpoint=False)
    A = np.exp(1j * th)
    w = minimax_weight(0.3 + A, A)
    assert abs(w - 1.0) < 1e-9
    F = 0.3 + (2.0 - 1.0j) * A + 0.5 * np.exp(2j * th)
    w = minimax_weight(F, A)
    assert np.abs(F - w * A).max() == pytest.approx(0.8, rel=1e-9)
    assert abs(w - (2.0 - 1.0j)) < 1e-6


def test_the_results_file_the_summary_and_the_tables_carry_it(studies, tmp_path):
    out = pipeline.run(studies / "warp_feed_fourbar.toml", tmp_path / "d.h5")
    assert out.results.with_name("d_shaking.png").exists()
    res = pipeline.solve_scene(studies / "warp_feed_fourbar.toml")
    cw = res.counterweight
    lines = peak_summary(res)
    assert lines["peak_shaking_force"].endswith(" deg") and " N at phi1 = " in \
        lines["peak_shaking_force"]
    assert " N·m about P1 at phi1 = " in lines["peak_shaking_moment"]
    assert f"{cw.before:.6g} N" in lines["counterweight"] and f"{cw.after:.6g} N" in \
        lines["counterweight"] and lines["counterweight"].startswith(f"{cw.mass_radius:.6g} kg·mm")
    assert out.summary["counterweight"] == lines["counterweight"]
    with h5py.File(out.results, "r") as f:
        d = f["dense"]
        for key, units in (("shaking_force", "N"), ("shaking_force_magnitude", "N"),
                           ("shaking_moment", "N·m")):
            assert d[key].attrs["units"] == units and d[key].attrs["long_name"], key
            assert d[key].dims[0][0].name == "/dense/phi1", key
        np.testing.assert_array_equal(d["shaking_force"][()], res.dense.forces.shaking[:, :2])
        assert d["shaking_moment"].attrs["about"] == "P1"
        assert "shaking_force" in f["table"]
        g = f["counterweight"]
        for key, units in (("mass_radius", "kg·mm"), ("angle", "deg"), ("peak_before", "N"),
                           ("peak_after", "N"), ("peak_after_phi1", "deg"),
                           ("shaking_force", "N")):
            assert g[key].attrs["units"] == units and g[key].attrs["long_name"], key
        assert g["peak_after"][()] == cw.after and g["mass_radius"][()] == cw.mass_radius
        p = f["peaks"]
        assert p["shaking_force"].attrs["units"] == "N"
        assert p["shaking_force"].attrs["item"] == "frame"
        assert p["shaking_force_grid"][()] == cw.before
        assert p["shaking_force"][()] >= cw.before
        assert p["shaking_moment"].attrs["units"] == "N·m"
    tables = pipeline.open(out.results)
    r = tables["reactions"]
    np.testing.assert_array_equal(r["shaking_F"], res.dense.forces.shaking_magnitude)
    np.testing.assert_array_equal(r["shaking_M"], res.dense.forces.shaking[:, 2])
    assert r.attrs["units"]["shaking_Fx"] == "N" and r.attrs["units"]["shaking_M"] == "N·m"
    peaks = tables["peaks"].set_index("quantity")
    assert peaks.loc["shaking_force", "item"] == "frame"
    assert peaks.loc["M_bal", "item"] == "crank"
    assert tables["counterweight"]["peak_after"][0] == cw.after
    csv = tmp_path / "csv"
    assert main(["export", str(out.results), "--csv", str(csv), "-q"]) == 0
    head = pd.read_csv(csv / "reactions.csv").columns
    assert {"shaking_Fx [N]", "shaking_Fy [N]", "shaking_F [N]", "shaking_M [N·m]"} <= set(head)
    assert (csv / "counterweight.csv").exists()
