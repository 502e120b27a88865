"""Throughput table (issue: run time against error; item 2): the project's
compiled kernels against a plain NumPy and a pure-Python baseline
(``baselines.py``), all in this process, for

1. four-bar positions (mechanism D, open configuration),
2. mechanism B full kinematics (positions, first and second analogs of P2, P3,
   P4, P5, P8 over a revolution),
3. the full sweep of the synthesis study (positions, dwell error, stroke,
   singularity margin; forces and peak reaction for the candidates meeting the
   constraints), on the sweep's own candidates.

Correct first, then timed: before any steady-state timing every baseline is
compared with the project on a few candidates (positions to 1e-9 mm, analogs
to 1e-8 relative, dwell error and stroke to 1e-9, peak reaction to 1e-6
relative, the same candidates accepted) and the run stops if they disagree;
after the timing the timed outputs are compared again, in full.  The project
is the mechanism compiler's generated kernels
(``pipeline.compiler.kernels_for``: one module per mechanism).  The project's
first call (compile, or load from numba's cache, plus one tiny run) is
reported apart from its steady state (best of a few calls, on all threads and
on one); ``--cold`` adds the generation and compile with empty caches
(``PIPELINE_CACHE_DIR`` and ``NUMBA_CACHE_DIR``), measured in a fresh process.
The project's kernels run on the mechanisms without their bodies (no hidden
centres of mass) for cases 1 and 2, so that both sides compute the same
points.

    python benchmarks/bench_throughput.py [--quick] [--cold]

``--quick`` takes about half a minute on a busy 2-core box, the default sizes
about two minutes.  Writes results/bench/throughput.csv (one row per case and
implementation, with the hardware); ``run(quick)`` returns the table as a
DataFrame (the checks' worst deviations in ``df.attrs["checks"]``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import baselines as bl  # noqa: E402
from common import ROOT, STUDIES, best_of, first_call, hardware, perturbed_rows  # noqa: E402

CSV = ROOT / "results" / "bench" / "throughput.csv"
POSITIONS = 360
D_VARS = ("crank.length", "RRR[1].L_AB", "RRR[1].L_CB", "P4.x")

# candidates per case and implementation, and repeats of the steady-state timing
# (project, NumPy, pure Python); the NumPy baselines keep every position in memory
SIZES = {
    # --quick is the suite's smoke run (it must not rot, it need not measure well):
    # the pure-Python baseline, the slowest by far, on a handful of candidates
    True: {"four-bar": (10_000, 2_000, 10), "kinematics": (1_000, 400, 10),
           "sweep": (1_000, 400, 10), "repeat": 1},
    False: {"four-bar": (40_000, 10_000, 200), "kinematics": (10_000, 1_000, 100),
            "sweep": (20_000, 5_000, 200), "repeat": 3},
}

TOL_POS = 1e-9          # mm
TOL_ANALOG = 1e-8       # relative to the largest |analog| of that point over the revolution
TOL_METRIC = 1e-9       # dwell error (1), stroke (mm), margin (1)
TOL_PEAK = 1e-6         # relative


class BaselineMismatch(RuntimeError):
    """A baseline does not compute what the project computes."""


# ----------------------------------------------------------------- helpers
def _kinematic_study(study, strip=True):
    """The study with its mechanism stripped of bodies and loads: the points a
    baseline computes, nothing more (no hidden centres of mass).  ``strip``
    False (--quick, the suite's smoke run): the study as it is, so that its
    kernels are the shipped study's own, which the suite compiles anyway (two
    modules of their own cost 25-30 s of a cold suite), at the price of timings
    that include the hidden centres of mass."""
    if not strip:
        return study
    mech = dataclasses.replace(study.mechanism, bodies=(), loads=(), slides=())
    return dataclasses.replace(study, mechanism=mech)


def _rows_for(plan_small, plan_full, pars):
    """Parameter rows of ``plan_full`` cut to ``plan_small`` (its leading columns)."""
    k = len(plan_small.par_names)
    if plan_full.par_names[:k] != plan_small.par_names:
        raise BaselineMismatch("the kinematic plan's parameters are not a prefix of the full plan's")
    return np.ascontiguousarray(pars[:, :k])


def _first_call(kernel, fn):
    """Seconds of the first call and what it was: 'compile' or 'cache load'."""
    before_hit = sum(kernel.stats.cache_hits.values())
    before_miss = sum(kernel.stats.cache_misses.values())
    secs = first_call(fn)
    if sum(kernel.stats.cache_misses.values()) > before_miss:
        how = "compile"
    elif sum(kernel.stats.cache_hits.values()) > before_hit:
        how = "cache load"
    else:
        how = "already loaded"
    return secs, how


def _threads():
    import numba
    return numba.get_num_threads()


def _project_timings(fn, repeat):
    """Steady-state seconds of ``fn`` on all threads and on one thread."""
    import numba
    secs = best_of(fn, repeat)
    threads = numba.get_num_threads()
    one = math.nan
    if threads > 1:
        try:
            numba.set_num_threads(1)
            one = best_of(fn, repeat)
        finally:
            numba.set_num_threads(threads)
    return secs, one


def _fail(case, what, value, tol):
    raise BaselineMismatch(f"{case}: {what} differs from the project by {value:.3g} "
                           f"(allowed {tol:g}); the baseline is wrong and no table is written")


CHECKS = []     # (case, what, worst deviation, allowed) of the current run


def _check(case, what, value, tol):
    CHECKS.append((case, what, float(value), tol))
    if not (value <= tol):
        _fail(case, what, value, tol)


def _relative(x, ref, axis):
    """max |x - ref| / max |ref| over ``axis`` (per candidate and point), worst case."""
    scale = np.max(np.abs(ref), axis=axis)
    return float(np.max(np.max(np.abs(x - ref), axis=axis) / np.where(scale > 0, scale, 1.0)))


# ----------------------------------------------------------------- case 1: four-bar
def four_bar_case(sizes, repeat, rows, strip=True):
    from pipeline.compiler import kernels_for
    from pipeline.solve.scene import batch_revolutions, revolution_angles, solve_curves
    from pipeline.study.reader import load_study
    n_proj, n_np, n_py = sizes
    study = _kinematic_study(load_study(STUDIES / "warp_feed_fourbar.toml"), strip)
    plan = study.mechanism.compile()
    phis = revolution_angles(study.mechanism.crank, POSITIONS)
    pars = perturbed_rows(plan, D_VARS, n_proj, spread=0.02, seed=1)
    w = int(plan.par[plan.param("RRR[1].W")])
    params = bl.fourbar_params(plan, pars)
    run = lambda p: batch_revolutions(study, p, POSITIONS, 0, False)
    first, how = _first_call(kernels_for(plan).batch, lambda: run(pars[:2]))

    # correct first: the reference and a few perturbed candidates, every position
    case = "four-bar positions"
    pts = [plan.point(p) for p in ("P2", "P3", "P5")]
    check = np.concatenate([plan.par[None, :], pars[:4]])
    ref = np.stack([solve_curves(plan, phis, 0, par=row).pos[:, pts] for row in check])
    got_np = bl.fourbar_positions_numpy(bl.fourbar_params(plan, check), phis, w)
    got_py = np.asarray(bl.fourbar_positions_python(bl.fourbar_params(plan, check), phis, w))
    _check(case, "NumPy positions [mm]", np.max(np.abs(got_np - ref)), TOL_POS)
    _check(case, "pure-Python positions [mm]", np.max(np.abs(got_py - ref)), TOL_POS)
    k90 = int(np.argmin(np.abs(phis - math.pi / 2)))
    if not (got_np[0, k90, 1, 1] > 0 and ref[0, k90, 1, 1] > 0):
        raise BaselineMismatch(f"{case}: C is not above AD at phi = 90 deg (not the open "
                               "configuration)")

    # then timed
    secs, one = _project_timings(lambda: run(pars), repeat)
    status = run(pars)[0]
    t_np = best_of(lambda: bl.fourbar_positions_numpy(params[:n_np], phis, w), repeat)
    t_py = best_of(lambda: bl.fourbar_positions_python(params[:n_py], phis, w), 1)
    out_np = bl.fourbar_positions_numpy(params[:n_np], phis, w)
    out_py = np.asarray(bl.fourbar_positions_python(params[:n_py], phis, w))
    _check(case, "assembled candidates (timed set)",
           np.sum((status[:n_np] == 0) != np.isfinite(out_np).all(axis=(1, 2, 3))), 0)
    _check(case, "pure Python vs NumPy (timed set) [mm]",
           np.max(np.abs(out_py - out_np[:n_py])), TOL_POS)
    unit = "candidate-positions/s"
    note = (f"positions of B, C, E ({'bodies stripped' if strip else 'bodies kept'}); "
            "NumPy/Python keep every position, the "
            "kernel reduces per candidate")
    rows += [(case, f"project (numba, {_threads()} threads)", n_proj, secs, unit, first, how, note),
             (case, "project (numba, 1 thread)", n_proj, one, unit, math.nan, "", ""),
             (case, "NumPy, vectorized", n_np, t_np, unit, math.nan, "", "closed form"),
             (case, "pure Python", n_py, t_py, unit, math.nan, "", "loops + math")]


# ----------------------------------------------------------------- case 2: class III kinematics
def _draw(study, n, seed_chunk=0):
    """n candidates of the sweep's own sampler: (problem, parameter rows)."""
    from pipeline.runs.sweep import build_problem
    from pipeline.study.sweep_spec import parameter_rows
    from pipeline.study.sampling import draw_candidates
    spec = dataclasses.replace(study.sweep, candidates=n, chunk_size=n)
    pb = build_problem(study, spec)
    return pb, parameter_rows(pb.plan, spec, draw_candidates(spec, seed_chunk))


