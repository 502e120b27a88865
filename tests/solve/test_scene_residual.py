"""The equilibrium residual of a scene: the relative virtual-power residual of
its kinetostatics at every position (kernels.forces.equilibrium_residual, the
function the sweep's force stage calls), stored beside the reactions, the
worst one in the run summary and a column of reactions.csv.

At rounding level on every shipped force scene and equal to the virtual-power
oracle of tests/support/power.py; with the balancing moment made 1 % wrong in
the force kernel, large, and again equal to the oracle's."""

import dataclasses

import h5py
import numpy as np
import pandas as pd
import pytest

import pipeline
import pipeline.compiler.plan_path
from pipeline.cli import main
from pipeline.solve.reactions import scene_forces
from pipeline.solve.scene import run_scene
from pipeline.study.reader import load_study
from support.power import virtual_power
from support.tolerances import EQUILIBRIUM_REL

FORCE_SCENES = ("ov7_class3", "warp_feed_fourbar", "ov7_class3_slider", "feed_fivebar",
                "cam_rocker_input", "actuator_slider_input", "scotch_yoke_rpp",
                "ppr_cross_slide", "slotted_rocker_prp")
WRONG = 1.01            # a balancing moment 1 % off


def _oracle(res, curves):
    """tests/support/power.py's relative residual per position (0 where every
    power term is 0: then the sum is 0 too)."""
    total, scale = virtual_power(res.study, res.plan, curves, curves.forces)
    still = scale == 0.0
    assert (total[still] == 0.0).all()
    return np.abs(total) / np.where(still, 1.0, scale)


@pytest.mark.parametrize("name", FORCE_SCENES)
def test_rounding_level_on_every_shipped_force_scene(studies, name):
    res = run_scene(load_study(studies / f"{name}.toml"))
    for curves in (res.table, res.dense):
        r = curves.forces.residual
        assert r.shape == curves.phi.shape and np.isfinite(r).all()
        assert r.max() <= EQUILIBRIUM_REL, (name, r.max())
        np.testing.assert_allclose(r, _oracle(res, curves), rtol=0, atol=EQUILIBRIUM_REL)
    # measured (this checkout): 2.7e-14 at most (ov7_class3's table)
    print(f"\n{name}: worst residual {res.dense.forces.residual.max():.2g} (dense), "
          f"{res.table.forces.residual.max():.2g} (table)")


@pytest.mark.parametrize("name", ["ov7_class3", "warp_feed_fourbar", "ov7_class3_slider"])
def test_a_wrong_balancing_moment_makes_it_large(studies, name, monkeypatch):
    """The force kernel's M_bal scaled by 1.01 (every other number as it was):
    the residual the scene reports grows by orders of magnitude, as the oracle's."""
    res = run_scene(load_study(studies / f"{name}.toml"))
    real = pipeline.compiler.plan_path.forces_curve_of   # (the scene's force kernel)

    def spoiled(plan):
        kernel = real(plan)

        def forces_curve(*args):
            kernel(*args)
            args[-1][:] *= WRONG          # m_out: the balancing moment
        return forces_curve

    monkeypatch.setattr(pipeline.compiler.plan_path, "forces_curve_of", spoiled)
    bad = scene_forces(res.study.mechanism, res.plan, res.dense)
    np.testing.assert_array_equal(bad.M_bal, res.dense.forces.M_bal * WRONG)
    assert bad.residual.max() > 1e6 * EQUILIBRIUM_REL, bad.residual.max()
    oracle = _oracle(res, dataclasses.replace(res.dense, forces=bad))
    np.testing.assert_allclose(bad.residual, oracle, rtol=EQUILIBRIUM_REL, atol=EQUILIBRIUM_REL)


def test_stored_summarised_and_exported(studies, tmp_path):
    out = pipeline.run(studies / "ov7_class3.toml", tmp_path / "b.h5", pictures=False)
    res = pipeline.solve_scene(studies / "ov7_class3.toml")
    r = res.dense.forces.residual
    k = int(np.argmax(r))
    line = out.summary["equilibrium_residual"]
    assert line.startswith(f"{r[k]:.3g} at phi1 = {np.degrees(res.dense.phi[k]):g} deg"), line
    with h5py.File(out.results, "r") as f:
        for group in ("table", "dense"):
            d = f[f"{group}/equilibrium_residual"]
            assert d.attrs["units"] == "1" and "virtual-power" in d.attrs["long_name"]
            assert d.dims[0][0].name == f"/{group}/phi1"
        np.testing.assert_array_equal(f["dense/equilibrium_residual"][()], r)
    csv = tmp_path / "csv"
    assert main(["export", str(out.results), "--csv", str(csv), "-q"]) == 0
    df = pd.read_csv(csv / "reactions.csv")
    assert df.columns[-1] == "M_bal [N·m]"
    np.testing.assert_allclose(df["equilibrium_residual [1]"], r, rtol=1e-11, atol=0)
