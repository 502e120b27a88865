"""A sweep's constraints are the ones its study states (issue 55, item 2): a
study without [sweep.constraints] holds its designs to none (no OV-7 stroke
window assumed), its summary says so, and analyze never puts an infeasible
design on a front."""

import math

import pytest

from pipeline.analysis.fronts import analyze
from pipeline.api import load_study
from pipeline.runs.sweep import run_sweep

# mechanism D (a four-bar whose rocker swings about 45 mm at 60 mm): far from the
# OV-7 eyelet's 11-15 mm, which a hidden default would have held it to
SWEEP = """
[sweep]
candidates = 40
seed = 3
positions = 72
chunk_size = 20
stroke_radius = 60.0
objectives = ["dwell_error", "peak_reaction"]

[sweep.variables]
crank = { param = "crank.length", min = 13.0, max = 16.0 }
"""


def four_bar_sweep(studies, folder, constraints=""):
    text = (studies / "warp_feed_fourbar.toml").read_text()
    text = text.replace('kind = "scene"', 'kind = "sweep"')
    text = text.replace('analysis = "forces"', 'analysis = "forces"\nrocker = ["P4", "P3"]')
    path = folder / "fourbar_sweep.toml"
    path.write_text(text + SWEEP + constraints)
    return load_study(path)


@pytest.fixture(scope="module")
def unconstrained(studies, tmp_path_factory):
    folder = tmp_path_factory.mktemp("free")
    study = four_bar_sweep(studies, folder)
    out = folder / "sweep.h5"
    return study, out, run_sweep(study, out, progress=False).summary


def test_a_sweep_without_constraints_has_none(unconstrained):
    study, _, summary = unconstrained
    spec = study.sweep
    assert spec.stated_constraints(has_margin=True) == ()
    assert spec.stroke_bounds == (-math.inf, math.inf) and spec.margin_min == -math.inf
    assert summary["constraints"].startswith("none given ([sweep.constraints])")
    ok = int(summary["status OK"].split()[0])
    assert ok > 0 and int(summary["feasible"].split()[0]) == ok


def test_analyze_ranks_the_designs_of_a_sweep_without_constraints(unconstrained):
    _, out, _ = unconstrained
    s = analyze(out)
    assert s["feasible"] > 0 and s["front 1"] > 0 and "note" not in s
    assert s["reference design"].startswith("front ")


def test_a_stated_window_is_said_and_no_infeasible_design_is_on_a_front(studies, tmp_path):
    """The OV-7 window stated for the four-bar: nothing meets it; the summaries
    say which constraints and that there is no front, and the reference design
    (infeasible too) is on none."""
    study = four_bar_sweep(studies, tmp_path, "\n[sweep.constraints]\nstroke = [11.0, 15.0]\n")
    out = tmp_path / "sweep.h5"
    summary = run_sweep(study, out, progress=False).summary
    assert summary["constraints"] == "11 <= stroke <= 15 mm"
    assert summary["feasible"].startswith("0 ")
    s = analyze(out)
    assert s["feasible"] == 0 and s["front 1"] == 0
    assert s["note"] == ("no candidate is feasible, so there is no front: the constraints are "
                         "11 <= stroke <= 15 mm")
    assert s["reference design"].startswith("infeasible (stroke ")
    assert "front 1" not in s["reference design"].split(";")[0]
    assert "on no front" in s["reference design"]


def test_the_ov7_studies_state_their_window(studies):
    """The window the OV-7 designs are held to is in their own files."""
    for name in ("ov7_synthesis", "ov7_synthesis_law", "ov7_search", "ov7_robust_search"):
        spec = load_study(studies / f"{name}.toml").sweep
        assert spec.stated_constraints(has_margin=True)[:2] == (
            ("stroke", 11.0, 15.0), ("singularity_margin", 0.3, math.inf)), name
