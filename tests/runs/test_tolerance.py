"""Tolerance analysis (pipeline.runs.tolerance): the sampled spread against
the linear prediction, the sensitivities against 40-digit central
differences, failed builds counted, the command and its file."""

from __future__ import annotations

import math
from dataclasses import replace

import h5py
import numpy as np
import pytest

from pipeline.cli import main
from pipeline.kernels import config as kc
from pipeline.runs.tolerance import analyse
from pipeline.study.reader import load_study, parse_study
from pipeline.study.tolerance_spec import ToleranceSpec
from support import mp_tolerance as mpt

from conftest import STUDIES


def fourbar_study():
    """The four-bar D of studies/warp_feed_fourbar.toml with its rocker DC
    declared (stroke and dwell are read from an output rocker)."""
    text = (STUDIES / "warp_feed_fourbar.toml").read_text()
    text = text.replace('working_point = "P5"', 'working_point = "P5"\nrocker = ["P4", "P3"]')
    return parse_study(text, STUDIES / "warp_feed_fourbar.toml")


def mech_b_study():
    return load_study(STUDIES / "ov7_synthesis.toml")


def small(study, tol=0.01):
    """Every drawn dimension within +-tol (mm or deg), normal at 3 sigma."""
    dims = ToleranceSpec().dimensions(study.mechanism)
    return ToleranceSpec(overrides=tuple((d.param, tol, "normal") for d in dims
                                         if d.tolerance > 0), samples=4096, seed=7)


@pytest.mark.parametrize("make", [fourbar_study, mech_b_study], ids=["fourbar", "mech_b"])
def test_sampled_spread_agrees_with_the_linear_prediction(make):
    study = make()
    a = analyse(study, study.mechanism, small(study), sweep_spec=study.sweep)
    assert (a.status == kc.OK).all()
    sampled, linear = a.sigma_sampled(), a.sigma_linear()
    assert len(a.metrics) >= 5
    for m, s, lin, ok in zip(a.metrics, sampled, linear, a.checked):
        assert lin > 0, m
        assert abs(s - lin) <= 0.03 * lin, (m, s, lin)
        assert ok[[d.tolerance > 0 for d in a.dimensions]].all(), m


def test_large_tolerances_show_where_the_linear_picture_fails():
    """The same comparison with ISO 2768-f tolerances is not a tautology: at the
    design's own tolerances the dwell error of mechanism B has a kink (its best
    window moves), and the two differ by more than 3 %."""
    study = mech_b_study()
    spec = ToleranceSpec(overrides=(("crank.phiM0", 0.5, "normal"),), samples=2048)
    a = analyse(study, study.mechanism, spec, sweep_spec=study.sweep)
    k = a.metrics.index("dwell_error")
    assert abs(a.sigma_sampled()[k] - a.sigma_linear()[k]) > 0.03 * a.sigma_linear()[k]


CASES = [
    (fourbar_study, mpt.fourbar_angles, mpt.fourbar_dims, "Attach[2].length",
     ["RRR[1].L_AB", "P4.x", "crank.phiM0", "Attach[2].length"]),
    (mech_b_study, mpt.mech_b_angles, mpt.mech_b_dims, "output arm.length",
     ["triad.L23", "P6.x", "crank.phiM0"]),
]


@pytest.mark.parametrize("make, angles, dims, arm, keys", CASES, ids=["fourbar", "mech_b"])
def test_sensitivities_agree_with_40_digit_central_differences(make, angles, dims, arm, keys):
    """A length, a pivot coordinate and an angle (the mounting phase): d stroke
    and d dwell error per mm or deg, against mpmath at 40 digits."""
    study = make()
    a = analyse(study, study.mechanism, small(study), sweep_spec=study.sweep, samples=16)
    params = [d.param for d in a.dimensions]
    if study.sweep is not None:       # the sweep's stroke radius is the arm L78
        assert study.sweep.stroke_radius == dims()[arm]
    for key in keys:
        j = params.index(key)
        want = mpt.central_difference(angles, dims(), key, arm)
        for m, w in zip(("stroke", "dwell_error"), want):
            got = a.sensitivity[a.metrics.index(m), j]
            scale = abs(a.nominal[a.metrics.index(m)])
            assert got == pytest.approx(w, rel=1e-6, abs=1e-9 * scale), (key, m, got, w)
            assert a.checked[a.metrics.index(m), j]


def test_builds_that_cannot_assemble_are_counted_not_dropped():
    study = fourbar_study()
    spec = ToleranceSpec(overrides=(("RRR[1].L_CB", 30.0, "uniform"),), samples=512)
    a = analyse(study, study.mechanism, spec)
    failed = a.status != kc.OK
    assert 0 < failed.sum() < len(failed)
    assert len(a.status) == 512 and np.isnan(a.values[failed]).all()
    assert a.yield_ == pytest.approx(1.0 - failed.mean())
    assert not a.meets[failed].any()
    # the crank (15) swings B from 23 to 53 mm of D: the coupler (41) and a rocker
    # L_CB outside [41 - 23, 41 + 23] mm cannot close the loop over the whole revolution
    # (the other dimensions' own tolerances blur the two edges a little)
    dev = a.deltas[:, [d.param for d in a.drawn].index("RRR[1].L_CB")]
    assert (failed == ((40.0 + dev < 18.0) | (40.0 + dev > 64.0))).mean() > 0.99


