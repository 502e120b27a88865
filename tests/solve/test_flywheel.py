"""Flywheel sizing (pipeline.solve.flywheel): the steady rotation of a dynamics
case found as the periodic solution of the energy equation over one
revolution, and the inertia added on the crank shaft for a target delta; both
checked by integrating the equation of motion in time (the compiled RK4 of
pipeline.solve.crank_motion, an independent route)."""

import re
from dataclasses import replace

import h5py
import pytest

from pipeline.base.errors import StudyError
from pipeline.cli import main
from pipeline.solve.crank_motion import integrate
from pipeline.solve.flywheel import _Orbit, size_flywheel, with_flywheel
from pipeline.study.reader import load_study, parse_study

from conftest import STUDIES

FOURBAR_DYNAMICS = """
[dynamics]
[dynamics.flywheel]
delta = 0.01
[[dynamics.cases]]
name = "steady"
phi_start = 0.0
omega_start = 60.0
M1 = 8.0
damping = 0.1
t_end = 4.0
dt = 1e-4
sample_dt = 0.01
"""


def takeup():
    return load_study(STUDIES / "takeup_dynamics.toml")


def fourbar():
    """Four-bar D driven by a constant moment against a damper and its warp tension
    (a function of phi)."""
    return parse_study((STUDIES / "warp_feed_fourbar.toml").read_text() + FOURBAR_DYNAMICS,
                       STUDIES / "warp_feed_fourbar.toml")


def fourbar_backwards():
    """The same driven the other way round (the orbit's samples are reversed)."""
    text = FOURBAR_DYNAMICS.replace("M1 = 8.0", "M1 = -8.0").replace("omega_start = 60.0",
                                                                      "omega_start = -60.0")
    return parse_study((STUDIES / "warp_feed_fourbar.toml").read_text() + text,
                       STUDIES / "warp_feed_fourbar.toml")


@pytest.mark.parametrize("make", [takeup, fourbar, fourbar_backwards],
                         ids=["takeup", "fourbar", "fourbar_backwards"])
def test_the_sized_system_integrated_again_has_the_target_delta(make):
    study = make()
    plan, mech = study.mechanism.compile(), study.mechanism
    name, target = study.dynamics.flywheel
    case = next(c for c in study.dynamics.cases if c.name == name)
    fw = size_flywheel(plan, mech, case, target)
    assert (fw.omega_mean < 0) == (make is fourbar_backwards)
    assert fw.J_add > 0 and fw.delta == pytest.approx(target, rel=1e-9)
    orbit = _Orbit(plan, mech, case)
    for J_add, want in ((fw.J_add, target), (0.0, fw.delta_without)):
        # in time, from the periodic rotation's speed at the start: no run-up to wait for
        start = orbit.s * orbit.periodic(J_add)[0]
        run = integrate(with_flywheel(plan, mech, J_add), mech,
                        replace(case, omega_start=start, t_end=4.0))
        steady = run.steady()
        assert steady["delta"] == pytest.approx(want, rel=1e-3), J_add
        assert abs(steady["omega_mean_change"]) < 1e-4 * abs(steady["omega_mean"])
        if J_add:
            assert steady["omega_min"] == pytest.approx(fw.omega_min, rel=1e-5)
            assert steady["omega_max"] == pytest.approx(fw.omega_max, rel=1e-5)
            assert steady["omega_mean"] == pytest.approx(fw.omega_mean, rel=1e-6)
    # a heavier flywheel does better, a lighter one worse: delta(J) falls through the target
    assert orbit.delta(1.5 * fw.J_add)[0] < target < orbit.delta(0.5 * fw.J_add)[0]


def test_the_scene_reports_and_stores_the_flywheel(tmp_path, capsys):
    out = tmp_path / "takeup.h5"
    assert main(["run", str(STUDIES / "takeup_dynamics.toml"), "-o", str(out),
                 "--no-pictures"]) == 0
    line = [ln for ln in capsys.readouterr().out.splitlines() if "runup flywheel" in ln]
    assert len(line) == 1 and "kg m^2 added on the crank shaft" in line[0]
    with h5py.File(out, "r") as f:
        g = f["flywheel"]
        assert g["J_add"].attrs["units"] == "kg*m^2" and g["J_add"][()] > 0
        assert g["delta"][()] == pytest.approx(0.02, rel=1e-9)
        assert g["omega_mean"].attrs["units"] == "rad/s" and g.attrs["body"] == "crank"


@pytest.mark.parametrize("section, field, words", [
    ('[dynamics.flywheel]\ncase = "nope"\ndelta = 0.02', "dynamics.flywheel.case",
     "no dynamics case"),
    ('[dynamics.flywheel]\ndelta = 1.5', "dynamics.flywheel.delta", "below 1"),
    ('[dynamics.flywheel]\ndelta = -0.1', "dynamics.flywheel.delta", "positive"),
])
def test_a_wrong_flywheel_section_is_one_line(section, field, words):
    text = (STUDIES / "takeup_dynamics.toml").read_text()
    text = re.sub(r"^\[dynamics\.flywheel\].*\ncase = .*\ndelta = .*\n", "", text, flags=re.M)
    assert "[dynamics.flywheel]" not in text
    text = text.replace("[[dynamics.cases]]", section + "\n\n[[dynamics.cases]]", 1)
    with pytest.raises(StudyError) as e:
        parse_study(text, "s.toml")
    assert field in str(e.value) and words in str(e.value) and "\n" not in str(e.value)
