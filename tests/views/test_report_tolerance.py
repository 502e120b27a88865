"""The report's tolerance section reads the designs' tolerance files (``pipeline
tolerance FILE --candidate ID``) and never runs a tolerance analysis itself:
without a file it names the command that writes one."""

import shlex

import h5py
import pytest

from pipeline.cli import main


@pytest.fixture
def analysed_sweep(synthesis_sweep, tmp_path):
    """A copy of the session's sweep with its analysis, and (analysis, data)."""
    from pipeline.analysis.fronts import analyze, has_analysis, read_analysis, read_sweep
    from pipeline.results.storage import open_results
    from support.sweep_helpers import copy_of
    p = copy_of(synthesis_sweep, tmp_path / "sweep", "s.h5")
    with open_results(p, "sweep") as f:
        done = has_analysis(f)
    if not done:
        analyze(p)
    with open_results(p, "sweep") as f:
        ana = read_analysis(f)
    return p, ana, read_sweep(p)


def _no_analysis(monkeypatch):
    """Any tolerance analysis (or any build of one) from here on fails the test."""
    from pipeline.runs import builds, tolerance

    def refuse(*a, **k):
        raise AssertionError("the report ran a tolerance analysis")
    monkeypatch.setattr(tolerance, "analyse", refuse)
    monkeypatch.setattr(builds.BuildEvaluator, "__init__", refuse)


def test_without_a_tolerance_file_the_report_names_the_command(analysed_sweep, monkeypatch):
    from pipeline.views import report
    p, ana, data = analysed_sweep
    _no_analysis(monkeypatch)
    section = report.tolerance_html(p, ana, data)
    knee = str(data.id(ana.knee))
    assert section.count("<p") == 1 and "<table" not in section
    assert f"<code>pipeline tolerance {shlex.quote(str(p))} --candidate {knee}</code>" in section


def test_the_report_shows_the_knee_s_tolerance_file(analysed_sweep, monkeypatch):
    from pipeline.views import report
    p, ana, data = analysed_sweep
    knee = str(data.id(ana.knee))
    out = p.with_name(f"s_candidate{knee}_tolerance.h5")    # where the command writes it
    assert main(["tolerance", str(p), "--candidate", "knee", "--samples", "32",
                 "--metrics", "stroke,dwell_error", "--no-pictures", "-q"]) == 0
    assert out.exists()
    _no_analysis(monkeypatch)
    monkeypatch.setattr(report, "EXPLORER_DRAWINGS", 1)      # the test's time, not the page's
    page = report.build_html(p, drawings=0)
    section = page.split("<h2>How the designs hold up when made</h2>")[1].split("<h2>")[0]
    with h5py.File(out, "r") as f:
        metrics = [m.decode() for m in f["summary/metric"][()]]
        k = metrics.index("stroke")
        values = [f[f"summary/{key}"][k] for key in ("nominal", "p05", "p95")]
        yield_, builds = float(f.attrs["yield"]), f["builds/status"].shape[0]
    row = section.split(f"candidate #{knee} (knee)")[1].split("</tr>")[0]
    assert f"{100 * yield_:.1f} % of {builds}" in row
    fmt = report._fmt
    assert f"{fmt(values[0])} [{fmt(values[1])}, {fmt(values[2])}]" in row
    assert "peak_reaction" not in row and "&ndash;" in row    # not asked of these builds
    assert 'aria-label="the knee&#x27;s builds"' in section     # its distributions drawn
    # the other designs have no file: the command for each
    assert f"--candidate reference</code>" in section
