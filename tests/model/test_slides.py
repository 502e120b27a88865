"""Prismatic pairs in a scene's outputs and the slider dyads' transmission
angles: each slide's normal force N, couple C and the point of action e = C/N
in reactions.csv, the HDF5 file and the peaks (against the kernel and the
Scotch yoke's closed form); the transmission angle of RRP, RPR, PRP and RPP
against hand computations, in the scene's peaks and the sweep's metric."""

import dataclasses
import math

import h5py
import numpy as np
import pandas as pd
import pytest

from pipeline.cli import main
from pipeline.solve.reactions import slide_action
from pipeline.kernels import config as kc
from pipeline.kernels import sweep as ks
from pipeline.group_types.rpp.model import RPP
from pipeline.model.mechanism import transmission_items
from pipeline.solve.peaks import _magnitudes, scene_peaks
from pipeline.runner import peak_summary
from pipeline.solve.scene_study import solve_scene
from pipeline.solve.scene import run_scene, solve_curves
from pipeline.results.storage import read_units
from pipeline.study.reader import load_study, parse_study
from pipeline.runs.sweep import build_problem
from pipeline.model.metric_catalogue import metric_values
from pipeline.study.sweep_spec import apply_design, parameter_rows
from pipeline.study.sampling import draw_checked
from support.tolerances import SWEEP_VS_SCENE_REL

CSV_REL = 1e-11          # CSV keeps 12 significant digits
CLOSED_FORM_REL = 1e-9   # kinetostatics against a closed form, relative to the largest term
PEAK_DEG = 1e-6          # a refined extreme against its closed form, deg


@pytest.fixture(scope="module")
def yoke_run(tmp_path_factory, studies):
    d = tmp_path_factory.mktemp("yoke")
    out = d / "yoke.h5"
    assert main(["run", str(studies / "scotch_yoke_rpp.toml"), "-o", str(out), "-q"]) == 0
    assert main(["export", str(out), "--csv", str(d / "csv"), "-q"]) == 0
    return load_study(studies / "scotch_yoke_rpp.toml"), out, d / "csv"


# ------------------------------------------------------------------ slide forces in the exports
def test_reactions_csv_has_every_slide_as_the_kernel_gives_it(yoke_run):
    """N, C and e per slide, with units, between the joints and the shaking
    force and moment, the equilibrium residual and M_bal; the rows equal the HDF5
    datasets and the kinetostatics kernel on the dense curves."""
    study, out, csv = yoke_run
    r = pd.read_csv(csv / "reactions.csv")
    assert list(r.columns) == ["phi1 [deg]", "R1 (ground / crank at P1) x [N]",
                               "R1 (ground / crank at P1) y [N]", "R1 (ground / crank at P1) [N]",
                               "R2 (crank / block at P2) x [N]", "R2 (crank / block at P2) y [N]",
                               "R2 (crank / block at P2) [N]", "N[block] [N]", "C[block] [N·m]",
                               "e[block] [mm]", "N[yoke] [N]", "C[yoke] [N·m]",
                               "e[yoke] [mm]", "shaking_Fx [N]", "shaking_Fy [N]",
                               "shaking_F [N]", "shaking_M [N·m]", "equilibrium_residual [1]",
                               "M_bal [N·m]"]
    res = run_scene(study)
    fr = res.dense.forces
    assert fr.slide_names == ("slide[block]", "slide[yoke]")
    with h5py.File(out, "r") as f:
        d = f["dense/slide_reactions"]
        assert list(read_units(d)) == ["N", "N·m"]
        np.testing.assert_array_equal(d[()], fr.slide)
        a = f["dense/slide_action"]
        assert set(read_units(a)) == {"mm"} and "C/N" in str(a.attrs["long_name"])
        np.testing.assert_array_equal(a[()], slide_action(fr.slide))
        assert f["table/slide_action"].shape == (13, 2)
    for k, lab in enumerate(("block", "yoke")):
        for col, want in ((f"N[{lab}] [N]", fr.slide[:, k, 0]),
                          (f"C[{lab}] [N·m]", fr.slide[:, k, 1])):
            np.testing.assert_allclose(r[col].values, want, rtol=CSV_REL,
                                       atol=CSV_REL * np.abs(want).max())
    e = r["e[yoke] [mm]"].values
    np.testing.assert_allclose(e, 1000.0 * fr.slide[:, 1, 1] / fr.slide[:, 1, 0], rtol=CSV_REL)