def test_a_sweep_candidate_is_held_to_the_sweep_constraints(synthesis_sweep, tmp_path):
    out = tmp_path / "knee_tol.h5"
    assert main(["tolerance", str(synthesis_sweep), "--candidate", "knee", "--samples", "512",
                 "-o", str(out), "-q"]) == 0
    with h5py.File(out, "r") as f:
        assert f.attrs["kind"] == "tolerance" and f.attrs["candidate"] != "reference"
        status = f["builds/status"][()]
        metrics = [x.decode() for x in f["summary/metric"][()]]
        stroke = f["builds/stroke"][()]
        meets = f["builds/meets"][()].astype(bool)
        margin = f["builds/singularity_margin"][()]
        assert status.shape == (512,) and f["builds/deviation"].shape[0] == 512
        assert {"stroke", "dwell_error", "peak_reaction"} <= set(metrics)
        assert f["sensitivity/stroke"].attrs["units"][0].endswith("mm/mm")
        assert float(f.attrs["yield"]) == pytest.approx(meets.mean())
        assert [x.decode() for x in f["constraints/metric"][()]] == ["stroke",
                                                                        "singularity_margin"]
    study = mech_b_study()
    lo, hi = study.sweep.stroke_bounds
    assert (meets == ((status == kc.OK) & (stroke >= lo) & (stroke <= hi)
                      & (margin >= study.sweep.margin_min))).all()
    assert (tmp_path / "knee_tol_histograms.png").stat().st_size > 10_000
    assert (tmp_path / "knee_tol_tornado.png").stat().st_size > 10_000
    # an earlier result is never replaced silently
    assert main(["tolerance", str(synthesis_sweep), "--candidate", "knee", "-o", str(out),
                 "-q"]) == 2


def test_the_file_opens_with_named_coordinates(synthesis_sweep, tmp_path):
    xr = pytest.importorskip("xarray")
    out = tmp_path / "ref_tol.h5"
    assert main(["tolerance", str(synthesis_sweep), "--candidate", "reference", "--samples",
                 "64", "-o", str(out), "-q", "--no-pictures"]) == 0
    ds = xr.open_dataset(out, group="summary", engine="h5netcdf")
    assert "dwell_error" in list(ds["metric"].values.astype(str))
    assert ds["std"].sel(metric="stroke") > 0
    sens = xr.open_dataset(out, group="sensitivity", engine="h5netcdf")
    assert sens["stroke"].sel(dimension="triad.L23") > 0


@pytest.mark.parametrize("section, field, words", [
    ('[tolerance.dimensions]\n"triad.L99" = 0.1', "tolerance.dimensions.'triad.L99'",
     "no toleranced dimension"),
    ('[tolerance.dimensions]\nL23 = -0.1', "tolerance.dimensions.L23", ">= 0"),
    ('[tolerance.dimensions]\nL23 = 40.0', "tolerance.dimensions.L23",
     "not a manufacturing tolerance"),
    ('[tolerance]\ndistribution = "triangular"', "tolerance.distribution", "normal, uniform"),
    ('[tolerance.constraints]\nstroke = { min = 1 }', "tolerance.constraints",
     "[sweep.constraints]"),
])
def test_a_wrong_tolerance_section_is_one_line_naming_the_field(section, field, words):
    from pipeline.base.errors import StudyError
    text = (STUDIES / "ov7_synthesis.toml").read_text()
    if not section.startswith("[tolerance]"):
        section = "[tolerance]\n" + section
    with pytest.raises(StudyError) as e:
        parse_study(text + "\n" + section + "\n", "s.toml")
    msg = str(e.value)
    assert field in msg and words in msg and "\n" not in msg


def test_study_tolerances_and_iso_defaults():
    study = parse_study((STUDIES / "ov7_synthesis.toml").read_text()
                        + '\n[tolerance]\nclass = "m"\n[tolerance.dimensions]\nL23 = 0.05\n'
                          '"P6.x" = { tolerance = 0.1, distribution = "uniform" }\n', "s.toml")
    dims = {d.param: d for d in study.tolerance.dimensions(study.mechanism)}
    assert dims["triad.L23"].tolerance == 0.05 and dims["triad.L23"].source == "study"
    assert dims["P6.x"].distribution == "uniform"
    assert dims["P6.x"].sigma == pytest.approx(0.1 / math.sqrt(3))
    assert dims["crank.length"].tolerance == 0.3          # ISO 2768-m, 30-120 mm
    assert dims["triad.L57"].tolerance == 0.5             # 120-400 mm
    assert dims["P1.x"].tolerance == 0.0                  # the datum
    assert dims["crank.phiM0"].tolerance == 0.0           # timed at assembly
    assert dims["output arm.angle"].tolerance == pytest.approx(10 / 60)  # leg 136.8 mm
    # a candidate's own sizes choose its classes
    from pipeline.study.sweep_spec import apply_design
    x = np.array([v.high for v in study.sweep.variables])
    big = apply_design(study.mechanism, study.sweep, x)
    cand = {d.param: d for d in study.tolerance.dimensions(big)}
    assert cand["triad.L23"].nominal == pytest.approx(272.5 * 1.2)
    assert replace(cand["crank.length"]).tolerance == 0.3


