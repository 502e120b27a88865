"""Friction on the paths beyond a scene's run (issue 52): an adaptive search
minimises the friction loss (a sweep's: tests/runs/test_sweep_friction.py); a
tolerance analysis of a design with friction has its force metrics with friction
and the friction's own; `pipeline compare` of scene files shows their friction (the mean
loss, the largest peak p*v) and says where the designs differ in it; a sweep's
design re-run as a scene (show --candidate, the report) keeps its friction."""

import re

import h5py
import numpy as np
import pytest

from pipeline.cli import main

FRICTION = """[mechanism.friction]
revolute = 0.08
pin_diameter = 10.0
pin_length = 12.0
"""


def with_friction(text, section=FRICTION):
    assert "[output]" in text
    return text.replace("[output]", section + "\n[output]", 1)


def error_line(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in err[0], err
    return err[0]


# ------------------------------------------------------------------ a search
def test_an_adaptive_search_with_friction_minimises_the_loss(studies, tmp_path):
    """A search with [mechanism.friction] and friction_loss as an objective runs
    (its generations through the sweep's evaluator, friction stage included)
    and stores the loss of every design that reached the force stage."""
    text = with_friction((studies / "ov7_search.toml").read_text())
    for old, new in (("population = 100 ", "population = 16 "),
                     ("evaluations = 20000 ", "evaluations = 32 ")):
        assert old in text
        text = text.replace(old, new, 1)
    text = re.sub(r'(?m)^objectives = .*$', 'objectives = ["dwell_error", "friction_loss"]',
                  text, count=1)
    study = tmp_path / "search_friction.toml"
    study.write_text(text)
    out = tmp_path / "out.h5"
    assert main(["run", str(study), "-o", str(out), "-q"]) == 0
    with h5py.File(out, "r") as f:
        loss = f["metrics/friction_loss"][()]
        forces = f["candidates/forces_evaluated"][()]
        st = f["candidates/status"][()]
        assert len(loss) == 32 and forces.any()
        ok = forces & (st == 0)
        assert np.isfinite(loss[ok]).all() and (loss[ok] > 0).all()
        assert np.isnan(loss[~forces]).all()


@pytest.fixture(scope="module")
def scenes(studies, tmp_path_factory):
    """Scene files: mechanism B with friction (ov7_friction), with half its
    coefficient, and without friction (ov7_class3)."""
    d = tmp_path_factory.mktemp("friction_scenes")
    half = d / "half.toml"
    text = (studies / "ov7_friction.toml").read_text()
    assert "revolute = 0.08 " in text
    half.write_text(text.replace("revolute = 0.08 ", "revolute = 0.04 ", 1))
    out = {}
    for key, study in (("full", studies / "ov7_friction.toml"), ("half", half),
                       ("none", studies / "ov7_class3.toml")):
        out[key] = d / f"{key}.h5"
        assert main(["run", str(study), "-o", str(out[key]), "-q", "--no-pictures"]) == 0
    return out


def test_tolerance_of_a_friction_design_is_with_friction(studies, tmp_path, capsys):
    """A tolerance analysis of mechanism B with friction: the design's own
    peak_reaction, peak_M_bal, friction_loss and peak_pv are those of the
    kinetostatics with friction on the scene's grid (``solve.friction``, reduced
    in numpy here), every build carries them; a friction metric asked of a
    frictionless design is refused in one line."""
    from dataclasses import replace

    from pipeline.kernels import config as kc
    from pipeline.runs.tolerance import analyse
    from pipeline.solve.friction import solve_positions
    from pipeline.solve.reactions import sample_loads
    from pipeline.solve.scene import revolution_angles, solve_curves
    from pipeline.study.reader import load_study
    from pipeline.study.tolerance_spec import ToleranceSpec
    study = load_study(studies / "ov7_friction.toml")
    mech = study.mechanism
    names = ("peak_reaction", "peak_M_bal", "friction_loss", "peak_pv")
    spec = replace(ToleranceSpec(), metrics=names, samples=16)
    res = analyse(study, mech, spec)
    plan = mech.compile()
    phi = revolution_angles(mech.crank, study.output.dense_positions)
    c = solve_curves(plan, phi, kc.ACCELERATIONS)
    R, _, M, _, fric, speed, found = solve_positions(plan, mech.friction, c.pos, c.d1, c.d2,
                                                     mech.crank.omega1, mech.crank.eps1,
                                                     sample_loads(mech, phi))
    assert (found[:, 0] == kc.OK).all()
    nj = len(plan.joint_names)
    r = np.hypot(R[..., 0], R[..., 1])
    d = np.asarray(mech.friction.diameters(), float)
    pv = r / (d * np.asarray(mech.friction.lengths(), float)) \
        * np.abs(speed[:, :nj] * mech.crank.omega1) * d * 0.5e-3
    loss = (-fric * speed * mech.crank.omega1).sum(axis=1)     # (no slides)
    want = {"peak_reaction": r.max(), "peak_M_bal": np.abs(M).max(),
            "friction_loss": loss.mean(), "peak_pv": pv.max()}
    for k, name in enumerate(res.metrics):
        if name in want:
            assert res.nominal[k] == pytest.approx(want[name], rel=1e-11), name
            ok = res.status == kc.OK
            assert np.isfinite(res.values[ok, k]).all() and ok.any()
    out = tmp_path / "t.h5"
    capsys.readouterr()
    source = studies / "ov7_class3.toml"
    assert main(["tolerance", str(source), "-o", str(out), "--samples", "16", "--no-pictures",
                 "-q", "--metrics", "stroke,friction_loss"]) == 2
    line = error_line(capsys)
    assert line.startswith(f"pipeline tolerance: error: {source}: ") and "friction_loss needs "\
        "friction in the joints" in line and not out.exists()


# ------------------------------------------------------------------ compared
def _friction_of(path):
    with h5py.File(path, "r") as f:
        g = f["friction"]
        pv = g["peak_pv"][()]
        j = int(np.argmax(pv))
        return (float(g["mean_loss"][()]), float(pv[j]), float(g["peak_pv_phi1"][j]),
                f["joint"].asstr()[j])


def test_compare_shows_the_friction_of_scene_files(scenes):
    from pipeline.analysis.compare import compare_files
    cmp = compare_files([scenes["full"], scenes["half"]])
    rows = {r.key: r for r in cmp.rows}
    for k, key in enumerate(("full", "half")):
        loss, pv, phi, joint = _friction_of(scenes[key])
        assert rows["friction_mean_loss"].values[k] == loss and loss > 0.0
        assert rows["friction_mean_loss"].unit == "W"
        r = rows["friction_peak_pv"]
        assert (r.values[k], r.phi1[k], r.items[k]) == (pv, phi, joint)
        assert r.unit == "MPa·m/s"
    assert rows["friction_mean_loss"].compared and rows["friction_peak_pv"].compared
    # half the coefficient, about half the loss (the reactions change a little with it)
    assert rows["friction_mean_loss"].change(1)[1] == pytest.approx(-0.5, abs=0.02)
    assert not any("friction" in n for n in cmp.notes)


def test_compare_says_which_designs_have_friction(scenes, capsys):
    from pipeline.analysis.compare import compare_files
    cmp = compare_files([scenes["full"], scenes["none"]])
    rows = {r.key: r for r in cmp.rows}
    assert not rows["friction_mean_loss"].compared
    assert rows["friction_mean_loss"].values[1] is None
    assert rows["M_bal"].compared      # shown, with a note that only one has friction
    assert any("include joint friction" in n and "full" in n for n in cmp.notes)
    assert any(n.startswith("not compared: friction loss and p*v; none has no joint friction")
               for n in cmp.notes)
    capsys.readouterr()
    assert main(["compare", str(scenes["full"]), str(scenes["none"]), "--no-pictures"]) == 0
    text = capsys.readouterr().out
    assert "mean friction loss" in text and "largest peak p*v" in text


# ------------------------------------------------------------------ a sweep's design
def test_a_sweep_design_rerun_as_a_scene_keeps_its_friction(studies, tmp_path, monkeypatch):
    """`pipeline show --candidate` and the report re-run a design through the
    scene path (``candidate.rerun_candidate``): with the study's friction, its
    reactions and M_bal are the friction-inclusive scene's.  (A sweep with
    friction is refused today, so the stored study is given friction here.)"""
    from pipeline.analysis import candidate as cand
    from pipeline.runs.sweep import run_sweep
    from pipeline.solve.scene import run_scene
    from pipeline.study.reader import load_study, parse_study
    out = tmp_path / "sweep.h5"
    run_sweep(load_study(studies / "ov7_synthesis.toml"), out, candidates=8, chunk_size=8,
              progress=False)
    stored = cand.load_study_from_results
    monkeypatch.setattr(cand, "load_study_from_results",
                        lambda f: parse_study(with_friction(stored(f).text), stored(f).path))
    run = cand.rerun_candidate(out, "reference")
    fr = run.dense.forces.friction
    assert fr is not None and (fr.status == 0).all()
    scene, _, _ = cand.candidate_scene(out, "reference")
    assert scene.mechanism.friction is not None
    want = run_scene(scene).dense.forces
    np.testing.assert_array_equal(run.dense.phi, want.phi)
    np.testing.assert_allclose(run.dense.forces.M_bal, want.M_bal, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(run.dense.forces.magnitude, want.magnitude, rtol=1e-10)
    # and friction changed them: the mean drive power is the mean loss
    assert not np.allclose(run.dense.forces.M_bal, fr.M_bal_frictionless, rtol=1e-6)