def kinematics_case(sizes, repeat, rows, strip=True):
    from pipeline.compiler import kernels_for
    from pipeline.solve.scene import batch_revolutions, revolution_angles, solve_curves
    from pipeline.study.reader import load_study
    n_proj, n_np, n_py = sizes
    full = load_study(STUDIES / "ov7_synthesis.toml")
    study = _kinematic_study(full, strip)
    plan = study.mechanism.compile()
    phis = revolution_angles(study.mechanism.crank, POSITIONS)
    run = lambda p: batch_revolutions(study, p, POSITIONS, 2, False)
    # the sweep's candidates that assemble over the whole revolution
    pb, drawn = _draw(full, int(2.2 * n_proj) + 50)
    drawn = _rows_for(plan, pb.plan, drawn)
    first, how = _first_call(kernels_for(plan).batch, lambda: run(drawn[:2]))
    st, _, _ = run(drawn)
    pars = np.ascontiguousarray(drawn[st == 0][:n_proj])
    if pars.shape[0] < n_proj:
        raise BaselineMismatch(f"only {pars.shape[0]} of {drawn.shape[0]} drawn candidates "
                               "assemble; draw more")

    # correct first: the reference design and a few candidates, every position
    case = "mechanism B kinematics"
    names = bl.POINTS_B
    pts = [plan.point(p) for p in names]
    check = np.concatenate([plan.par[None, :], pars[:5]])
    curves = [solve_curves(plan, phis, 2, par=row) for row in check]
    ref = [np.stack([getattr(c, k)[:, pts] for c in curves]) for k in ("pos", "d1", "d2")]
    crow = bl.class3_rows(plan, check)
    s_np, *got_np = bl.class3_kinematics_numpy(crow, phis)
    got_py = bl.class3_kinematics_python(crow, phis)
    s_py = np.array([g[0] for g in got_py])
    got_py = [np.array([g[k] for g in got_py]) for k in (1, 2, 3)]
    proj_ok = np.array([c.overall == 0 for c in curves])
    for label, s, got in (("NumPy", s_np, got_np), ("pure-Python", s_py, got_py)):
        _check(case, f"{label} assembled candidates", np.sum((s == 0) != proj_ok), 0)
        _check(case, f"{label} positions [mm]", np.max(np.abs(got[0] - ref[0])), TOL_POS)
        _check(case, f"{label} first analogs (relative)", _relative(got[1], ref[1], (1, 3)),
               TOL_ANALOG)
        _check(case, f"{label} second analogs (relative)", _relative(got[2], ref[2], (1, 3)),
               TOL_ANALOG)

    # then timed
    secs, one = _project_timings(lambda: run(pars), repeat)
    status, peak_acc, _ = run(pars)
    r_np = bl.class3_rows(plan, pars[:n_np])
    r_py = bl.class3_rows(plan, pars[:n_py])
    t_np = best_of(lambda: bl.class3_kinematics_numpy(r_np, phis), repeat)
    t_py = best_of(lambda: bl.class3_kinematics_python(r_py, phis), 1)
    s_np, _, _, d2 = bl.class3_kinematics_numpy(r_np, phis)
    _check(case, "assembled candidates (timed set)", np.sum((s_np == 0) != (status[:n_np] == 0)), 0)
    p8 = names.index("P8")
    acc = np.hypot(d2[:, :, p8, 0], d2[:, :, p8, 1]).max(axis=1)
    _check(case, "peak |P8''| (timed set, relative)",
           float(np.max(np.abs(acc / peak_acc[:n_np] - 1.0))), TOL_ANALOG)
    unit = "candidate-positions/s"
    rows += [(case, f"project (numba, {_threads()} threads)", n_proj, secs, unit, first, how,
              "sampler candidates that assemble; P2..P5, P8 with both analogs"),
             (case, "project (numba, 1 thread)", n_proj, one, unit, math.nan, "", ""),
             (case, "NumPy, vectorized", n_np, t_np, unit, math.nan, "",
              "Newton on all candidates at once per position; analogs in one pass"),
             (case, "pure Python", n_py, t_py, unit, math.nan, "", "loops + math")]