def test_slide_forces_of_the_scotch_yoke_follow_from_statics(yoke_run):
    """The yoke (m = 0.35 kg, S 40 mm ahead of P3) moves x = L cos(phi1): the
    block in the vertical slot passes only a horizontal force, so
    N[block] = m a_x - fx (the load fx = -25 sign(sin phi1) at P4), the frame
    carries the yoke's weight and the load's fy = -5 N, N[yoke] = m g + 5, and
    the yoke's moments about S give C[yoke] = 0.04 * 5 + y2 N[block] / 1000
    (y2 = L sin phi1, the block's height); the block is pinned at its centre
    of mass and does not turn: C[block] = 0."""
    study, _, csv = yoke_run
    r = pd.read_csv(csv / "reactions.csv")
    phi = np.radians(r["phi1 [deg]"].values)
    m, L, w, g = 0.35, 12.0, study.mechanism.crank.omega1, study.mechanism.gravity
    n_block = m * (-L * w ** 2 * np.cos(phi) / 1000.0) + 25.0 * np.sign(np.sin(phi))
    scale = 67.0
    np.testing.assert_allclose(r["N[block] [N]"], n_block, atol=CLOSED_FORM_REL * scale)
    np.testing.assert_allclose(r["N[yoke] [N]"], m * g + 5.0, atol=CLOSED_FORM_REL * scale)
    c_yoke = 0.2 + L * np.sin(phi) * n_block / 1000.0
    np.testing.assert_allclose(r["C[yoke] [N·m]"], c_yoke, atol=CLOSED_FORM_REL * scale * 1e-3)
    np.testing.assert_allclose(r["e[yoke] [mm]"], 1000.0 * c_yoke / (m * g + 5.0),
                               rtol=1e-8)
    assert np.abs(r["C[block] [N·m]"]).max() <= CLOSED_FORM_REL * scale * 1e-3


def test_slide_peaks(yoke_run):
    """Peak |N| and |C| per slide in peaks.csv and the file's /peaks, and the
    run summary's largest slide force: |N[block]| = 0.35 * 1.2 |cos| + 25
    peaks at 67 N as phi1 -> 180 deg (the load flips sign there)."""
    study, out, csv = yoke_run
    p = pd.read_csv(csv / "peaks.csv")
    normal = p[p.quantity == "slide_normal"].set_index("item")
    couple = p[p.quantity == "slide_couple"].set_index("item")
    assert list(normal.index) == ["slide[block]", "slide[yoke]"] == list(couple.index)
    assert set(normal.unit) == {"N"} and set(couple.unit) == {"N·m"}
    assert normal.loc["slide[block]", "value"] == pytest.approx(67.0, rel=1e-9)
    assert normal.loc["slide[yoke]", "value"] == pytest.approx(0.35 * 9.81 + 5.0, rel=CSV_REL)
    assert (normal["value"] >= normal["grid_value"]).all()
    r = pd.read_csv(csv / "reactions.csv")
    assert couple.loc["slide[yoke]", "value"] >= np.abs(r["C[yoke] [N·m]"]).max()
    with h5py.File(out, "r") as f:
        assert "long_name" in f["peaks/slide_normal"].attrs
        assert [x.decode() if isinstance(x, bytes) else x
                for x in f["peaks/slide_normal"].dims[0][0][()]] == list(normal.index)
    res = solve_scene(study)
    assert peak_summary(res)["peak_slide_force"].startswith("67.0 N at slide[block]")


# ------------------------------------------------------------------ transmission angles
def _fold(deg):
    deg = np.mod(deg, 180.0)
    return np.minimum(deg, 180.0 - deg)


