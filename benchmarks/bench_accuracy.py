"""Run time against error: how much accuracy each setting buys, and at what cost.

(a) positions per revolution (12 .. 3600) for the dwell error and the peak
    reaction of mechanism B, against a converged value;
(b) the Newton tolerance and iteration cap;
(c) exact analogs against finite-difference analogs (the Mathcad way);
(d) the RK4 step for mechanism C;
(e) strict IEEE against numba's floating-point flags: the default (FMA
    contraction in the sweep's lane walk) and fastmath (fresh processes, their
    own caches).

Each study is a table (CSV) and a log-log plot of error against time in the
output folder (``out``; default results/bench/ of the checkout).  Times are
steady state (after a warm-up), per candidate.

    python benchmarks/bench_accuracy.py [--quick] [-o DIR]
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

from pipeline.base.files import save_figure
from pipeline.base.progress import ticking

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import ROOT, STUDIES, best_of, hardware  # noqa: E402

DEFAULT_OUT = ROOT / "results" / "bench"   # where run() writes unless told otherwise
REPEAT_ROWS = 64          # identical candidates per timing call (amortises call overhead)


def _synthesis():
    from pipeline.study.reader import load_study
    return load_study(STUDIES / "ov7_synthesis.toml")


def _class3_scene(positions):
    """Mechanism B's scene study, its compiled plan and one revolution's crank angles."""
    from pipeline.solve.scene import revolution_angles
    from pipeline.study.reader import load_study
    study = load_study(STUDIES / "ov7_class3.toml")
    return study, study.mechanism.compile(), revolution_angles(study.mechanism.crank, positions)


def _rows(plan, n=REPEAT_ROWS):
    return np.ascontiguousarray(np.repeat(plan.par[None, :], n, axis=0))


def _plot(df, x, ys, title, path, xlabel="time per candidate [s]"):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 4.5), layout="constrained")
    for y, label in ys:
        d = df[(df[y] > 0) & np.isfinite(df[y])]
        ax.loglog(d[x], d[y], "o-", label=label)
        for _, r in d.iterrows():
            ax.annotate(str(r["setting"]), (r[x], r[y]), fontsize=7, xytext=(3, 3),
                        textcoords="offset points")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("error")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    save_figure(fig, path, dpi=110)
    plt.close(fig)


# ----------------------------------------------------------------- (a) positions
def positions_study(quick, out=DEFAULT_OUT):
    from pipeline.kernels.sweep import M_DWELL, M_PEAK_R
    from pipeline.runs.sweep import build_problem
    study = _synthesis()
    ns = [12, 24, 36, 72, 120, 180, 360, 720] + ([] if quick else [1440, 3600])
    n_ref = 7200 if quick else 36000
    rows = []
    ref_pb = build_problem(study, dataclasses.replace(study.sweep, positions=n_ref))
    _, mref = ref_pb.evaluate_rows(_rows(ref_pb.plan, 1), parallel=False)
    for n in ns:
        pb = build_problem(study, dataclasses.replace(study.sweep, positions=n))
        r = _rows(pb.plan)
        pb.evaluate_rows(r[:1], parallel=False)
        secs = best_of(lambda: pb.evaluate_rows(r, parallel=False), 3) / len(r)
        _, m = pb.evaluate_rows(r[:1], parallel=False)
        rows.append({"setting": n, "positions": n, "time_s": secs,
                     "dwell_error": m[0, M_DWELL], "peak_reaction_N": m[0, M_PEAK_R],
                     "dwell_abs_error": abs(m[0, M_DWELL] - mref[0, M_DWELL]),
                     "peak_rel_error": abs(m[0, M_PEAK_R] / mref[0, M_PEAK_R] - 1)})
    df = pd.DataFrame(rows)
    df.attrs["note"] = (f"mechanism B at omega1 = -97.2 rad/s, dwell 150 deg; converged "
                        f"values at {n_ref} positions: dwell error {mref[0, M_DWELL]:.6f}, "
                        f"peak reaction {mref[0, M_PEAK_R]:.3f} N")
    _plot(df, "time_s", [("dwell_abs_error", "dwell error (absolute)"),
                         ("peak_rel_error", "peak reaction (relative)")],
          "(a) positions per revolution", Path(out) / "a_positions.png")
    return df


# ----------------------------------------------------------------- (b) Newton
def newton_study(quick, out=DEFAULT_OUT):
    from pipeline.kernels import config as kc
    from pipeline.solve.scene import batch_revolutions, solve_curves
    study, plan, phis = _class3_scene(360)
    tight = kc.default_tolerances(newton_tol=1e-15, newton_maxiter=100)
    ref = solve_curves(plan, phis, kc.POSITIONS, tight).pos[:, :plan.n_visible]
    r = _rows(plan)
    settings = [(f"tol {t:g}", dict(newton_tol=t)) for t in (1e-2, 1e-4, 1e-6, 1e-8, 1e-10,
                                                               1e-12, 1e-14)]
    settings += [(f"cap {c}", dict(newton_tol=1e-14, newton_maxiter=c)) for c in (1, 2, 3, 5)]
    rows = []
    for label, kw in settings:
        tols = kc.default_tolerances(**kw)
        c = solve_curves(plan, phis, kc.POSITIONS, tols)
        err = np.nanmax(np.abs(c.pos[:, :plan.n_visible] - ref)) if c.overall == kc.OK else math.nan
        batch_revolutions(study, r[:1], 360, kc.POSITIONS, False, tols)
        secs = best_of(lambda: batch_revolutions(study, r, 360, kc.POSITIONS, False, tols),
                       3) / len(r)
        rows.append({"setting": label, "time_s": secs, "status": kc.STATUS_NAMES[c.overall],
                     "position_error_mm": err, "mean_iterations": float(np.mean(c.iterations))})
    df = pd.DataFrame(rows)
    df.attrs["note"] = "mechanism B, 360 positions, positions only; error = max over points"
    _plot(df, "time_s", [("position_error_mm", "position error [mm]")],
          "(b) Newton tolerance and iteration cap", Path(out) / "b_newton.png")
    return df


# ----------------------------------------------------------------- (c) analogs
def analogs_study(quick, out=DEFAULT_OUT):
    from pipeline.kernels import config as kc
    from pipeline.solve.scene import batch_revolutions, solve_curves
    study, plan, phis = _class3_scene(360)
    exact = solve_curves(plan, phis, kc.ACCELERATIONS)
    i8 = plan.point("P8")
    s1 = np.abs(exact.d1[:, i8]).max()
    s2 = np.abs(exact.d2[:, i8]).max()
    r = _rows(plan)
    batch_revolutions(study, r[:1], 360, kc.ACCELERATIONS, False)
    t_exact = best_of(lambda: batch_revolutions(study, r, 360, kc.ACCELERATIONS, False), 3)
    t_pos = best_of(lambda: batch_revolutions(study, r, 360, kc.POSITIONS, False), 3)
    rows = [{"setting": "exact", "time_s": t_exact / len(r), "velocity_rel_error": 0.0,
             "acceleration_rel_error": 0.0}]
    for h in (1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7):
        c = [solve_curves(plan, phis + k * h, kc.POSITIONS) for k in (-1, 0, 1)]
        p = [x.pos[:, i8] for x in c]
        fd1 = (p[2] - p[0]) / (2 * h)
        fd2 = (p[2] - 2 * p[1] + p[0]) / h ** 2
        rows.append({"setting": f"FD h={h:g}",
                     # central differences need three position solves per position
                     "time_s": 3 * t_pos / len(r),
                     "velocity_rel_error": np.abs(fd1 - exact.d1[:, i8]).max() / s1,
                     "acceleration_rel_error": np.abs(fd2 - exact.d2[:, i8]).max() / s2})
    df = pd.DataFrame(rows)
    df.attrs["note"] = ("mechanism B, eyelet P8, 360 positions; exact = analogs from the "
                        "differentiated closure equations; FD = central differences of positions")
    _plot(df[df.setting != "exact"], "time_s",
          [("velocity_rel_error", "velocity analog"),
           ("acceleration_rel_error", "acceleration analog")],
          f"(c) finite-difference analogs (exact: 0 error at {t_exact / len(r):.1e} s)",
          Path(out) / "c_analogs.png")
    return df


# ----------------------------------------------------------------- (d) RK4
def rk4_study(quick, out=DEFAULT_OUT):
    from pipeline.solve import crank_motion as dy
    from pipeline.study.reader import load_study
    study = load_study(STUDIES / "takeup_dynamics.toml")
    plan = study.mechanism.compile()
    mech = study.mechanism
    case = next(c for c in study.dynamics.cases if c.name == "runup")
    if quick:
        case = dy.with_changes(case, t_end=2.0)
    ref = dy.integrate(plan, mech, dy.with_changes(case, dt=1e-3), "dop853")
    rows = []
    for dt in (2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4) if not quick else (2e-3, 1e-3, 5e-4, 2.5e-4):
        c = dy.with_changes(case, dt=dt)
        dy.integrate(plan, mech, dy.with_changes(c, t_end=c.sample_dt), checked=False)
        best = math.inf
        for _ in range(2):      # the integrator alone at this step: no estimate, no refinement
            res = dy.integrate(plan, mech, c, checked=False)
            best = min(best, res.seconds)
        rows.append({"setting": f"dt={dt:g}", "dt_s": dt, "time_s": best,
                     "phi_error_rad": abs(res.phi1[-1] - ref.phi1[-1])})
    df = pd.DataFrame(rows)
    e = df.phi_error_rad.values
    df["order"] = np.r_[np.nan, np.log(e[:-1] / e[1:]) / np.log(df.dt_s.values[:-1] / df.dt_s.values[1:])]
    df.attrs["note"] = (f"mechanism C run-up, error of phi1 at {case.t_end:g} s against DOP853 "
                        f"(rtol = atol = {dy.DOP853_TOL:g}); time per simulation")
    _plot(df, "time_s", [("phi_error_rad", "phi1 error [rad]")], "(d) RK4 step",
          Path(out) / "d_rk4.png", xlabel="time per simulation [s]")
    return df


# ----------------------------------------------------------------- (e) fastmath
_PROBE = r"""
import json, sys, time, dataclasses
import numpy as np
sys.path.insert(0, {bench!r})
from common import best_of
from pipeline.study.reader import load_study
from pipeline.runs.sweep import build_problem
from pipeline.study.sweep_spec import parameter_rows
from pipeline.study.sampling import draw_candidates
s = load_study({study!r})
spec = dataclasses.replace(s.sweep, candidates={n}, chunk_size={n})
pb = build_problem(s, spec)
rows = parameter_rows(pb.plan, spec, draw_candidates(spec, 0))
t = time.perf_counter(); pb.evaluate_rows(rows[:2], parallel=False); compile_s = time.perf_counter() - t
secs = best_of(lambda: pb.evaluate_rows(rows, parallel=False), 2)
st, m = pb.evaluate_rows(rows, parallel=False)
np.savez({npz!r}, status=st, metrics=m)
print(json.dumps(dict(compile_s=compile_s, secs=secs)))
"""


# floating-point modes of the kernels (PIPELINE_FASTMATH, pipeline.kernels.config)
FP_MODES = {"strict": "strict IEEE everywhere",
            "default": "strict IEEE, FMA contraction in the sweep's lane walk (the default)",
            "fast": "{nsz, arcp, contract, afn, reassoc} everywhere"}


def _fp_mode():
    """The PIPELINE_FASTMATH mode the kernels of this process are compiled with."""
    from pipeline.kernels import config
    if config.FASTMATH:
        return "fast"
    return "default" if getattr(config, "LANE_FASTMATH", False) else "strict"


def fastmath_study(quick, out=DEFAULT_OUT):
    """The sweep's metrics under each floating-point mode (FP_MODES) against
    strict IEEE.  The mode of this process runs here (its kernels are compiled
    already); every other mode runs in a fresh process with its own caches
    (numba's and the generated modules'), because neither cache key includes
    the floating-point flags."""
    here = _fp_mode()
    n = 500 if quick else 10000
    # quick (the suite's smoke run): this process's mode and strict IEEE, the
    # reference, so one fresh process with cold caches runs, not two
    modes = [m for m in FP_MODES if not quick or m in (here, "strict")]
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for mode in modes:
            npz = os.path.join(tmp, f"{mode}.npz")
            code = _PROBE.format(bench=str(Path(__file__).resolve().parent),
                                 study=str(STUDIES / "ov7_synthesis.toml"), n=n, npz=npz)
            if mode == here:
                ns = {}
                import contextlib
                import io
                buf = io.StringIO()
                with contextlib.redirect_stdout(buf):
                    exec(compile(code, f"<{mode} probe>", "exec"), ns)  # noqa: S102 - our own code
                info = json.loads(buf.getvalue().strip().splitlines()[-1])
            else:
                env = dict(os.environ, PIPELINE_FASTMATH=mode)
                if "fast" in (mode, here) or not quick:
                    # numba's cache key has no floating-point flags: the library kernels
                    # of "fast" differ, so a cold cache of its own (and always in a full
                    # run, whose compile time includes it); "default" and "strict" differ
                    # in the lane walk only, which is in the generated module, whose name
                    # carries the flags: the smoke run shares this process's caches
                    env.update(NUMBA_CACHE_DIR=os.path.join(tmp, f"cache_{mode}"),
                               PIPELINE_CACHE_DIR=os.path.join(tmp, f"modules_{mode}"))
                r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                                   text=True)
                if r.returncode:
                    raise RuntimeError(f"{mode} floating-point probe failed:\n{r.stderr[-2000:]}")
                info = json.loads(r.stdout.strip().splitlines()[-1])
            with np.load(npz) as z:
                info["status"], info["metrics"] = z["status"], z["metrics"]
            info["fresh_process"] = mode != here
            results[mode] = info
    s = results["strict"]
    rows = []
    from pipeline.kernels.sweep import M_DWELL, M_PEAK_R, M_STROKE
    for mode, flags in FP_MODES.items():
        if mode not in results:
            continue
        r = results[mode]
        both = (s["status"] == 0) & (r["status"] == 0)
        row = {"setting": mode, "flags": flags, "time_s": r["secs"] / n,
               "compile_s": r["compile_s"], "fresh_process": r["fresh_process"],
               "status_agreement": float(np.mean(s["status"] == r["status"]))}
        for name, col in (("dwell_error", M_DWELL), ("stroke", M_STROKE),
                          ("peak_reaction", M_PEAK_R)):
            a, b = s["metrics"][both, col], r["metrics"][both, col]
            ok = np.isfinite(a) & np.isfinite(b)
            row[f"{name}_rel_error"] = float(np.max(np.abs(b[ok] / a[ok] - 1))) if ok.any() else 0.0
        rows.append(row)
    df = pd.DataFrame(rows)
    df.attrs["note"] = (f"{n} synthesis candidates on one thread; modes of PIPELINE_FASTMATH "
                        f"(this process: {here}; the others in a fresh process"
                        + (" sharing this one's caches (smoke run)" if quick else
                           " and caches, their compile time includes the cold caches")
                        + "); errors against strict IEEE")
    _plot(df[df.setting != "strict"], "time_s", [("dwell_error_rel_error", "dwell error"),
                                                 ("peak_reaction_rel_error", "peak reaction")],
          "(e) floating-point flags against strict IEEE", Path(out) / "e_fastmath.png")
    return df


STUDIES_ALL = {"a_positions": positions_study, "b_newton": newton_study,
               "c_analogs": analogs_study, "d_rk4": rk4_study, "e_fastmath": fastmath_study}


def run(quick=False, only=None, echo=print, out=None):
    """Run the studies (all, or those named in ``only``), writing each table and
    plot into the folder ``out`` (default DEFAULT_OUT); return the tables."""
    out = Path(out) if out is not None else DEFAULT_OUT
    out.mkdir(parents=True, exist_ok=True)
    echo(f"hardware: {hardware()}")
    tables = {}
    for name, fn in STUDIES_ALL.items():
        if only and name not in only:
            continue
        t = time.perf_counter()
        with ticking(f"bench {name}", say_done=False):     # a live line; its time follows
            df = fn(quick, out)
        df.to_csv(out / f"{name}.csv", index=False)
        tables[name] = df
        echo(f"\n{name} ({time.perf_counter() - t:.1f} s): {df.attrs.get('note', '')}")
        echo(df.to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    return tables


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--only", nargs="*", choices=list(STUDIES_ALL))
    ap.add_argument("-o", "--output", metavar="DIR", default=str(DEFAULT_OUT),
                    help="folder for the tables and plots (default: %(default)s)")
    a = ap.parse_args(argv)
    run(a.quick, a.only, out=a.output)


if __name__ == "__main__":
    main()
