"""The plan path (``pipeline.compiler.plan_path``): a scene's positions and forces
by kernels compiled once per installation that read the plan as data give the
generated module's bits, on every shipped study's mechanism, at its own row and
at rows that fail part-way (failure angle, group, margins and all)."""

import math
import warnings

import numpy as np
import pytest
from conftest import STUDIES

from pipeline.compiler import kernels_for, plan_path, structure_key
from pipeline.kernels import config as kc
from pipeline.kernels.walk import walk_revolution
from pipeline.solve.reactions import sample_loads
from pipeline.solve.scene import revolution_angles
from pipeline.study.reader import load_study


def _plans():
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for path in sorted(STUDIES.glob("*.toml")):
            plan = load_study(path).mechanism.compile()
            out.setdefault(structure_key(plan), (path.stem, plan))
    return list(out.values())


PLANS = _plans()


def _outputs(plan, n):
    return ([np.full((n, plan.n_points, 2), np.nan) for _ in range(3)]
            + [np.zeros(n, np.int8), np.zeros((n, plan.n_groups)), np.zeros(n), np.empty(2)])


def _same(a, b):
    return all(np.array_equal(np.asarray(x).view(np.uint8), np.asarray(y).view(np.uint8))
               for x, y in zip(a, b))


def _rows(plan):
    """The plan's own row and rows moved from it (each parameter by up to 12 %,
    differently per row): some fail part-way round."""
    j = np.arange(plan.par.shape[0])
    return [plan.par] + [plan.par * (1.0 + 0.12 * np.sin(7.0 * r + 1.3 * j)) for r in range(6)]


def test_every_shipped_mechanism_is_on_the_plan_path():
    """(a table law's spline too: its module arrays in K's tail)"""
    assert [name for name, plan in PLANS if plan_path.plan_constants(plan) is None] == []
    assert any(f.arrays for f in plan_path.forms())


@pytest.mark.parametrize("name,plan", PLANS, ids=[p[0] for p in PLANS])
def test_scene_positions_are_the_generated_modules_bits(name, plan):
    gen = kernels_for(plan)
    phis = 0.3 + 2.0 * math.pi * np.arange(240) / 240
    tols = kc.default_tolerances()
    statuses = []
    for par in _rows(plan):
        K = plan_path.plan_constants(plan, par)
        h = int(K[5])
        KG = gen.constants_array(par)
        assert _same([K[h:h + len(KG)]], [KG])
        for order in (0, 2):
            a, b = _outputs(plan, len(phis)), _outputs(plan, len(phis))
            args = (phis, 0.3 + 2.0 * math.pi, order, tols)
            sa = plan_path.revolution(plan, par, *args, *a)
            sb = gen.revolution(par, *args, *b)
            assert sa == sb and _same(a, b), (name, order)
            statuses.append(sa)
    assert statuses[0] == kc.OK


def test_failures_part_way_are_compared_too():
    """The moved rows above do fail, part-way and at the start, on several
    mechanisms: the comparison covers the failure paths (the watch's refine,
    the located angle and group)."""
    failed = 0
    tols = kc.default_tolerances()
    phis = 0.3 + 2.0 * math.pi * np.arange(240) / 240
    for name, plan in PLANS:
        for par in _rows(plan)[1:]:
            out = _outputs(plan, len(phis))
            st = plan_path.revolution(plan, par, phis, 0.3 + 2.0 * math.pi, 2, tols, *out)
            failed += st != kc.OK and 0 < int(np.argmax(out[3] != kc.OK)) < len(phis)
    assert failed >= 3


@pytest.mark.parametrize("name,plan", [p for p in PLANS if len(p[1].body_names)],
                         ids=[p[0] for p in PLANS if len(p[1].body_names)])
def test_scene_forces_are_the_generated_modules_bits(name, plan):
    """The tape of the generated forces_at (``pipeline.kernels.tape``) gives its
    bits: reactions, slides and drives, loads at the centres of mass, M_bal."""
    forces = plan_path.forces_curve_of(plan)
    assert forces is not None
    study = load_study(STUDIES / f"{name}.toml")
    mech = study.mechanism
    phis = revolution_angles(mech.crank, 180)
    n = len(phis)
    gen = kernels_for(plan)
    pos, d1, d2, *_ = out = _outputs(plan, n)
    gen.revolution(plan.par, phis, math.nan, 2, kc.default_tolerances(), *out)
    loads = sample_loads(mech, phis)
    shapes = ((n, len(plan.body_names), 3), (n, len(plan.joint_names), 2),
              (n, len(plan.slide_names) + plan.n_inputs, 2), (n,))
    a = [np.zeros(s) for s in shapes]
    b = [np.zeros(s) for s in shapes]
    forces(plan.par, pos, d1, d2, mech.crank.omega1, mech.crank.eps1, loads, *a)
    gen.forces_curve(plan.par, pos, d1, d2, mech.crank.omega1, mech.crank.eps1, loads, *b)
    assert np.isfinite(a[3]).all()
    assert _same(a, b)