# ----------------------------------------------------------------- case 3: the sweep
def sweep_case(sizes, repeat, rows):
    from pipeline.kernels import sweep as ks
    from pipeline.study.reader import load_study
    n_proj, n_np, n_py = sizes
    study = load_study(STUDIES / "ov7_synthesis.toml")
    if study.mechanism.loads:
        raise BaselineMismatch("the sweep baselines model no external loads")
    pb, pars = _draw(study, n_proj)
    spec = pb.spec
    setup = bl.SweepSetup(dwell_w=pb.dwell_w, stroke_radius=spec.stroke_radius,
                          stroke_bounds=tuple(spec.stroke_bounds), margin_min=spec.margin_min,
                          omega1=pb.omega1, eps1=pb.eps1, gravity=pb.plan.gravity,
                          forces=spec.wants_forces)
    run = lambda p: pb.evaluate_rows(p, True)
    first, how = _first_call(pb.kernels.evaluate_lanes, lambda: run(pars[:2]))

    # correct first: candidates of every kind (forces run, constraints missed, failed)
    case = "sweep (synthesis study)"
    st, met = run(pars[:400])
    forced = met[:, ks.M_FORCES_DONE] == 1.0
    pick = np.concatenate([np.flatnonzero(forced)[:5], np.flatnonzero((st == 0) & ~forced)[:4],
                           np.flatnonzero(st != 0)[:4]])
    if not forced.any():
        raise BaselineMismatch(f"{case}: no candidate for the force check among the first 400")
    check = pars[pick]
    crow = bl.class3_rows(pb.plan, check)
    for label, fn in (("NumPy", bl.sweep_numpy), ("pure-Python", bl.sweep_python)):
        _compare_sweep(case, label, fn(crow, pb.phis, setup), st[pick], met[pick], ks)

    # then timed
    secs, one = _project_timings(lambda: run(pars), repeat)
    status, metrics = run(pars)
    r_np = bl.class3_rows(pb.plan, pars[:n_np])
    r_py = bl.class3_rows(pb.plan, pars[:n_py])
    t_np = best_of(lambda: bl.sweep_numpy(r_np, pb.phis, setup), repeat)
    t_py = best_of(lambda: bl.sweep_python(r_py, pb.phis, setup), 1)
    _compare_sweep(case, "NumPy (timed set)", bl.sweep_numpy(r_np, pb.phis, setup),
                   status[:n_np], metrics[:n_np], ks)
    _compare_sweep(case, "pure-Python (timed set)", bl.sweep_python(r_py, pb.phis, setup),
                   status[:n_py], metrics[:n_py], ks)
    share = lambda n: f"{np.mean(status[:n] == 0):.0%} assemble, forces for " \
                      f"{np.mean(metrics[:n, ks.M_FORCES_DONE] == 1.0):.0%}"
    unit = "candidates/s"
    rows += [(case, f"project (numba, {_threads()} threads)", n_proj, secs, unit, first, how,
              f"{share(n_proj)}; staged: forces only where stroke and margin are met"),
             (case, "project (numba, 1 thread)", n_proj, one, unit, math.nan, "", ""),
             (case, "NumPy, vectorized", n_np, t_np, unit, math.nan, "",
              f"{share(n_np)}; same staging; forces by numpy.linalg.solve, batched"),
             (case, "pure Python", n_py, t_py, unit, math.nan, "",
              f"{share(n_py)}; same staging; 15x15 elimination in lists")]


