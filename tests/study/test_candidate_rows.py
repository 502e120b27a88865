"""A sweep's candidates: the compiled parameter rows (``kernels.candidates``)
against the column-by-column NumPy form they replaced, bit for bit, on every
shipped study with a mass model; the triangle redraws, which now look again
only at the rows just redrawn, against the loop over every row each round."""

import numpy as np
import pytest

from pipeline.study.reader import load_study
from pipeline.study.sampling import REDRAW_ROUNDS, draw_unit
from pipeline.study.sweep_spec import apply_design, draw_checked, parameter_rows

MASS_MODEL_STUDIES = ("ov7_synthesis", "ov7_synthesis_law", "ov7_search", "ov7_robust_search",
                      "ov7_class3_slider_sweep")


def _numpy_rows(plan, spec, x):
    """The NumPy form: the reference row repeated, each column written over
    every row, the mass model's three products per body."""
    base = plan.par
    pars = np.repeat(base[None, :], x.shape[0], axis=0)
    for j, v in enumerate(spec.variables):
        pars[:, plan.param(v.param)] = x[:, j] * v.factor
    for ms in spec.mass_model:
        k = plan.param(ms.length_param)
        mass, inertia = plan.param(f"{ms.body}.mass"), plan.param(f"{ms.body}.J_S")
        arm = plan.param(f"S[{ms.body}].length")
        ratio = pars[:, k] / base[k]
        cube = ratio * ratio * ratio
        pars[:, mass], pars[:, inertia], pars[:, arm] = (base[mass] * ratio, base[inertia] * cube,
                                                         base[arm] * ratio)
    return pars


def _sweep(studies, name):
    study = load_study(studies / f"{name}.toml")
    spec = study.sweep if study.sweep is not None else study.search.sweep
    return study, spec


@pytest.mark.parametrize("name", MASS_MODEL_STUDIES)
def test_parameter_rows_are_numpys_bits(studies, name):
    study, spec = _sweep(studies, name)
    plan = study.mechanism.compile()
    assert spec.mass_model, "a study with a mass model"
    x = draw_checked(spec, 0)[0][:2000]
    got = parameter_rows(plan, spec, x)
    assert got.shape == (len(x), plan.par.shape[0])
    assert got.tobytes() == _numpy_rows(plan, spec, x).tobytes()
    # a strided view of the rows (a search's X) is read as its values
    assert parameter_rows(plan, spec, x[::3]).tobytes() == _numpy_rows(plan, spec,
                                                                        x[::3]).tobytes()


def test_scene_path_scales_the_mass_data_alike(studies):
    """apply_design (the scene path, Python scalars through the same compiled
    formula) gives each body the row's mass, J_S and arm."""
    study, spec = _sweep(studies, "ov7_synthesis")
    plan = study.mechanism.compile()
    x = draw_checked(spec, 1)[0][:5]
    rows = parameter_rows(plan, spec, x)
    for xi, row in zip(x, rows):
        mech = apply_design(study.mechanism, spec, xi)
        for body in mech.bodies:
            assert row[plan.param(f"{body.name}.mass")] == body.mass
            assert row[plan.param(f"{body.name}.J_S")] == body.J_S


def _redraws_over_every_row(spec, chunk):
    """The loop before: every round looks at every row again."""
    u = draw_unit(spec, chunk)
    low = np.array([v.low for v in spec.variables])
    high = np.array([v.high for v in spec.variables])
    x = low + u * (high - low)
    rejected = np.zeros(len(spec.triangles), np.int64)
    rng = None
    for _ in range(REDRAW_ROUNDS):
        bad = np.zeros(x.shape[0], bool)
        for k, t in enumerate(spec.triangles):
            b = t.broken(x) & ~bad
            rejected[k] += int(b.sum())
            bad |= b
        if not bad.any():
            return x, rejected
        if rng is None:
            rng = np.random.default_rng([spec.seed, chunk, 0x7EDA])
        x[bad] = low + rng.random((int(bad.sum()), len(low))) * (high - low)
    raise AssertionError("no buildable draw")


@pytest.mark.parametrize("chunk", [0, 3])
def test_redraws_look_again_at_the_redrawn_rows_only(studies, chunk):
    """The same rows and the same rejections per triangle (a third of the
    default study's draws break its triangle, some several times)."""
    from dataclasses import replace
    study, spec = _sweep(studies, "ov7_synthesis")
    spec = replace(spec.with_candidates(200_000), chunk_size=50_000)
    assert spec.triangles
    x, rejected = draw_checked(spec, chunk)
    x0, rejected0 = _redraws_over_every_row(spec, chunk)
    assert x.tobytes() == x0.tobytes()
    assert rejected.tolist() == rejected0.tolist() and rejected.sum() > 10_000
