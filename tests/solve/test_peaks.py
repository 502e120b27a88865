"""Peaks refined between grid positions (issue 14 item 1): never below the
largest sample of a 100x finer revolution, and at its crank angle."""

import numpy as np
import pytest

import pipeline
from conftest import STUDIES
from pipeline.solve.reactions import scene_forces
from pipeline.solve.peaks import _magnitudes, scene_peaks
from pipeline.solve.scene import revolution_angles, solve_curves
from support import naive
from support.tolerances import DWELL_VS_NAIVE_REL

FINE = 100_000      # a brute-force revolution: 0.0036 deg steps


@pytest.mark.parametrize("name", ["ov7_base", "ov7_class3", "warp_feed_fourbar",
                                  "takeup_dynamics"])
def test_refined_peaks_match_a_100x_finer_revolution(studies, name):
    res = pipeline.solve_scene(studies / f"{name}.toml")
    peaks = scene_peaks(res)
    assert peaks
    # most peaks lie between two of the 360 grid positions, above the grid's sample
    between = [p for p in peaks if p.value > p.grid_value * (1 + 1e-12)
               and abs(p.phi1 * res.study.output.dense_positions / 360.0
                       - round(p.phi1 * res.study.output.dense_positions / 360.0)) > 1e-3]
    assert len(between) >= len([p for p in peaks if p.grid_value > 0]) // 2
    crank = res.study.mechanism.crank
    fine = solve_curves(res.plan, revolution_angles(crank, FINE), 2, res.tolerances)
    forces = scene_forces(res.study.mechanism, res.plan, fine) if res.dense.forces is not None \
        else None
    ref = _magnitudes(res.study, res.plan, fine, forces)
    step = 360.0 / FINE
    for p in peaks:
        if p.quantity == "min_transmission_angle":     # refined as the deviation from 90 deg
            dev = ref[("transmission_deviation", p.item, p.unit)]
            low = 90.0 - float(np.nanmax(dev))
            assert p.value <= p.grid_value and low - 1e-7 <= p.value <= low + 1e-12, (p, low)
            continue
        values = ref[(p.quantity, p.item, p.unit)]
        top = float(np.nanmax(values))
        assert p.value >= p.grid_value
        if top == 0.0:
            assert p.value == 0.0
            continue
        # at least the brute force's largest sample, and above it by no more than its
        # O(h^2) shortfall
        assert top * (1 - 1e-12) <= p.value <= top * (1 + 1e-7), (p, top)
        k = int(np.nanargmax(values))
        near = np.rad2deg(fine.phi[k])
        gap = abs((p.phi1 - near + 180.0) % 360.0 - 180.0)
        deg = np.rad2deg(fine.phi)
        away = np.abs((deg - near + 180.0) % 360.0 - 180.0) > 1.0
        second = float(np.nanmax(values[away])) if away.any() else 0.0
        if top - second > 1e-6 * top:       # no rival peak elsewhere: the same place
            assert gap <= 2 * step, (p, near)


def test_scene_summary_and_file_give_the_refined_peaks(studies, tmp_path, capsys):
    from pipeline.cli import main
    import h5py
    out = tmp_path / "b.h5"
    assert main(["run", str(studies / "ov7_class3.toml"), "-o", str(out), "--no-pictures"]) == 0
    text = capsys.readouterr().out
    assert "peak velocity P8:" in text and "peak acceleration P8:" in text
    with h5py.File(out, "r") as f:
        g = f["peaks"]
        assert (g["reaction"][()] >= g["reaction_grid"][()]).all()
        i = [x.decode() if isinstance(x, bytes) else x for x in f["point"][()]].index("P8")
        v = g["velocity"][i]
        assert f"peak velocity P8: {v:.6g} m/s" in text
        assert g["velocity"].dims[0][0].name == "/point"