def _compare_sweep(case, label, got, status, metrics, ks):
    ok = status == 0
    _check(case, f"{label} assembled candidates", np.sum((got["status"] == 0) != ok), 0)
    done = metrics[:, ks.M_FORCES_DONE] == 1.0
    _check(case, f"{label} force stage run", np.sum(got["forces_done"] != done), 0)
    if ok.any():
        for what, key, col in (("dwell error", "dwell_error", ks.M_DWELL),
                               ("stroke [mm]", "stroke", ks.M_STROKE),
                               ("singularity margin", "margin", ks.M_MARGIN)):
            _check(case, f"{label} {what}", np.max(np.abs(got[key][ok] - metrics[ok, col])),
                   TOL_METRIC)
    if done.any():
        _check(case, f"{label} peak reaction (relative)",
               np.max(np.abs(got["peak_reaction"][done] / metrics[done, ks.M_PEAK_R] - 1.0)),
               TOL_PEAK)


# ----------------------------------------------------------------- cold compile
def _cold_probe():
    """(Run in a fresh process with empty caches.)  First calls of the
    project's two kernels (the four-bar's generated ``batch`` and the synthesis
    study's generated ``evaluate``) on tiny inputs, each with the generation
    of its module; prints them as JSON."""
    from pipeline.compiler import kernels_for
    from pipeline.solve.scene import batch_revolutions
    from pipeline.study.reader import load_study
    study = _kinematic_study(load_study(STUDIES / "warp_feed_fourbar.toml"))
    plan = study.mechanism.compile()
    pars = perturbed_rows(plan, (), 2)
    t = time.perf_counter()
    batch = kernels_for(plan).batch          # generate and import the module
    gen_batch = time.perf_counter() - t
    t_batch, how_batch = _first_call(batch, lambda: batch_revolutions(study, pars, 12, 0, False))
    pb, rows = _draw(load_study(STUDIES / "ov7_synthesis.toml"), 2)
    t = time.perf_counter()
    evaluate = pb.kernels.evaluate_lanes      # (evaluate's jitted body)
    gen_sweep = time.perf_counter() - t
    t_sweep, how_sweep = _first_call(evaluate, lambda: pb.evaluate_rows(rows, True))
    t_batch += gen_batch
    t_sweep += gen_sweep
    print(json.dumps({"batch": [t_batch, how_batch], "sweep": [t_sweep, how_sweep]}))


