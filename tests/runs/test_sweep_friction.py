"""A sweep with [mechanism.friction] (issue 52): its metrics friction_loss and
peak_pv, and its force peaks with friction, computed on the careful path
(``runs.sweep_friction``), against the scene's own path for the same design
(the design rebuilt by ``apply_design``, its kinematics by ``solve_curves``
and its friction by ``solve.friction.solve_positions``, reduced in numpy);
a candidate whose slide locks is FRICTION_LOCK at the angle and slide a
scene of the same design reports; a metric that cannot hold with friction
is refused in one line."""

import math
import re

import h5py
import numpy as np
import pytest

from pipeline.base.errors import StudyError
from pipeline.cli import main
from pipeline.kernels import config as kc
from pipeline.kernels import sweep as ks
from pipeline.model.metric_catalogue import FRICTION_COLUMN
from pipeline.runs.sweep import build_problem
from pipeline.solve.friction import solve_positions
from pipeline.solve.reactions import sample_loads
from pipeline.solve.scene import run_scene, solve_curves
from pipeline.study.reader import parse_study
from pipeline.study.sampling import draw_checked
from pipeline.study.sweep_spec import apply_design, parameter_rows

REL = 1e-11         # the same equations on the same grid, reduced in another order
LOCK_RAD = 1e-8     # a locking angle: both paths bisect to 1e-10 rad

FRICTION_B = """[mechanism.friction]
revolute = 0.08
pin_diameter = 10.0
pins = { P1 = 14.0, P2 = 12.0 }
pin_length = 12.0
"""


def _study(studies, name, section, objectives, metrics=None, positions=None):
    text = (studies / f"{name}.toml").read_text()
    text = text.replace("[output]", section + "\n[output]", 1)
    lines = [ln for ln in text.splitlines() if not ln.startswith(("objectives =", "metrics ="))]
    k = lines.index("[sweep]") + 1
    lines.insert(k, f"objectives = {objectives!r}".replace("'", '"'))
    if metrics is not None:
        lines.insert(k, f"metrics = {metrics!r}".replace("'", '"'))
    text = "\n".join(lines) + "\n"
    if positions is not None:
        text, n = re.subn(r"(?m)^positions = 360\b", f"positions = {positions}", text, 1)
        assert n == 1
    return text


def _evaluate(study, n):
    spec = study.sweep.with_candidates(n)
    problem = build_problem(study, spec)
    x, _ = draw_checked(spec, 0)
    status, rows = problem.evaluate_rows(parameter_rows(problem.plan, spec, x), n_jobs=2)
    return spec, problem, x, status, rows


def _scene_path(study, spec, problem, x):
    """The design's friction by the scene's own functions, on the sweep's grid."""
    mech = apply_design(study.mechanism, spec, x)
    plan = mech.compile()
    c = solve_curves(plan, problem.phis, kc.ACCELERATIONS, close_at=problem.phi_close)
    assert c.overall == kc.OK
    R, S, M, _, fric, speed, found = solve_positions(
        plan, mech.friction, c.pos, c.d1, c.d2, mech.crank.omega1, mech.crank.eps1,
        sample_loads(mech, problem.phis))
    nj = len(plan.joint_names)
    unit = np.r_[np.ones(nj), np.full(fric.shape[1] - nj, 1e-3)]
    loss = (-fric * speed * unit * mech.crank.omega1).sum(axis=1)
    d = np.asarray(mech.friction.diameters(), float)
    length = np.asarray(mech.friction.lengths(), float)
    r = np.hypot(R[..., 0], R[..., 1])
    pv = r / (d * length) * np.abs(speed[:, :nj] * mech.crank.omega1) * d * 0.5e-3
    k, j = np.unravel_index(np.argmax(r), r.shape)
    return dict(status=found[:, 0], loss=loss.mean(), pv=pv.max(), peak_r=r.max(), joint=j,
                phi=problem.phis[k], peak_m=np.abs(M).max())


def test_friction_metrics_agree_with_the_scenes_path(studies):
    """Mechanism B's synthesis with friction at every pin: for the candidates of
    the force stage, friction_loss, peak_pv and the force peaks with friction
    as the scene's functions give them for the same design on the same grid;
    the force peaks differ from the frictionless sweep's."""
    text = _study(studies, "ov7_synthesis", FRICTION_B, ["dwell_error", "friction_loss"],
                  ["peak_pv", "peak_reaction", "peak_M_bal"], positions=120)
    study = parse_study(text, "b_friction.toml")
    spec, problem, x, status, rows = _evaluate(study, 300)
    done = np.flatnonzero((status == kc.OK) & (rows[:, ks.M_FORCES_DONE] == 1.0))
    assert len(done) >= 10
    loss = rows[:, FRICTION_COLUMN["friction_loss"]]
    pv = rows[:, FRICTION_COLUMN["peak_pv"]]
    assert np.isfinite(loss[done]).all() and (loss[done] > 0).all()
    other = np.setdiff1d(np.arange(len(status)), done)
    assert np.isnan(loss[other]).all() and np.isnan(pv[other]).all()
    for i in done[:12]:
        ref = _scene_path(study, spec, problem, x[i])
        assert (ref["status"] == kc.OK).all()
        assert loss[i] == pytest.approx(ref["loss"], rel=REL)
        assert pv[i] == pytest.approx(ref["pv"], rel=REL)
        assert rows[i, ks.M_PEAK_R] == pytest.approx(ref["peak_r"], rel=REL)
        assert rows[i, ks.M_PEAK_JOINT] == ref["joint"]
        assert rows[i, ks.M_PEAK_PHI] == ref["phi"]
        assert rows[i, ks.M_PEAK_MBAL] == pytest.approx(ref["peak_m"], rel=REL)
    # without the section: the same candidates, frictionless peaks (lower M_bal's
    # peak is not guaranteed, but the numbers differ)
    plain = parse_study(_study(studies, "ov7_synthesis", "", ["dwell_error", "peak_reaction"],
                               ["peak_M_bal"], positions=120), "b.toml")
    _, _, _, st0, rows0 = _evaluate(plain, 300)
    assert (st0 == status).all()
    assert (rows0[done, ks.M_PEAK_MBAL] != rows[done, ks.M_PEAK_MBAL]).all()