def test_a_new_mechanism_compiles_nothing_of_its_own():
    """Every mechanism runs on the same compiled kernels (one signature each)."""
    mod = plan_path.plan_kernels()
    tols = kc.default_tolerances()
    phis = np.linspace(0.0, 6.0, 12)
    for name, plan in PLANS:
        plan_path.revolution(plan, plan.par, phis, math.nan, 2, tols, *_outputs(plan, len(phis)))
    assert len(mod.advance_first_class.signatures) == 1
    assert len(mod.start_first_class.signatures) == 1
    assert len(mod.derive.signatures) == 1
    # advance and start passed looked up once (kernels.walk.FixedFunction): the
    # walk's own signature, not one more
    assert len(walk_revolution.signatures) == 1


def test_a_plans_structure_is_kept_per_plan_object():
    """structure_key reads a plan's arrays once per plan object (a frozen Plan),
    gives each plan its own structure, and forgets a plan that is gone."""
    import gc

    from pipeline.compiler import _STRUCTURES
    (name_a, a), (name_b, b) = PLANS[:2]
    assert structure_key(a) == structure_key(a) and structure_key(a) != structure_key(b)
    again = load_study(STUDIES / f"{name_a}.toml").mechanism.compile()
    assert again is not a and structure_key(again) == structure_key(a)
    key = id(again)
    assert key in _STRUCTURES
    del again
    gc.collect()
    assert key not in _STRUCTURES


def test_the_plan_path_can_be_turned_off(monkeypatch):
    name, plan = PLANS[0]
    monkeypatch.setenv("PIPELINE_PLAN_PATH", "0")
    assert plan_path.revolution(plan, plan.par, np.zeros(1), math.nan, 0,
                                kc.default_tolerances(), *_outputs(plan, 1)) is None
    assert plan_path.forces_curve_of(plan) is None
    assert not plan_path.covers(plan)


def _arrays(obj):
    """Every array field of a dataclass result, by name."""
    return {k: v for k, v in vars(obj).items() if isinstance(v, np.ndarray)}


@pytest.mark.parametrize("friction", [False, True], ids=["frictionless", "friction"])
def test_crank_dynamics_are_the_generated_modules_bits(friction, tmp_path, monkeypatch):
    """RK4 (with the bearings' friction too: its own integrator) and the reduced
    terms on the plan path's advance and start give the generated module's bits
    (each case's first 20 ms, its error estimate's companion run included)."""
    from support.friction_sections import TAKEUP_FRICTION

    from pipeline.solve.crank_motion import integrate, with_changes
    from pipeline.solve.reduced_dynamics import reduced_terms
    path = STUDIES / "takeup_dynamics.toml"
    if friction:
        path = tmp_path / "takeup_friction.toml"
        path.write_text((STUDIES / "takeup_dynamics.toml").read_text() + TAKEUP_FRICTION)
    study = load_study(path)
    mech = study.mechanism
    plan = mech.compile()
    assert plan_path.dynamics_of(plan) is not None
    cases = [with_changes(c, t_end=0.02) for c in study.dynamics.cases]
    phis = np.linspace(0.0, 2.0 * math.pi, 17)
    runs = {}
    for on in ("1", "0"):
        monkeypatch.setenv("PIPELINE_PLAN_PATH", on)
        runs[on] = ([integrate(plan, mech, c, "rk4") for c in cases],
                    reduced_terms(plan, phis, mechanism=mech))
    (cases_a, terms_a), (cases_b, terms_b) = runs["1"], runs["0"]
    assert len(cases_a) == len(cases_b) > 0 and all(c.status == kc.OK for c in cases_a)
    for a, b in zip(cases_a, cases_b):
        fa, fb = _arrays(a), _arrays(b)
        assert fa.keys() == fb.keys() and fa
        assert [k for k in fa if not _same([fa[k]], [fb[k]])] == []
    assert _same(terms_a, terms_b)