def test_scene_dwell_and_stroke_equal_the_sweeps_reference_design(studies, synthesis_sweep):
    """Mechanism B as a scene (ov7_class3) and as the synthesis study's reference
    design: the same dwell error and stroke, by two paths."""
    import h5py

    from pipeline.solve.peaks import scene_motion
    res = pipeline.solve_scene(studies / "ov7_class3.toml")
    m = scene_motion(res)
    with h5py.File(synthesis_sweep, "r") as f:
        ref_dwell = float(f["reference/dwell_error"][0])
        ref_stroke = float(f["reference/stroke"][0])
    assert m["dwell_error"] == pytest.approx(ref_dwell, rel=1e-9)
    assert m["stroke"] == pytest.approx(ref_stroke, rel=1e-9)
    # naive.py's fsolve revolution at the same 360 positions (DOMAIN.md section 9 gives
    # 0.0712 at 720 positions: naive.py's self-check holds that one)
    dwell, _, stroke = naive.naive_mech_b_motion(360)
    assert m["dwell_error"] == pytest.approx(dwell, rel=DWELL_VS_NAIVE_REL)
    assert m["stroke"] == pytest.approx(stroke, rel=DWELL_VS_NAIVE_REL)


def test_transmission_angle_of_a_dyad_by_hand(studies):
    """The first dyad's transmission angle at its refined minimum, from the
    positions by the cosine law (an independent formula)."""
    res = pipeline.solve_scene(studies / "ov7_base.toml")
    p = [q for q in scene_peaks(res) if q.quantity == "min_transmission_angle"][0]
    g = [x for x in res.study.mechanism.groups if hasattr(x, "L_AB")][0]
    c = solve_curves(res.plan, np.array([res.dense.phi[0], np.radians(p.phi1)]), 0,
                     res.tolerances)
    A, B, C = (c.pos[-1, res.plan.point_names.index(n)] for n in (g.A, g.B, g.C))
    ab, cb, ac = np.linalg.norm(A - B), np.linalg.norm(C - B), np.linalg.norm(A - C)
    mu = np.degrees(np.arccos((ab ** 2 + cb ** 2 - ac ** 2) / (2 * ab * cb)))
    assert min(mu, 180 - mu) == pytest.approx(p.value, abs=1e-9)


def test_pin_sizing_is_set_per_study_and_per_joint(studies, tmp_path, capsys):
    """[output.pins]: length and allowable stress for every pin, and per joint;
    the stored d_min follows d = (32 R l / (pi sigma))^(1/3)."""
    import h5py

    from pipeline.cli import main
    text = (studies / "ov7_class3.toml").read_text().replace(
        "[output]\n", "[output]\npins = { length = 12.0, sigma = 150.0, R2 = { length = 20.0 } }\n", 1)
    study = tmp_path / "pins.toml"
    study.write_text(text)
    out = tmp_path / "p.h5"
    assert main(["run", str(study), "-o", str(out), "--no-pictures"]) == 0
    assert "(12 mm, 150 MPa)" in capsys.readouterr().out
    with h5py.File(out, "r") as f:
        g = f["peaks"]
        names = [x.decode() if isinstance(x, bytes) else x for x in f["joint"][()]]
        L, S, R, D = (g[k][()] for k in ("pin_length", "pin_sigma", "reaction", "pin_d_min"))
    assert L[names.index("R2")] == 20.0 and L[names.index("R1")] == 12.0 and (S == 150.0).all()
    np.testing.assert_allclose(D, np.cbrt(32 * R * L / (np.pi * S)), rtol=1e-14)
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("R2 = { length", "R99 = { length"))
    assert main(["run", str(bad), "-o", str(tmp_path / "b.h5"), "-q"]) == 2
    assert "output.pins.R99: unknown joint" in capsys.readouterr().err