SLOT_FRICTION = """[mechanism.friction]
revolute = 0.05
slide = {f}
pin_diameter = 6.0
pin_length = 8.0
"""


def test_a_locking_slide_is_friction_lock_where_the_scene_locates_it(studies, tmp_path):
    """The slotted rocker with slide friction 0.36: its candidates lock; each one's
    status, crank angle (between positions) and slide are those of a scene of the
    same design; in the results file the lock names the slide."""
    text = _study(studies, "slotted_rocker_prp_sweep", SLOT_FRICTION.format(f=0.36),
                  ["friction_loss", "peak_reaction"], positions=90)
    study = parse_study(text, "slot.toml")
    spec, problem, x, status, rows = _evaluate(study, 6)
    locked = np.flatnonzero(status == kc.FRICTION_LOCK)
    assert len(locked) >= 3
    names = problem.friction.names
    ng = problem.plan.n_groups
    for i in locked[:3]:
        mech = apply_design(study.mechanism, spec, x[i])
        from dataclasses import replace
        res = run_scene(replace(study, kind="scene", mechanism=mech))
        fail = res.failure
        assert fail["status"] == "FRICTION_LOCK"
        assert abs(rows[i, ks.M_FAIL_PHI] - math.radians(fail["phi_deg"])) <= LOCK_RAD
        assert names[int(rows[i, ks.M_FAIL_GROUP]) - ng] == fail["group"]
        assert np.isnan(rows[i, [ks.M_PEAK_R, ks.M_PEAK_MBAL]]).all()
        assert np.isnan(rows[i, FRICTION_COLUMN["friction_loss"]])
    study_file = tmp_path / "slot.toml"
    study_file.write_text(text)
    out = tmp_path / "slot.h5"
    assert main(["run", str(study_file), "-o", str(out), "--candidates", "4", "-q"]) == 0
    with h5py.File(out, "r") as f:
        st = f["candidates/status"][()]
        fg = f["candidates/fail_group"]
        groups = [g.decode() if isinstance(g, bytes) else str(g) for g in fg.attrs["groups"]]
        assert (st == kc.FRICTION_LOCK).any()
        k = int(np.flatnonzero(st == kc.FRICTION_LOCK)[0])
        assert groups[int(fg[k])].startswith("slide[")
        assert "FRICTION_LOCK" in fg.attrs["long_name"]


def test_a_sweep_with_friction_stores_its_metrics_with_units(studies, tmp_path):
    """`pipeline run` of a sweep whose objective is friction_loss: the file keeps
    friction_loss [W] and peak_pv [MPa*m/s] for the feasible designs."""
    study_file = tmp_path / "b_friction.toml"
    study_file.write_text(_study(studies, "ov7_synthesis", FRICTION_B,
                                 ["dwell_error", "friction_loss"], ["peak_pv"], positions=90))
    out = tmp_path / "b.h5"
    assert main(["run", str(study_file), "-o", str(out), "--candidates", "200", "-q"]) == 0
    with h5py.File(out, "r") as f:
        feasible = f["candidates/feasible"][()]
        assert feasible.any()
        for name, units in (("friction_loss", "W"), ("peak_pv", "MPa*m/s")):
            d = f["metrics"][name]
            assert d.attrs["units"] in (units, units.replace("*", "·"))
            assert np.isfinite(d[()][feasible]).all() and (d[()][feasible] > 0).all()


@pytest.mark.parametrize("section, objectives, words", [
    ("", ["dwell_error", "friction_loss"], "friction_loss needs friction in the joints"),
    (FRICTION_B, ["dwell_error", "equilibrium_residual"], "equilibrium_residual is the "
                                                          "frictionless"),
])
def test_a_metric_that_cannot_hold_is_refused_in_one_line(studies, section, objectives, words):
    with pytest.raises(StudyError) as e:
        parse_study(_study(studies, "ov7_synthesis", section, objectives), "s.toml")
    line = str(e.value)
    assert "\n" not in line and "sweep.objectives" in line and words in line