def robust_study():
    return parse_study((STUDIES / "ov7_robust_search.toml").read_text(),
                       STUDIES / "ov7_robust_search.toml")


def test_robust_metrics_are_the_quantile_and_the_yield_of_the_designs_builds():
    """The reference design's robust columns against its own tolerance analysis
    with the same draws (64 builds, seed 1, the 95th percentile); a design that
    fails its constraints nominally carries none."""
    from pipeline.model.metric_catalogue import metric_values
    from pipeline.runs.sweep import build_problem
    study = robust_study()
    spec = replace(study.sweep, metrics=study.sweep.metrics + ("build_yield",))
    problem = build_problem(study, spec)
    ref = problem.plan.par
    short = ref.copy()
    short[problem.plan.param("crank.length")] *= 0.5       # half the stroke: infeasible
    status, rows = problem.evaluate_rows(np.stack([ref, short]))
    a = analyse(study, study.mechanism, replace(study.tolerance, samples=64),
                sweep_spec=study.sweep)
    k = a.metrics.index("dwell_error")
    want = np.quantile(np.where(a.status == kc.OK, a.values[:, k], np.inf), 0.95)
    assert metric_values(rows, "robust_dwell_error")[0] == want
    assert metric_values(rows, "build_yield")[0] == a.yield_
    assert metric_values(rows, "dwell_error")[0] < want
    assert np.isnan(metric_values(rows, "robust_dwell_error")[1])
    assert np.isnan(metric_values(rows, "build_yield")[1])


def test_a_sweep_with_a_robust_objective_says_which_designs_carry_it(tmp_path):
    from pipeline.runs.sweep import run_sweep
    study = robust_study()
    study = replace(study, search=None)
    out = tmp_path / "robust_sweep.h5"
    run_sweep(study, out, candidates=300, chunk_size=300, progress=False)
    with h5py.File(out, "r") as f:
        r = f["metrics/robust_dwell_error"][()]
        nominal = f["metrics/dwell_error"][()]
        feasible = f["candidates/feasible"][()].astype(bool)
        assert "builds" in f["metrics/robust_dwell_error"].attrs["long_name"]
    assert feasible.any() and np.isfinite(r[feasible]).all()
    assert (r[feasible] > nominal[feasible]).mean() > 0.9       # builds are worse, mostly
    assert np.isnan(r[~np.isfinite(nominal)]).all()


def test_the_metrics_of_the_builds_can_be_chosen(tmp_path, capsys):
    """--metrics (or [tolerance] metrics): stroke and dwell error alone skip the
    force stage, and give the same numbers as the whole analysis."""
    out = tmp_path / "k.h5"
    study = STUDIES / "ov7_class3.toml"
    assert main(["tolerance", str(study), "--metrics", "dwell_error", "--samples", "128",
                 "-o", str(out), "-q", "--no-pictures"]) == 0
    whole = tmp_path / "w.h5"
    assert main(["tolerance", str(study), "--samples", "128", "-o", str(whole), "-q",
                 "--no-pictures"]) == 0
    with h5py.File(out, "r") as f, h5py.File(whole, "r") as g:
        assert [x.decode() for x in f["summary/metric"][()]] == ["stroke", "dwell_error"]
        np.testing.assert_array_equal(f["builds/dwell_error"][()], g["builds/dwell_error"][()])
    assert main(["tolerance", str(study), "--metrics", "peak_joint", "-o",
                 str(tmp_path / "x.h5")]) == 2
    assert "not a metric of a build" in capsys.readouterr().err


def test_a_candidate_of_a_sweep_that_bounds_its_yield_is_toleranced(tmp_path):
    """A sweep whose constraints bound a robust metric (build_yield): its
    candidates' builds are held to the other constraints (a build has no
    builds of its own)."""
    from pipeline.runs.sweep import run_sweep
    text = (STUDIES / "ov7_robust_search.toml").read_text().replace("singularity_margin_min = 0.3",
                              "singularity_margin_min = 0.3\nbuild_yield = { min = 0.5 }")
    study = replace(parse_study(text, STUDIES / "ov7_robust_search.toml"), search=None)
    out = tmp_path / "y.h5"
    run_sweep(study, out, candidates=200, chunk_size=200, progress=False)
    with h5py.File(out, "r") as f:
        y = f["metrics/build_yield"][()]
        feasible = f["candidates/feasible"][()].astype(bool)
    assert (y[feasible] >= 0.5).all()
    assert main(["tolerance", str(out), "--candidate", "reference", "--samples", "64", "-o",
                 str(tmp_path / "t.h5"), "-q", "--no-pictures"]) == 0
    with h5py.File(tmp_path / "t.h5", "r") as f:
        assert "build_yield" not in [x.decode() for x in f["constraints/metric"][()]]
