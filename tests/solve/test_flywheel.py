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
    text = capsys.readouterr().out
    line = [ln for ln in text.splitlines() if "runup flywheel" in ln]
    assert len(line) == 1 and "kg·m² added on the crank shaft" in line[0]
    # every motion's summary prints its error estimate (issue 58)
    for case in ("runup", "free"):
        line = [ln for ln in text.splitlines() if f"{case} error_phi1:" in ln]
        assert len(line) == 1 and "rad estimated (accepted: 8e-08 rad" in line[0], text
    with h5py.File(out, "r") as f:
        g = f["flywheel"]
        assert g["J_add"].attrs["units"] == "kg·m²" and g["J_add"][()] > 0
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


# ----------------------------------------------------------------- no steady rotation (issue 58)
def _takeup_with(line_old, line_new):
    text = (STUDIES / "takeup_dynamics.toml").read_text()
    assert text.count(line_old) >= 1
    return text.replace(line_old, line_new, 1)


def test_no_damping_under_the_flywheels_case_is_one_line_when_read():
    """damping = 0: brentq's "Failed to converge after 500 iterations" with a traceback."""
    with pytest.raises(StudyError) as e:
        parse_study(_takeup_with("damping = 2e-4", "damping = 0.0"), "s.toml")
    msg = str(e.value)
    assert msg.startswith("s.toml: dynamics.cases[0].damping: ") and "\n" not in msg
    assert "speeds up forever" in msg and "flywheel" in msg


@pytest.mark.parametrize("changes, words", [
    (dict(damping=0.0), "speeds up forever"),
    (dict(damping=1e4), "stops within a revolution"),
    (dict(M1=1e300), "beyond the study's limit"),
    (dict(M1=2.5), "beyond the study's limit"),        # M1 / b = 12,500 rad/s
], ids=["damping=0", "damping=1e4", "M1=1e300", "M1=2.5"])
def test_without_a_steady_rotation_no_flywheel_is_sized(changes, words):
    """The sizing itself, asked directly: its reason, never scipy's words (brentq's
    "f(a) and f(b) must have different signs", "Failed to converge")."""
    from pipeline.solve.crank_motion import with_changes
    from pipeline.solve.flywheel import NoSteadyRotation
    study = takeup()
    plan, mech = study.mechanism.compile(), study.mechanism
    case = with_changes(next(c for c in study.dynamics.cases if c.name == "runup"), **changes)
    with pytest.raises(NoSteadyRotation) as e:
        size_flywheel(plan, mech, case, 0.02)
    assert words in str(e.value) and "f(a)" not in str(e.value) and "\n" not in str(e.value)


@pytest.mark.parametrize("line_new", ['M1 = 1e6', 'M1 = "1e300"', "damping = 1e4"])
def test_a_refused_case_gets_no_flywheel(tmp_path, capsys, line_new):
    """M1 = 1e6 (a SINGULAR run-up, yet a flywheel sized for 5.0e9 rad/s), M1 = "1e300" and
    damping = 1e4 (tracebacks): the run-up is refused, and the flywheel line says so in one
    line naming the study file and the field."""
    study = tmp_path / "s.toml"
    old = "damping = 2e-4" if line_new.startswith("damping") else "M1 = 0.025"
    study.write_text(_takeup_with(old, line_new))
    out = tmp_path / "s.h5"
    assert main(["run", str(study), "-o", str(out), "--no-pictures"]) == 0
    text = capsys.readouterr().out
    status = [ln for ln in text.splitlines() if "runup status:" in ln]
    assert len(status) == 1 and status[0].split()[-1] in ("INACCURATE", "TOO_FAST")
    line = [ln for ln in text.splitlines() if "runup flywheel" in ln]
    assert len(line) == 1, text
    assert f"not sized: {study}: dynamics.flywheel: case 'runup' ended " in line[0]
    assert "omega_mean" not in text.split("runup status")[1].split("free status")[0]
    with h5py.File(out, "r") as f:
        assert "J_add" not in f["flywheel"] and "not sized" not in f["flywheel"].attrs["case"]
        assert f["flywheel"].attrs["not_sized"].startswith(f"{study}: dynamics.flywheel: ")
        assert f["dynamics/runup"].attrs["status"] in ("INACCURATE", "TOO_FAST")


