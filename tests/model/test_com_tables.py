"""Centres of mass in the tables (issue 14 item 4): their velocity and
acceleration analogs equal finite differences of their positions, as the
points' do, and the scene file and bodies.csv carry them with the loads."""

import h5py
import numpy as np
import pandas as pd

import pipeline
from pipeline.cli import main
from pipeline.solve.scene import solve_curves


def test_com_analogs_are_finite_differences_of_positions(studies):
    res = pipeline.solve_scene(studies / "ov7_class3.toml")
    plan = res.plan
    com = np.asarray(plan.body_com)
    h = 1e-5
    for phi in np.radians([-17.0, -123.4, -250.0]):
        c = solve_curves(plan, np.array([res.dense.phi[0], phi - h, phi, phi + h]), 2,
                         res.tolerances)
        S = c.pos[1:, com]
        fd1 = (S[2] - S[0]) / (2 * h)
        fd2 = (c.d1[3, com] - c.d1[1, com]) / (2 * h)
        scale = np.abs(c.d1[2, com]).max()
        np.testing.assert_allclose(c.d1[2, com], fd1, rtol=0, atol=1e-7 * scale)
        np.testing.assert_allclose(c.d2[2, com], fd2, rtol=0,
                                   atol=1e-6 * np.abs(c.d2[2, com]).max())


def test_scene_file_and_bodies_table_carry_the_centres_of_mass(studies, tmp_path):
    out = tmp_path / "b.h5"
    assert main(["run", str(studies / "ov7_class3.toml"), "-o", str(out), "-q",
                 "--no-pictures"]) == 0
    assert main(["export", str(out), "--csv", str(tmp_path / "csv"), "-q"]) == 0
    bodies = pd.read_csv(tmp_path / "csv" / "bodies.csv")
    with h5py.File(out, "r") as f:
        d = f["dense"]
        assert d["com_position"].dims[1][0].name == "/body"
        names = [x.decode() if isinstance(x, bytes) else x for x in f["body"][()]]
        b = names.index("lead 2-3")
        np.testing.assert_allclose(bodies["S[lead 2-3]_x [mm]"], d["com_position"][:, b, 0],
                                   rtol=1e-11)
        np.testing.assert_allclose(bodies["AS[lead 2-3]_y [m/s²]"],
                                   d["com_acceleration"][:, b, 1], rtol=1e-11, atol=1e-9)
        np.testing.assert_allclose(bodies["Fx[lead 2-3] [N]"], d["body_loads"][:, b, 0],
                                   rtol=1e-11, atol=1e-9)
        # the inertia force of a body without applied loads: -m a_S (plus gravity in y)
        plan = pipeline.solve_scene(studies / "ov7_class3.toml").plan
        m = plan.par[plan.param("lead 2-3.mass")]
        np.testing.assert_allclose(d["body_loads"][:, b, 0], -m * d["com_acceleration"][:, b, 0],
                                   rtol=1e-9, atol=1e-9)