def test_prp_transmission_is_the_angle_between_the_guides(studies):
    """The slotted rocker's PRP: the slot along D->C against the horizontal
    frame guide.  On the grid: the rocker's angle folded; its smallest value,
    refined, at the rocker's far extreme (crank and coupler folded: |AC| =
    41 - 15), where the angle at D is arccos((38^2 + 40^2 - 26^2) / (2 38 40))."""
    study = load_study(studies / "slotted_rocker_prp.toml")
    items = {label: kind for label, kind, _ in transmission_items(study.mechanism)}
    assert items == {"P2-P3-P4": "dyad", "slider": "lines"}
    res = run_scene(study)
    grid = _magnitudes(study, res.plan, res.dense)
    r = res.dense.pos[:, res.plan.point("P3")] - res.dense.pos[:, res.plan.point("P4")]
    rocker = np.degrees(np.arctan2(r[:, 1], r[:, 0]))
    np.testing.assert_allclose(90.0 - grid[("transmission_deviation", "slider", "deg")],
                               _fold(rocker), atol=1e-10)
    peak = next(p for p in scene_peaks(res) if p.quantity == "min_transmission_angle"
                and p.item == "slider")
    hand = math.degrees(math.acos((38.0 ** 2 + 40.0 ** 2 - 26.0 ** 2) / (2 * 38.0 * 40.0)))
    assert peak.value == pytest.approx(hand, abs=PEAK_DEG)
    assert peak.value <= peak.grid_value


@pytest.mark.parametrize("slot_deg", [90.0, 60.0, 115.0])
def test_rpp_transmission_is_the_slot_against_the_guide(studies, slot_deg):
    """The Scotch yoke: the block pushes the yoke across the slot, the yoke
    moves along its guide: the slot's angle from the guide, folded, at every
    crank angle."""
    study = load_study(studies / "scotch_yoke_rpp.toml")
    m = study.mechanism
    groups = tuple(dataclasses.replace(g, slot_angle=math.radians(slot_deg))
                   if isinstance(g, RPP) else g for g in m.groups)
    study = dataclasses.replace(study, mechanism=dataclasses.replace(m, groups=groups))
    res = run_scene(study)
    mu = 90.0 - _magnitudes(study, res.plan, res.dense)[("transmission_deviation", "yoke", "deg")]
    np.testing.assert_allclose(mu, _fold(slot_deg), atol=1e-12)


def test_rrp_and_rpr_transmission_angles(studies):
    """The take-up's needle bar (RRP: crank l1 = 16.3, rod l2 = 44.2 on a
    vertical guide through the crank pivot): 90 deg minus the rod's angle
    from the guide, smallest with the crank across the guide, 90 - arcsin(l1/l2);
    its coulisse without offset (RPR): 90 deg throughout."""
    study = load_study(studies / "takeup_dynamics.toml")
    res = run_scene(study)
    grid = _magnitudes(study, res.plan, res.dense)
    P = {p: res.dense.pos[:, res.plan.point(p)] for p in ("P2", "P3")}
    rod = P["P3"] - P["P2"]
    from_guide = np.degrees(np.arctan2(np.abs(rod[:, 0]), np.abs(rod[:, 1])))
    np.testing.assert_allclose(90.0 - grid[("transmission_deviation", "needle bar", "deg")],
                               90.0 - from_guide, atol=1e-10)
    np.testing.assert_allclose(grid[("transmission_deviation", "coulisse", "deg")], 0.0,
                               atol=1e-10)
    peaks = {p.item: p for p in scene_peaks(res) if p.quantity == "min_transmission_angle"}
    assert peaks["needle bar"].value == pytest.approx(
        90.0 - math.degrees(math.asin(16.3 / 44.2)), abs=PEAK_DEG)