def test_the_flywheel_sized_beside_the_integration_is_the_one_sized_after_it():
    """A scene sizes the flywheel while its case is integrated, on the case as the study
    declares it (size_study_flywheel); before, after the integration, on the case the
    run returned, whose step a refinement may have halved: the same numbers, since the
    sizing reads the case's drive, damping and start, never its step."""
    from pipeline.solve.flywheel import flywheel_of, size_study_flywheel
    from pipeline.solve.crank_motion import run_dynamics
    study = takeup()
    plan, mech = study.mechanism.compile(), study.mechanism
    name, target = study.dynamics.flywheel
    case = next(c for c in study.dynamics.cases if c.name == name)
    beside = size_study_flywheel(study, plan)
    assert beside == size_flywheel(plan, mech, replace(case, dt=case.dt / 4.0), target)
    assert beside.refused == "" and beside.J_add > 0.0

    class Done:         # a sizing already under way, as solve_scene hands it over
        def result(self):
            return beside
    cases = run_dynamics(study, plan)
    assert flywheel_of(study, plan, cases, Done()) is beside
    assert flywheel_of(study, plan, cases) == beside


def test_the_extremes_are_refined_between_the_nodes():
    """The take-up's flywheel with the speed extremes refined between the orbit's
    RK4 nodes: J_add at 1440 steps within 1e-7 of the refined reference at 4x the
    steps, where the nodes' own extremes miss it by more (issue 53)."""
    from scipy.optimize import brentq

    from pipeline.solve.flywheel import ORBIT_STEPS, _Orbit, size_flywheel
    from pipeline.study.reader import load_study
    study = load_study(STUDIES / "takeup_dynamics.toml")
    plan = study.mechanism.compile()
    case = next(c for c in study.dynamics.cases if c.name == "runup")
    target = 0.02
    ref = size_flywheel(plan, study.mechanism, case, target, steps=4 * ORBIT_STEPS)
    got = size_flywheel(plan, study.mechanism, case, target)
    assert got.J_add == pytest.approx(ref.J_add, rel=1e-7)
    assert got.omega_max == pytest.approx(ref.omega_max, rel=1e-9)
    orbit = _Orbit(plan, study.mechanism, case)
    grid = brentq(lambda j: orbit.delta(j, refined=False)[0] - target, 0.0, 4 * ref.J_add,
                  xtol=1e-15, rtol=1e-12)
    assert abs(grid - ref.J_add) > 1e-7 * ref.J_add       # the nodes alone: not within it
    d, lo, hi, _ = orbit.delta(got.J_add)
    g, glo, ghi, _ = orbit.delta(got.J_add, refined=False)
    assert hi >= ghi and lo <= glo and d >= g                 # refined: never inside the nodes'


def _orbit_in_python(orbit, K0, J_add):
    """The orbit's RK4 in plain Python floats, step by step (the slow reference
    of kernels.dynamics.energy_orbit): K at the nodes, or None where it stops."""
    import math
    J = [float(x) for x in orbit.J + J_add]
    d = [float(x) for x in orbit.drive]
    h, b, k = float(orbit.h), float(orbit.b), float(K0)
    out = [k]

    def f(i, k):
        return d[i] - b * math.sqrt(max(2.0 * k / J[i], 0.0))
    for j in range(orbit.n):
        i = 2 * j
        k1 = f(i, k)
        k2 = f(i + 1, k + 0.5 * h * k1)
        k3 = f(i + 1, k + 0.5 * h * k2)
        k4 = f(i + 2, k + h * k3)
        k = k + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        if not k > 0.0:
            return None
        out.append(k)
    return out


def test_the_compiled_orbit_is_the_python_steps_to_the_bit():
    """The orbit's compiled RK4 (kernels.dynamics.energy_orbit) gives the plain
    Python steps' numbers bit for bit, from slow starts where the crank stops
    on the way (None, both) to fast ones, with inertia added or not."""
    import numpy as np
    from support.friction_sections import TAKEUP_FRICTION
    # (with the bearings' friction: the slow starts stop within the revolution)
    st = parse_study((STUDIES / "takeup_dynamics.toml").read_text() + TAKEUP_FRICTION,
                     "takeup_friction.toml")
    plan = st.mechanism.compile()
    orbit = _Orbit(plan, st.mechanism, st.dynamics.cases[0])
    stopped = ran = 0
    for K0 in np.geomspace(1e-6, 1e3, 15):
        for J_add in (0.0, 3e-3):
            a, b = _orbit_in_python(orbit, K0, J_add), orbit.run(K0, J_add)
            assert (a is None) == (b is None), (K0, J_add)
            if a is None:
                stopped += 1
            else:
                ran += 1
                assert np.array_equal(np.array(a).view(np.int64), b.view(np.int64))
    assert ran > 0 and stopped > 0, (ran, stopped)
