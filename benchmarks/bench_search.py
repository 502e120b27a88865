"""Adaptive search against the Monte-Carlo sweep on the default study (issue 17).

Hypervolume of the feasible front against evaluations and against wall time:
the Monte-Carlo sweep (the project's Sobol draws, studies/ov7_synthesis.toml)
to 200,000 candidates, and the adaptive search (studies/ov7_search.toml:
NSGA-II, SMS-EMOA, AGE-MOEA from pymoo, population 100) to 20,000 evaluations,
3 seeds each, every run through the real runner (`run_sweep`, `run_search`:
kernels on all cores, HDF5 file and journal written as usual).

One normalisation for all (the search's own, stored in its file): each
objective (dwell error, peak reaction) divided by the study's reference
design's (mechanism B: 0.07209, 1073.8 N); reference point (1.1, 1.1).

    python benchmarks/bench_search.py [--quick | --smoke] [-o DIR]

The table gives each method's rate (evaluated designs per second of wall time,
HDF5 and journal included) beside the sweep's.  NSGA-II runs on arrays
(pipeline/runs/nsga2.py); each of its seeds runs again in pymoo's own NSGA2
loop, the baseline, which must give the same results file bit for bit (the
script exits 1 where it does not).

Writes search.md (the table), search.csv (every curve) and search.png (the
plot) into DIR (default results/bench/); the runs' own files go to a temporary
folder inside DIR, removed at the end.  Wall time counts from the call of the
runner (kernels already compiled: a warm-up run comes first) to the chunk or
generation written.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import io
import re
import statistics
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np

from common import ROOT, STUDIES, hardware

SEEDS = (1, 2, 3)
METHODS = (("nsga2", "NSGA-II"), ("smsemoa", "SMS-EMOA"), ("agemoea", "AGE-MOEA"))
SWEEP_GRID = (1000, 2000, 5000, 10_000, 20_000, 50_000, 100_000, 200_000)


def study_with(path: Path, folder: Path, name: str, **changes):
    """A copy of the study at ``path`` with top-level keys of its sections
    changed (``"sweep.seed": 1``), written into ``folder`` and loaded."""
    from pipeline.study.reader import load_study
    text = path.read_text()
    for key, value in changes.items():
        section, field = key.split(".")
        start = re.search(rf"^\[{re.escape(section)}\].*$", text, re.M).end()
        end = re.search(r"^\[", text[start:], re.M)
        end = start + end.start() if end else len(text)
        line = f"{field} = {value!r}".replace("'", '"')
        body, n = re.subn(rf"^{field} = .*$", line, text[start:end], count=1, flags=re.M)
        if not n:
            body = "\n" + line + body
        text = text[:start] + body + text[end:]
    p = folder / f"{name}.toml"
    p.write_text(text)
    return load_study(p)


def front_numbers(path, n, scale):
    """(hypervolume, least feasible peak reaction) of the first n candidates."""
    from pipeline.runs.search_problem import hypervolume
    with h5py.File(path, "r") as f:
        F = np.stack([f[f"metrics/{o}"][:n] for o in f.attrs["objectives"]], axis=1)
        feas = f["candidates/feasible"][:n]
        peak = f["metrics/peak_reaction"][:n][feas]
    return hypervolume(F, feas, scale), float(peak.min()) if peak.size else float("nan")


def run_sweep_timed(study, out, n):
    """The sweep through `run_sweep`, with the time each chunk was written."""
    import pipeline.runs.sweep as sw
    real = sw.SweepFile.write_chunk
    stamps = []

    def stamped(self, d, chunk, *a, **k):
        real(self, d, chunk, *a, **k)
        stamps.append((self.spec.chunk_bounds(chunk)[1], time.perf_counter()))
    sw.SweepFile.write_chunk = stamped
    try:
        t0 = time.perf_counter()
        sw.run_sweep(study, out, candidates=n, progress=False)
    finally:
        sw.SweepFile.write_chunk = real
    done = np.array([s[0] for s in stamps])
    secs = np.array([s[1] - t0 for s in stamps])
    return done, secs


def run_search_timed(study, out):
    from pipeline.runs.search import run_search
    rows = []
    t0 = time.perf_counter()
    run_search(study, out, progress=False,
               on_generation=lambda r: rows.append((r["evaluations"], r["hypervolume"],
                                                    time.perf_counter() - t0)))
    return np.array(rows)


@contextlib.contextmanager
def pymoo_loop():
    """run_search's NSGA-II driven in pymoo's own loop (``search._InPymoo``)
    instead of on arrays: the baseline of the array version."""
    import pipeline.runs.search as se
    real = se.make_algorithm
    se.make_algorithm = lambda search, x0, repair, box: se._InPymoo(search, x0, repair, box)
    try:
        yield
    finally:
        se.make_algorithm = real


def same_candidates(a, b):
    """Whether two search files hold the same designs, statuses, metrics and
    history, bit for bit (every dataset of those groups; the attributes hold
    wall times)."""
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        for group in ("candidates", "metrics", "search"):
            if set(fa[group]) != set(fb[group]):
                return False
            for k in fa[group]:
                x, y = fa[group][k][()], fb[group][k][()]
                if x.dtype != y.dtype or x.shape != y.shape or (
                        x.tobytes() != y.tobytes() if x.dtype.kind != "O" else
                        not (x == y).all()):
                    return False
    return True


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="a short run: sweep 20,000, search 4,000 evaluations")
    ap.add_argument("--smoke", action="store_true",
                    help="that it runs (the test suite): sweep 2,000, search 400 "
                         "evaluations, 2 seeds, no warm-up")
    ap.add_argument("-o", "--out", default=str(ROOT / "results" / "bench"))
    a = ap.parse_args(argv)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from pipeline.base.files import save_figure, write_text
    from pipeline.study.search_spec import NORMALISATION
    from pipeline.runs.search_problem import hv_scale
    from pipeline.runs.sweep import build_problem

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    n_sweep, n_search = ((2_000, 400) if a.smoke else (20_000, 4_000) if a.quick
                         else (200_000, 20_000))
    seeds = SEEDS[:2] if a.smoke else SEEDS
    grid = sorted({g for g in SWEEP_GRID if g <= n_sweep} | {n_search, n_sweep})
    print(f"hardware: {hardware()}")
    identical = []  # NSGA-II on arrays against pymoo's own loop: the same file?
    curves = []     # (method, seed, evaluations, wall_s, hypervolume)
    table = {}      # (method, evaluations) -> [(hv, least peak, wall)]
    with tempfile.TemporaryDirectory(dir=out, prefix=".bench_search.") as tmp:
        tmp = Path(tmp)
        base = study_with(STUDIES / "ov7_synthesis.toml", tmp, "sweep_warm")
        scale = hv_scale(build_problem(base, base.sweep))
        print(f"normalisation: {NORMALISATION}: scale {scale[0]:.6g}, {scale[1]:.6g} N")
        # warm-up (kernels, pymoo's numba code): not timed
        run_sweep_timed(base, tmp / "warm.h5", 500 if a.smoke else 2000)
        for method, _ in () if a.smoke else METHODS:
            s = study_with(STUDIES / "ov7_search.toml", tmp, f"warm_{method}",
                           **{"search.method": method, "search.evaluations": 400})
            run_search_timed(s, tmp / f"warm_{method}.h5")

        for seed in seeds:
            s = study_with(STUDIES / "ov7_synthesis.toml", tmp, f"sweep_{seed}",
                           **{"sweep.seed": seed})
            path = tmp / f"sweep_{seed}.h5"
            done, secs = run_sweep_timed(s, path, n_sweep)
            for n in grid:
                hv, peak = front_numbers(path, n, scale)
                wall = float(np.interp(n, np.concatenate([[0], done]),
                                       np.concatenate([[0.0], secs])))
                curves.append(("sweep", seed, n, wall, hv))
                if n in (n_search, n_sweep):
                    table.setdefault(("sweep", n), []).append((hv, peak, wall))
            print(f"sweep seed {seed}: {n_sweep:,} in {secs[-1]:.1f} s, hypervolume "
                  f"{curves[-1][4]:.4f}", flush=True)
        for method, label in METHODS:
            for seed in seeds:
                s = study_with(STUDIES / "ov7_search.toml", tmp, f"{method}_{seed}",
                               **{"search.method": method, "search.seed": seed,
                                  "search.evaluations": n_search})
                path = tmp / f"{method}_{seed}.h5"
                rows = run_search_timed(s, path)
                for ev, hv, wall in rows:
                    curves.append((method, seed, int(ev), wall, hv))
                n = int(rows[-1, 0])
                hv, peak = front_numbers(path, n, scale)
                assert abs(hv - rows[-1, 1]) <= 1e-12 * hv   # the history is the file's front
                table.setdefault((method, n_search), []).append((hv, peak, rows[-1, 2]))
                print(f"{label} seed {seed}: {n:,} in {rows[-1, 2]:.1f} s, hypervolume "
                      f"{hv:.4f}, least peak reaction {peak:.1f} N", flush=True)
                if method == "nsga2":
                    # the baseline: the same search in pymoo's own NSGA2 loop (its
                    # population objects), which must give the same file, bit for bit
                    base = tmp / f"{method}_{seed}_pymoo.h5"
                    with pymoo_loop():
                        rows = run_search_timed(s, base)
                    same = same_candidates(path, base)
                    identical.append(same)
                    table.setdefault(("nsga2-pymoo", n_search), []).append(
                        (*front_numbers(base, n, scale), rows[-1, 2]))
                    print(f"{label} in pymoo's own loop, seed {seed}: {rows[-1, 2]:.1f} s, "
                          f"{'the same designs and results' if same else 'DIFFERENT designs'}",
                          flush=True)

    # ---- the table
    def row(label, key):
        v = table[key]
        hv = [x[0] for x in v]
        peaks = [x[1] for x in v]
        walls = [x[2] for x in v]
        wall = statistics.mean(walls)
        return (f"| {label} | {key[1]:,} | {statistics.mean(hv):.4f} +- "
                f"{statistics.stdev(hv):.4f} | {', '.join(f'{h:.4f}' for h in hv)} | "
                f"{min(peaks):.1f} - {max(peaks):.1f} | {wall:.1f} | {key[1] / wall:,.0f} |")
    lines = ["# Adaptive search against the Monte-Carlo sweep (default study)", "",
             f"Hardware: {hardware()}.", "",
             f"Hypervolume of the feasible front: {NORMALISATION} (scale "
             f"{scale[0]:.6g}, {scale[1]:.6g} N: mechanism B's dwell error and peak "
             f"reaction). Seeds {', '.join(map(str, seeds))} for every method; "
             "wall time of the real runner (HDF5 and journal written), kernels compiled "
             "beforehand.", "",
             "| method | evaluations | hypervolume (mean +- sd) | per seed | least feasible "
             "peak reaction [N] (range over seeds) | wall time [s] (mean) | designs/s |",
             "|---|---|---|---|---|---|---|"]
    lines.append(row("Monte-Carlo sweep (Sobol)", ("sweep", n_search)))
    lines.append(row("Monte-Carlo sweep (Sobol)", ("sweep", n_sweep)))
    for method, label in METHODS:
        lines.append(row(f"{label} (pymoo's{' on arrays' if method == 'nsga2' else ''}), "
                         "population 100", (method, n_search)))
        if method == "nsga2":
            lines.append(row("NSGA-II in pymoo's own loop (the baseline), population 100",
                             ("nsga2-pymoo", n_search)))
    sweep = table[("sweep", n_sweep)]
    sweep_hv = statistics.mean(x[0] for x in sweep)
    sweep_peak = statistics.mean(x[1] for x in sweep)
    lines.append("")
    arrays = statistics.mean(x[2] for x in table[("nsga2", n_search)])
    loop = statistics.mean(x[2] for x in table[("nsga2-pymoo", n_search)])
    lines.append(f"* NSGA-II on arrays (`pipeline/runs/nsga2.py`) against pymoo's own NSGA2 loop, "
                 f"the same seeds in this process: {loop / arrays:.1f}x the designs per second; "
                 f"the results files {'identical' if all(identical) else 'NOT identical'} "
                 f"(every dataset of the candidates, metrics and history) for "
                 f"{sum(identical)} of {len(identical)} seeds.")
    for method, label in METHODS:
        runs = table[(method, n_search)]
        hv = statistics.mean(x[0] for x in runs)
        peak = statistics.mean(x[1] for x in runs)
        worst = max(x[1] for x in runs)
        lines.append(f"* {label} after {n_search:,} evaluations against the sweep after "
                     f"{n_sweep:,} (means of the seeds): hypervolume {hv:.4f} vs {sweep_hv:.4f} "
                     f"({'larger' if hv > sweep_hv else 'NOT larger'}); least peak reaction "
                     f"{peak:.1f} N vs {sweep_peak:.1f} N "
                     f"({'lower' if peak < sweep_peak else 'NOT lower'}; its worst seed "
                     f"{worst:.1f} N against the sweep's best {min(x[1] for x in sweep):.1f} N).")
    text = "\n".join(lines) + "\n"
    write_text(out / "search.md", text)
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["method", "seed", "evaluations", "wall_s", "hypervolume"])
    w.writerows(curves)
    write_text(out / "search.csv", buf.getvalue())

    # ---- the plot
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), layout="constrained")
    colours = {"sweep": "0.35", "nsga2": "C0", "smsemoa": "C1", "agemoea": "C2"}
    labels = {"sweep": "Monte-Carlo sweep (Sobol)", **{m: f"{lab} (pymoo)" for m, lab in METHODS}}
    for method in colours:
        for seed in seeds:
            c = np.array([r[2:] for r in curves if r[0] == method and r[1] == seed], float)
            if not len(c):
                continue
            kw = dict(color=colours[method], lw=1.3, alpha=0.85,
                      label=labels[method] if seed == seeds[0] else None)
            axes[0].plot(c[:, 0], c[:, 2], **kw)
            axes[1].plot(c[:, 1], c[:, 2], **kw)
    axes[0].set_xscale("log")
    axes[0].set_xlabel("evaluations")
    axes[1].set_xscale("log")
    axes[1].set_xlabel("wall time [s]")
    for ax in axes:
        ax.set_ylabel("hypervolume of the feasible front")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    fig.suptitle("default study: objectives / mechanism B's, reference point (1.1, 1.1); "
                 f"{len(seeds)} seeds each", fontsize=10)
    save_figure(fig, out / "search.png", dpi=110)
    print()
    print(text)
    print(f"written: {out / 'search.md'}, {out / 'search.csv'}, {out / 'search.png'}")
    if not all(identical):
        raise SystemExit("NSGA-II on arrays and pymoo's own NSGA2 loop gave different files")


if __name__ == "__main__":
    main()
