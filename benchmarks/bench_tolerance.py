"""Tolerance analysis of mechanism B (issue 30): 10,000 builds within ISO
2768-f, every metric of the sweep (forces too) for every build, beside the
nominal sweep's throughput on the same machine, in the same process.

    python benchmarks/bench_tolerance.py [--smoke] [-o DIR]

Measures, after a first call that compiles (or loads the cache), reported
apart:

* the nominal sweep: ``SweepProblem.evaluate_rows`` of the default synthesis
  (studies/ov7_synthesis.toml) on 10,000 of its Sobol draws, all cores:
  candidates/s (the force stage only for candidates within the stroke and
  margin limits, as a sweep runs);
* the whole analysis ``pipeline.runs.tolerance.analyse`` of mechanism B with
  10,000 builds (draws, every metric of every build, the yield, the
  sensitivities and the one-at-a-time runs): wall seconds, and the builds/s
  of its evaluation alone, as a ratio to the sweep's candidates/s;
* the same with the kinematic metrics only (stroke, dwell error, margin:
  ``[tolerance] metrics`` or ``--metrics``), which need no force stage.

Writes tolerance.md into DIR (default results/bench/).  --smoke: 256 builds
and 512 sweep candidates, seconds, for the test suite (no figure to hold).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path


from common import ROOT, STUDIES, best_of, first_call, hardware, smoke_main

BUILDS = 10_000
TARGET_S = 1.0          # issue 30: 10,000 builds of mechanism B in at most 1 s


def run(smoke=False, out=None, echo=print):
    from pipeline.runs.sweep import build_problem
    from pipeline.runs.builds import BuildEvaluator, build_rows, deviations
    from pipeline.runs.tolerance import analyse
    from pipeline.study.reader import load_study
    from pipeline.study.sampling import draw_checked
    from pipeline.study.sweep_spec import parameter_rows
    from pipeline.study.tolerance_spec import ToleranceSpec, drawn
    builds = 256 if smoke else BUILDS
    study = load_study(STUDIES / "ov7_synthesis.toml")
    spec = replace(study.sweep, candidates=512 if smoke else BUILDS,
                   chunk_size=512 if smoke else BUILDS)
    problem = build_problem(study, spec)
    x, _ = draw_checked(spec, 0)
    pars = parameter_rows(problem.plan, spec, x)
    compile_sweep = first_call(lambda: problem.evaluate_rows(pars[:8]))
    sweep_s = best_of(lambda: problem.evaluate_rows(pars), 1 if smoke else 3)
    sweep_rate = len(pars) / sweep_s

    tol = ToleranceSpec(samples=builds)
    compile_tol = first_call(lambda: analyse(study, study.mechanism, tol, samples=8,
                                             sweep_spec=study.sweep))
    whole_s = best_of(lambda: analyse(study, study.mechanism, tol, sweep_spec=study.sweep),
                      1 if smoke else 3)
    kin = replace(tol, metrics=("stroke", "dwell_error", "singularity_margin"))
    analyse(study, study.mechanism, kin, samples=8, sweep_spec=study.sweep)
    kin_s = best_of(lambda: analyse(study, study.mechanism, kin, sweep_spec=study.sweep),
                    1 if smoke else 3)
    ev = BuildEvaluator(study, study.mechanism)
    dims = drawn(tol.dimensions(study.mechanism))
    rows = build_rows(ev.plan, ev.plan.par, dims, deviations(dims, builds, tol.seed))
    eval_s = best_of(lambda: ev(rows), 1 if smoke else 3)
    build_rate = builds / eval_s
    lines = ["# Tolerance analysis of mechanism B" + (" (smoke run)" if smoke else ""), "",
             f"hardware: {hardware()}", "",
             "| measurement | value |", "|---|---|",
             f"| first call of the sweep's kernels (compile or cache load) | {compile_sweep:.2f} s |",
             f"| first tolerance analysis, 8 builds (compile or cache load) | {compile_tol:.2f} s |",
             f"| nominal sweep, {len(pars):,} candidates | {sweep_s:.3f} s, "
             f"{sweep_rate:,.0f} candidates/s |",
             f"| tolerance analysis, {builds:,} builds, whole | {whole_s:.3f} s "
             f"(target {TARGET_S:g} s for {BUILDS:,}) |",
             f"| its evaluation alone (every metric, forces of every build) | {eval_s:.3f} s, "
             f"{build_rate:,.0f} builds/s |",
             f"| builds/s : nominal sweep candidates/s | {build_rate / sweep_rate:.2f} |",
             f"| tolerance analysis, {builds:,} builds, stroke, dwell error and margin only "
             f"(`--metrics`: no force stage), whole | {kin_s:.3f} s |", ""]
    text = "\n".join(lines)
    echo(text)
    out = Path(out) if out else ROOT / "results" / "bench"
    out.mkdir(parents=True, exist_ok=True)
    (out / "tolerance.md").write_text(text + "\n")
    return {"whole_s": whole_s, "eval_s": eval_s, "sweep_rate": sweep_rate, "kinematic_s": kin_s,
            "build_rate": build_rate, "builds": builds}


if __name__ == "__main__":
    smoke_main(run, __doc__, "tolerance.md")