def cold_compile():
    """Seconds to the first result of each project kernel in a fresh process
    whose caches are empty (no generated module, no numba cache: the
    generation and compile a new install pays once per mechanism)."""
    code = f"import sys; sys.path.insert(0, {str(HERE)!r}); import bench_throughput as b; b._cold_probe()"
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=os.path.join(cache, "numba"),
                   PIPELINE_CACHE_DIR=os.path.join(cache, "pipeline"))
        r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                           check=True)
    out = json.loads(r.stdout.strip().splitlines()[-1])
    for kernel, (secs, how) in out.items():
        if how != "compile":
            raise RuntimeError(f"cold probe: the {kernel} kernel was not compiled ({how})")
    return {k: v[0] for k, v in out.items()}


# ----------------------------------------------------------------- the table
def run(quick: bool = False, csv=CSV, cold: bool = False) -> pd.DataFrame:
    """Check the baselines, time everything, return the throughput table (and
    write it to ``csv`` unless None).  ``cold`` also measures the project's
    compile time with an empty numba cache in a fresh process.  Raises
    BaselineMismatch if a baseline disagrees with the project."""
    sizes = SIZES[bool(quick)]
    rows = []
    CHECKS.clear()
    four_bar_case(sizes["four-bar"], sizes["repeat"], rows, strip=not quick)
    kinematics_case(sizes["kinematics"], sizes["repeat"], rows, strip=not quick)
    sweep_case(sizes["sweep"], sizes["repeat"], rows)
    df = pd.DataFrame(rows, columns=["case", "implementation", "candidates", "seconds", "unit",
                                     "first_call_s", "first_call", "notes"])
    df["cold_compile_s"] = math.nan
    if cold:
        c = cold_compile()
        first = df["first_call_s"].notna()
        df.loc[first, "cold_compile_s"] = np.where(df.loc[first, "case"].str.startswith("sweep"),
                                                   c["sweep"], c["batch"])
    per = np.where(df["unit"] == "candidates/s", 1, POSITIONS)
    df.insert(3, "positions", POSITIONS)
    df.insert(5, "rate", df["candidates"] * per / df["seconds"])
    project = df.groupby("case")["rate"].transform("first")
    df.insert(6, "x_slower", project / df["rate"])
    df["hardware"] = hardware()
    df.attrs["hardware"] = hardware()
    df.attrs["checks"] = pd.DataFrame(CHECKS, columns=["case", "check", "worst", "allowed"])
    if csv is not None:
        Path(csv).parent.mkdir(parents=True, exist_ok=True)
        df.to_csv(csv, index=False)
    return df