def test_the_sweeps_min_transmission_angle_covers_the_prp(studies):
    """The PRP sweep with min_transmission_angle: the generated kernels' value is
    the smaller of the four-bar's angle at C and the slot-guide angle over the
    grid, computed from each candidate's scene curves (the tilted guide:
    guide2_angle); with the guide tilted back the PRP's is the smaller one."""
    text = (studies / "slotted_rocker_prp_sweep.toml").read_text()
    old = 'metrics = ["peak_acceleration", "peak_reaction", "peak_M_bal", "stroke"]'
    assert old in text
    text = text.replace(old, old[:-1] + ', "min_transmission_angle"]').replace(
        "positions = 360", "positions = 72")
    study = parse_study(text, "prp_transmission.toml")
    pb = build_problem(study, study.sweep)
    x, _ = draw_checked(pb.spec, 0)
    x = x[:40]
    _, m = pb.evaluate_rows(np.ascontiguousarray(parameter_rows(pb.plan, pb.spec, x)))
    done = np.flatnonzero(m[:, ks.M_FORCES_DONE] == 1.0)
    assert len(done) >= 10
    prp_smaller = 0
    for i in done:
        mech = apply_design(study.mechanism, study.sweep, x[i])
        plan = mech.compile()
        c = solve_curves(plan, pb.phis, kc.POSITIONS)
        assert c.overall == kc.OK
        P = {p: c.pos[:, plan.point(p)] for p in ("P2", "P3", "P4")}
        u, w = P["P2"] - P["P3"], P["P4"] - P["P3"]
        at_c = np.degrees(np.arccos(np.abs((u * w).sum(1)) / (np.hypot(*u.T) * np.hypot(*w.T))))
        slot = np.degrees(np.arctan2(*(P["P3"] - P["P4"])[:, ::-1].T))
        prp = _fold(slot - x[i, 0])                     # x[:, 0]: the guide's tilt, deg
        want = min(at_c.min(), prp.min())
        assert metric_values(m, "min_transmission_angle")[i] == pytest.approx(want, abs=1e-9)
        prp_smaller += prp.min() < at_c.min()
    assert prp_smaller >= 3


@pytest.mark.parametrize("name", ["takeup_dynamics", "slotted_rocker_prp", "scotch_yoke_rpp"])
def test_the_generated_transmission_is_the_scenes(studies, name):
    """The generated kernels' smallest transmission angle (the sweep's) at every
    dense position equals the smallest of pipeline.peaks' per group: RRP and
    RPR (the take-up), PRP and RRR (the slotted rocker), RPP (the yoke)."""
    from pipeline.compiler import kernels_for
    study = load_study(studies / f"{name}.toml")
    res = run_scene(study)
    mod = kernels_for(res.plan)
    K = mod.constants(res.plan.par)
    got = np.degrees([mod.transmission(K, np.ascontiguousarray(p)) for p in res.dense.pos])
    grid = _magnitudes(study, res.plan, res.dense)
    want = np.min([90.0 - v for (q, _, _), v in grid.items() if q == "transmission_deviation"],
                  axis=0)
    np.testing.assert_allclose(got, want, atol=1e-12)


def test_a_slide_turns_with_its_guide_when_a_sweep_turns_the_guide(studies):
    """The PRP sweep turns the frame's guide (slider.guide2_angle); the slide
    written along it (absolute 0 deg) follows the guide's parameter, so a
    tilted candidate's forces are those of a study that declares the tilt in
    both places."""
    import dataclasses
    from pipeline.solve.reactions import scene_forces
    from pipeline.solve.scene import revolution_angles, solve_curves
    from pipeline.study.reader import load_study, parse_study
    study = load_study(studies / "slotted_rocker_prp.toml")
    m = study.mechanism
    assert m.slides[1].follows == ("slider.guide2_angle",)
    tilt = -20.0
    prp = dataclasses.replace(m.groups[1], guide2_angle=math.radians(tilt))
    swept = dataclasses.replace(m, groups=(m.groups[0], prp))          # as a sweep row does
    text = study.text.replace("guide2_angle = 0.0", f"guide2_angle = {tilt}")
    text = text.replace('guide = "ground"\nangle = 0.0', f'guide = "ground"\nangle = {tilt}')
    declared = parse_study(text, "tilted.toml").mechanism
    out = []
    for mech in (swept, declared):
        plan = mech.compile()
        c = solve_curves(plan, revolution_angles(mech.crank, 24), 2, close_at=2 * math.pi)
        out.append(scene_forces(mech, plan, c))
    # (a slide left at 0 deg gives M_bal 4.8 against 8.0 N*m at this tilt: the test can fail)
    for a, b in ((out[0].R, out[1].R), (out[0].slide, out[1].slide), (out[0].M_bal, out[1].M_bal)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * np.abs(b).max())
