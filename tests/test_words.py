"""Words a newcomer reads (issue 55, item 4): joints by their names in every
table, no unit "1" after a pure number, analyze's summary with units, a
misspelt command answered with the nearest one, and the tolerance classes a
robust search and `pipeline tolerance --candidate` use, each said."""

import logging

import pytest

import pipeline
from pipeline.analysis.fronts import analyze
from pipeline.api import load_study
from pipeline.cli import main
from pipeline.runner import tolerance_summary
from pipeline.runs.builds import robust_for
from pipeline.runs.sweep import run_sweep
from pipeline.views.browse import browse
from pipeline.views.tables import candidates as sweep_table


@pytest.fixture(scope="module")
def swept(studies, tmp_path_factory):
    out = tmp_path_factory.mktemp("words") / "sweep.h5"
    run_sweep(load_study(studies / "ov7_synthesis.toml"), out, candidates=200, progress=False)
    return out


def test_a_misspelt_command_gets_the_nearest(capsys):
    with pytest.raises(SystemExit) as e:
        main(["analyse", "results/x.h5"])
    assert e.value.code == 2
    assert "unknown command 'analyse'; did you mean 'analyze'?" in capsys.readouterr().err


def test_tables_name_the_peak_joint_as_the_joints_are_named(swept):
    df = sweep_table(swept)
    named = df["peak_joint"][df["peak_joint"] != ""]
    assert len(named) and set(named) <= {f"R{k}" for k in range(1, 8)}
    assert df.attrs["units"]["peak_joint"] == ""
    i = int(df[df["feasible"]]["candidate"].iloc[0])
    text = browse(swept, candidate=i, wide=True)
    line = next(x for x in text.splitlines() if x.strip().startswith("peak_joint ="))
    assert line.split("=")[1].split()[0] == df.set_index("candidate").at[i, "peak_joint"]
    for name in ("dwell_error", "newton_iterations", "singularity_margin"):
        line = next(x for x in text.splitlines() if x.strip().startswith(f"{name} ="))
        assert line.split("=")[1].split()[1] != "1", line     # no unit "1" after the number


def test_analyze_says_its_units(swept):
    s = analyze(swept)
    assert "peak_reaction" in s["knee"] and s["knee"].endswith(" N")


def test_each_tolerance_analysis_says_which_classes(studies, caplog):
    study = load_study(studies / "ov7_robust_search.toml")
    with caplog.at_level(logging.INFO, logger="pipeline.runs.builds"):
        robust_for(study, study.sweep)
    said = " ".join(r.getMessage() for r in caplog.records)
    assert "ISO 2768-f at the reference design's sizes for every design" in said
    a = pipeline.tolerance(studies / "ov7_class3.toml", samples=64)
    assert "ISO 2768-f at this design's own sizes" in tolerance_summary(a)["builds"]