def test_a_positions_only_scene_has_the_peaks_positions_give(studies, tmp_path):
    """analysis = "positions": no analogs, so no velocity or acceleration peaks;
    the transmission angles (positions only) are still refined (this scene
    once stopped with numpy's 'All-NaN slice')."""
    text = (studies / "ov7_base.toml").read_text()
    lines = [('analysis = "positions"' if ln.startswith("analysis =") else ln)
             for ln in text.splitlines()]
    assert 'analysis = "positions"' in lines
    path = tmp_path / "positions.toml"
    path.write_text("\n".join(lines) + "\n")
    res = pipeline.solve_scene(pipeline.load_study(path))
    kinds = {p.quantity for p in res.peaks}
    assert kinds == {"min_transmission_angle"}, kinds
    assert all(np.isfinite(p.value) for p in res.peaks)


@pytest.mark.parametrize("name", ["ov7_friction", "takeup_dynamics", "ppr_cross_slide"])
def test_one_quantitys_magnitudes_are_those_among_all(studies, name):
    """A refined peak's trial angle computes its own quantity
    (``_magnitudes(..., quantity)``): the same arrays to the bit as among every
    quantity's, and no force or transmission angle for a quantity of the motion,
    for each quantity of a scene with friction, slides and dynamics."""
    from pipeline.solve.peaks import FORCE_PEAKS, MOTION_PEAKS
    from pipeline.study.reader import load_study
    study = load_study(studies / f"{name}.toml")
    res = pipeline.solve_scene(studies / f"{name}.toml")
    dense = res.dense
    every = _magnitudes(study, res.plan, dense, dense.forces)
    quantities = {k[0] for k in every}
    assert {"velocity", "transmission_deviation", "reaction"} <= quantities
    for q in quantities:
        assert q in MOTION_PEAKS + FORCE_PEAKS + ("transmission_deviation",), q
        # (as scene_peaks asks: the forces for a quantity of theirs only)
        own = _magnitudes(study, res.plan, dense, dense.forces if q in FORCE_PEAKS else None, q)
        assert {k for k in every if k[0] == q} <= set(own), q
        if q not in FORCE_PEAKS:        # nothing but the motion's, or the angle asked for
            assert {k[0] for k in own} <= set(MOTION_PEAKS + (q,)), q
        for k, v in own.items():
            assert np.array_equal(*(np.ascontiguousarray(x).view(np.uint8)
                                    for x in (v, every[k]))), k


SCENES = sorted(p.stem for p in STUDIES.glob("*.toml")
                if 'kind = "scene"' in p.read_text(encoding="utf-8"))


@pytest.mark.parametrize("name", SCENES)
def test_a_trial_angles_walk_from_the_position_before_is_the_walk_from_the_start(studies,
                                                                                  name):
    """A refined peak's trial angle is walked on from the dense position before it
    (``Continuation``: the state kept there) in one step: every number of the row
    the same to the bit as the walk from the revolution's first position through
    every position before, in every shipped scene (class III groups, slides, input
    laws); trial angles inside a step, across two, and at the revolution's end."""
    from pipeline.kernels import config as kc
    from pipeline.solve.scene import Continuation
    from pipeline.study.reader import load_study
    study = load_study(studies / f"{name}.toml")
    plan = study.mechanism.compile()
    phis = revolution_angles(study.mechanism.crank, study.output.dense_positions)
    tols = kc.default_tolerances()
    resume = Continuation.of(plan, phis, 2, tols)
    assert resume is not None, "the shipped scenes are on the plan path"
    n, step = len(phis), phis[1] - phis[0]
    for m, frac in ((1, 0.37), (n // 3, 1.61), (n - 1, 0.5), (n, 0.999)):
        phi = phis[m - 1] + frac * step
        row = resume.row(m, phi)
        walked = solve_curves(plan, np.concatenate([phis[:m], [phi]]), 2, tols)
        assert row.status[0] == walked.status[-1] == kc.OK
        for f in ("phi", "pos", "d1", "d2", "status", "margin", "iterations", "links"):
            a, b = getattr(row, f)[0], getattr(walked, f)[-1]
            assert a.tobytes() == b.tobytes(), (m, f)
