"""The HTML report of a sweep (issue 28): how long its explorer takes to build
(every feasible design gathered, the cycle of front 1, the knee and the
reference design re-run as scenes and written as data for plotly.js) and how
long the whole report takes, on the main job's 250,000 candidates
(studies/ov7_synthesis.toml), and how large the page is.

    python benchmarks/bench_report.py [--smoke] [-o DIR] [--file RESULTS.h5]

Measures, in one process, after a first call that compiles (or loads the
cache of) the scene path's kernels, reported apart:

* the explorer (``views.explorer.explorer_html``): its first call and its
  steady state (best of 3), against the issue's target of 5 s;
* one embedded design: its re-run and data now, against its re-run and the
  matplotlib picture the explorer embedded before (``show.candidate_figure``
  as a 60-dpi PNG), the baseline, as a ratio;
* the whole report (``views.report.build_html``: pictures, explorer,
  importances, representatives, tolerances, comparison, animation): first
  call and steady state, and the page's size with the plotly.js bundle's share.

Without --file the sweep is run first (not timed) into a temporary folder and
analyzed.  Writes report.md into DIR (default results/bench/).  --smoke: a
2,000-candidate sweep (or the file given), one repeat, one whole report (its
first call), for the test suite.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from common import ROOT, STUDIES, best_of, first_call, hardware

CANDIDATES = 250_000
SMOKE_CANDIDATES = 2_000
TARGET_S = 5.0          # issue 28: the explorer, and the report, of 250,000 candidates in 5 s


def sweep_file(folder, candidates):
    """The main job's sweep with ``candidates`` candidates, analyzed, in ``folder``."""
    from pipeline.analysis.fronts import analyze
    from pipeline.runs.sweep import run_sweep
    from pipeline.study.reader import load_study
    out = Path(folder) / "ov7_synthesis.h5"
    run_sweep(load_study(STUDIES / "ov7_synthesis.toml"), out, candidates=candidates,
              progress=False)
    analyze(out)
    return out


def _loaded(path):
    from pipeline.analysis.fronts import read_analysis, read_sweep
    from pipeline.results.storage import open_results
    data = read_sweep(path)
    with open_results(path, "sweep") as f:
        ana = read_analysis(f)
    return data, ana


def _per_design(path, rows):
    """Seconds per design: (re-run + data now, re-run + PNG before)."""
    from pipeline.analysis.candidate import rerun_candidate
    from pipeline.views.explorer_designs import design_cycle
    from pipeline.views.report_figures import _png
    from pipeline.views.show import candidate_figure
    t = time.perf_counter()
    for r in rows:
        design_cycle(rerun_candidate(path, int(r), forces=True))
    now = (time.perf_counter() - t) / len(rows)
    t = time.perf_counter()
    for r in rows:
        _png(candidate_figure(rerun_candidate(path, int(r))), dpi=60)
    before = (time.perf_counter() - t) / len(rows)
    return now, before


def run(smoke=False, out=None, echo=print, source=None):
    """The measurements (a dict), written as report.md into ``out``; ``source``:
    an analyzed sweep file to use instead of running the sweep."""
    from pipeline.analysis.fronts import analyze
    from pipeline.results.storage import open_results
    from pipeline.analysis.fronts import has_analysis
    from pipeline.views import explorer as ex
    from pipeline.views.page import plotly_js
    from pipeline.views.report import build_html
    repeat = 1 if smoke else 3
    with tempfile.TemporaryDirectory() as tmp:
        if source is None:
            path = sweep_file(tmp, SMOKE_CANDIDATES if smoke else CANDIDATES)
        else:
            path = Path(source)
            with open_results(path, "sweep") as f:
                ready = has_analysis(f)
            if not ready:
                analyze(path)
        data, ana = _loaded(path)

        first_explorer = first_call(lambda: ex.explorer_html(path, data, ana))
        page = {}

        def explorer():
            page["explorer"] = ex.explorer_html(path, data, ana)
        explorer_s = best_of(explorer, repeat)
        payload, _, _ = ex.explorer_payload(path, data, ana)
        n_designs = len(payload["designs"])
        sample = list(ana.front1[:1 if smoke else 5])
        now_s, before_s = _per_design(path, sample) if sample else (float("nan"),) * 2

        def whole():
            page["html"] = build_html(path)
        first_report = first_call(whole)
        # a smoke run builds the whole report once (its first call: seconds of
        # tolerances, comparison and animation that are not the explorer's)
        report_s = first_report if smoke else best_of(whole, 2)
    size = len(page["html"].encode())
    bundle = len(str(plotly_js()).encode())
    n_points = payload["ids"]["length"]
    lines = ["# The HTML report's explorer and the whole report" + (" (smoke run)" if smoke else ""),
             "", f"hardware: {hardware()}", "",
             f"sweep: {data.n:,} candidates, {int(data.feasible.sum()):,} feasible, "
             f"{ana.front1.size} on front 1; the explorer holds {n_points:,} designs "
             f"({payload['counts']['feasible_shown']:,} feasible, "
             f"{payload['counts']['infeasible_shown']:,} infeasible for 'all'), "
             f"{len(payload['columns'])} columns, {n_designs} designs with their cycle", "",
             "| measurement | value |", "|---|---|",
             f"| explorer, first call (scene kernels compiled or loaded) | {first_explorer:.2f} s |",
             f"| explorer, steady state (best of {repeat}) | {explorer_s:.2f} s "
             f"(target {TARGET_S:g} s for {CANDIDATES:,} candidates) |",
             f"| one design embedded now: re-run with reactions + data | {1000 * now_s:.0f} ms |",
             f"| one design embedded before: re-run + matplotlib PNG (baseline) | "
             f"{1000 * before_s:.0f} ms |",
             f"| before : now, per design | {before_s / now_s:.1f} |",
             f"| whole report, first call | {first_report:.1f} s |",
             "| whole report, steady state (best of 2) | " + (
                 "not measured in a smoke run |" if smoke else
                 f"{report_s:.1f} s (target {TARGET_S:g} s for {CANDIDATES:,} candidates) |"),
             f"| page | {size / 2 ** 20:.1f} MiB, of which plotly.js (packed) "
             f"{bundle / 2 ** 20:.1f} MiB "
             f"and the explorer's section {len(page['explorer'].encode()) / 2 ** 20:.1f} MiB |",
             ""]
    text = "\n".join(lines)
    echo(text)
    out = Path(out) if out else ROOT / "results" / "bench"
    out.mkdir(parents=True, exist_ok=True)
    (out / "report.md").write_text(text + "\n")
    return {"explorer_s": explorer_s, "first_explorer_s": first_explorer, "report_s": report_s,
            "first_report_s": first_report, "page_bytes": size, "points": n_points,
            "designs": n_designs, "per_design_s": now_s, "per_design_before_s": before_s}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--smoke", action="store_true", help="tiny sizes (seconds), for the suite")
    ap.add_argument("-o", "--output", help="folder for report.md (default results/bench/)")
    ap.add_argument("--file", help="an analyzed sweep file to use instead of running the "
                                   f"sweep ({CANDIDATES:,} candidates; --smoke: "
                                   f"{SMOKE_CANDIDATES:,})")
    a = ap.parse_args()
    import logging
    logging.basicConfig(level=logging.WARNING, format="%(message)s")
    import matplotlib
    matplotlib.use("Agg")
    run(a.smoke, a.output, source=a.file)


if __name__ == "__main__":
    main()