def format_table(df) -> str:
    out = []
    for case, g in df.groupby("case", sort=False):
        out.append(f"{case}: {g['unit'].iloc[0]}, {g['positions'].iloc[0]} positions per "
                   "revolution")
        out.append(f"  {'implementation':<26}{'cand.':>8} {'steady':>10}{'rate':>14}  "
                   f"{'vs project':>14}")
        for _, r in g.iterrows():
            rate = f"{r['rate']:>14,.0f}" if math.isfinite(r["rate"]) else f"{'-':>14}"
            x = r["x_slower"]
            slower = ("-" if not math.isfinite(x) else "(project)" if r.name == g.index[0]
                      else "about the same" if 0.95 <= x <= 1.05
                      else f"{x:,.1f}x slower" if x > 1 else f"{1 / x:,.1f}x faster")
            first = (f"first call {r['first_call_s']:.2f} s ({r['first_call']})"
                     if math.isfinite(r["first_call_s"]) else "")
            if math.isfinite(r["cold_compile_s"]):
                first += f"; empty cache {r['cold_compile_s']:.1f} s"
            out.append(f"  {r['implementation']:<26}{r['candidates']:>8,} {r['seconds']:>8.3f} s"
                       f"{rate}  {slower:>14}  {first}")
            if r["notes"]:
                out.append(f"  {'':<26}{r['notes']}")
        out.append("")
    return "\n".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small sizes (about half a minute)")
    ap.add_argument("--cold", action="store_true",
                    help="also time the project's compile with an empty numba cache (fresh "
                         "process; a minute or more)")
    ap.add_argument("--csv", default=str(CSV), help="where to write the table (default: %(default)s)")
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    print(f"hardware: {hardware()}")
    try:
        df = run(a.quick, a.csv, a.cold)
    except BaselineMismatch as e:
        print(f"ABORTED: {e}", file=sys.stderr)
        return 1
    print("vs project: the project's rate on all threads / this rate; the baselines run on "
          "one core\n")
    print(format_table(df))
    print("baselines against the project (worst deviation / allowed), before timing and on "
          "the timed outputs:")
    for _, c in df.attrs["checks"].iterrows():
        print(f"  {c['case']:<24} {c['check']:<46} {c['worst']:>9.2g} / {c['allowed']:g}")
    print(f"written {a.csv}; {time.perf_counter() - t0:.0f} s in all")
    return 0


if __name__ == "__main__":
    sys.exit(main())
