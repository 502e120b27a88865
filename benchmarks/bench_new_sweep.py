"""A new sweep mechanism's first candidates, end to end: the compile beside the run, or not.

    python benchmarks/bench_new_sweep.py [--rounds 3] [--study NAME] [--candidates 100000]
                                         [--one-process] [--against DIR] [--smoke] [-o DIR]

``pipeline run STUDY --candidates N`` (the main job's study by default, 100,000
candidates) in a fresh process, the wall time of the whole process, as a
mechanism new to the cache: every generated module (``pipeline_mech_*``) and its
compiled code removed first, the library compiled (the state after a first
sweep of another mechanism, or ``pipeline compile --library``).  The ways,
alternated round by round on the same machine:

* beside: the default; the run compiles the careful stages and ``evaluate``
  while a process beside compiles the force lanes, the lane walk and the
  kernels round them (``pipeline.compiler.beside``);
* with ``--one-process``, ``PIPELINE_COMPILE_BESIDE=0``: every kernel in the
  run (what the process beside buys; about 1.6 times as long);
* with ``--against DIR``, another checkout of the package (an earlier commit:
  ``git worktree add DIR REV``) the default way (and in one process, with
  ``--one-process``), so that "sooner than before" is measured in one run,
  alternately.

Issue 53's line: a new mechanism's sweep, its first 100,000 candidates done
sooner than today.  --smoke (the test suite: that it runs): 500 candidates, one
round, the default way only, the generated modules kept (in PIPELINE_CACHE_DIR
where it is set: the suite's, where the main job's module is compiled early).
Writes DIR/new_sweep.md.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import (ROOT, STUDIES, beside_done, forget_mechanisms,  # noqa: E402
                               fresh_mechanism_env, hardware, write_table)

def ways(one_process=False, against=None):
    """{way: (checkout, environment settings)}."""
    out = {"beside": (ROOT, {})}
    if one_process:
        out["one process"] = (ROOT, {"PIPELINE_COMPILE_BESIDE": "0"})
    if against is not None:
        out[f"beside, {Path(against).name}"] = (Path(against).resolve(), {})
        if one_process:
            out[f"one process, {Path(against).name}"] = (Path(against).resolve(),
                                                          {"PIPELINE_COMPILE_BESIDE": "0"})
    return out


def _run_env(code, cache, settings):
    """The runs' environment for the checkout ``code`` (its package first on the
    path, the process beside's too)."""
    env = fresh_mechanism_env(PIPELINE_CACHE_DIR=str(cache), **settings)
    env["PYTHONPATH"] = os.pathsep.join([str(code)] + [p for p in env.get("PYTHONPATH", "")
                                                       .split(os.pathsep) if p])
    return env


def sweep_seconds(study, n, cache, out, code, settings, keep=False):
    """Wall seconds of ``pipeline run study --candidates n`` as a new mechanism
    (``keep``: as the cache has it)."""
    if not keep:
        forget_mechanisms(cache)
    t = time.perf_counter()
    subprocess.run([sys.executable, "-m", "pipeline.cli", "run", str(STUDIES / f"{study}.toml"),
                    "--candidates", str(n), "-o", str(out / f"{study}.h5"), "--overwrite", "-q"],
                   env=_run_env(code, cache, settings), check=True, cwd=code,
                   stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t
    beside_done()
    return wall


def measure(study, n, rounds, chosen, keep=False, echo=print):
    """{way: [seconds per round]}, the ways alternated (``keep``: the generated
    modules kept, in PIPELINE_CACHE_DIR where it is set)."""
    times = {w: [] for w in chosen}
    with tempfile.TemporaryDirectory() as d:
        # (a folder name of its own: numba's cache names its folder after it)
        cache, out = Path(d) / f"modules_{Path(d).name}", Path(d) / "out"
        if keep and os.environ.get("PIPELINE_CACHE_DIR"):
            cache = Path(os.environ["PIPELINE_CACHE_DIR"])
        out.mkdir()
        for code in sorted({c for c, _ in chosen.values()}):   # once per installation
            t = time.perf_counter()
            subprocess.run([sys.executable, "-m", "pipeline.cli", "compile", "--library", "-q"],
                           env=_run_env(code, cache, {}), check=True, cwd=code)
            echo(f"library of {code} compiled or loaded in {time.perf_counter() - t:.1f} s")
        for r in range(rounds):
            order = list(chosen.items()) if r % 2 == 0 else list(chosen.items())[::-1]
            for way, (code, settings) in order:
                times[way].append(sweep_seconds(study, n, cache, out, code, settings, keep))
            echo(f"round {r + 1}: " + ", ".join(f"{w} {times[w][-1]:.1f} s" for w in chosen))
    return times


def table(times, study, n, rounds):
    def span(v):
        s = sorted(v)
        mid = s[len(s) // 2] if len(s) % 2 else 0.5 * (s[len(s) // 2 - 1] + s[len(s) // 2])
        return f"{s[0]:.1f}-{s[-1]:.1f} s (median {mid:.1f})" if len(s) > 1 else f"{s[0]:.1f} s"
    lines = ["# A new sweep mechanism's first candidates, end to end", "",
             f"hardware: {hardware()}", "",
             f"`pipeline run studies/{study}.toml --candidates {n:,}`, each a fresh process, "
             f"every generated module removed first (the library compiled); {rounds} round(s), "
             "the ways alternated.", "", "| way | seconds |", "|---|---|"]
    lines += [f"| {w} | {span(v)} |" for w, v in times.items()]
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--study", default="ov7_synthesis", help="a sweep study of studies/")
    ap.add_argument("--candidates", type=int, default=100_000)
    ap.add_argument("--one-process", action="store_true",
                    help="also every kernel in the run's process (PIPELINE_COMPILE_BESIDE=0)")
    ap.add_argument("--against", help="another checkout of the package, run the default way")
    ap.add_argument("--smoke", action="store_true", help="that it runs: 500 candidates, once")
    ap.add_argument("-o", "--out", default=str(ROOT / "results" / "bench"))
    a = ap.parse_args(argv)
    if a.against and not (Path(a.against) / "pipeline" / "__init__.py").is_file():
        ap.error(f"--against {a.against}: no checkout of the package there (pipeline/)")
    chosen = ways(a.one_process, a.against)
    study, n, rounds = a.study, a.candidates, a.rounds
    if a.smoke:
        chosen = {"beside": chosen["beside"]}
        n, rounds = 500, 1
    text = table(measure(study, n, rounds, chosen, keep=a.smoke), study, n, rounds)
    write_table(a.out, "new_sweep.md", text)
    return text


if __name__ == "__main__":
    main()
