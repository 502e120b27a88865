"""A new mechanism's scene, end to end: the plan path against the generated module.

    python benchmarks/bench_new_mechanism.py [--rounds 2] [--study NAME] [--smoke] [-o DIR]

Each shipped scene study runs as a user runs it (``pipeline run STUDY
--no-pictures``, a fresh process, the wall time of the whole process), as a
mechanism new to the cache: every generated module (``pipeline_mech_*``) and its
compiled code removed first, the library kept compiled (the state after the
first sweep, or ``pipeline compile --library``).  Two ways, alternated
round by round on the same machine:

* plan path: the scene on kernels compiled once per installation that read the
  mechanism's plan as data (``pipeline.compiler.plan_path``), the default;
* generated: ``PIPELINE_PLAN_PATH=0``, the scene on the mechanism's own generated
  module, compiled for it (its forces in a process beside, as a user's run).

Python's bytecode as an installation has it (the library's compile and one
untimed scene write it).  A set PYTHONDONTWRITEBYTECODE, as in some sandboxes,
is left out of the runs: every process would compile the package's 33,000
lines of source again, about 0.15 s that no installed copy spends.
Both write the same numbers (tests/compiler/test_plan_path.py holds the bits).
Issue 53's line: a new mechanism's scene in at most 2 s end to end.
--smoke (the test suite): one study, one round.  Writes DIR/new_mechanism.md.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import (ROOT, STUDIES, beside_done, forget_mechanisms,  # noqa: E402
                               fresh_mechanism_env, hardware, write_table)

SCENES = ("ov7_base", "warp_feed_fourbar", "feed_fivebar", "ov7_class3", "ov7_class3_slider",
          "ov7_friction", "scotch_yoke_rpp", "slotted_rocker_prp", "ppr_cross_slide",
          "cam_rocker_input", "actuator_slider_input", "takeup_dynamics")
WAYS = {"plan path": "1", "generated": "0"}


def scene_seconds(study, cache, out, plan_path):
    """Wall seconds of ``pipeline run study`` as a new mechanism."""
    forget_mechanisms(cache)
    env = fresh_mechanism_env(PIPELINE_CACHE_DIR=str(cache), PIPELINE_PLAN_PATH=plan_path)
    t = time.perf_counter()
    subprocess.run([sys.executable, "-m", "pipeline.cli", "run", str(STUDIES / f"{study}.toml"),
                    "-o", str(out / f"{study}.h5"), "--overwrite", "--no-pictures", "-q"],
                   env=env, check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t
    beside_done()
    return wall


def measure(studies, rounds, echo=print):
    """{study: {way: [seconds per round]}}, the ways alternated."""
    times = {s: {w: [] for w in WAYS} for s in studies}
    with tempfile.TemporaryDirectory() as d:
        # (a folder name of its own: numba's cache names its folder after it)
        cache, out = Path(d) / f"modules_{Path(d).name}", Path(d) / "out"
        out.mkdir()
        env = fresh_mechanism_env(PIPELINE_CACHE_DIR=str(cache))
        t = time.perf_counter()     # the library, once per installation (not timed below)
        subprocess.run([sys.executable, "-m", "pipeline.cli", "compile", "--library", "-q"],
                       env=env, check=True, cwd=ROOT)
        echo(f"library (plan path included) compiled or loaded in {time.perf_counter() - t:.1f} s")
        scene_seconds(studies[0], cache, out, WAYS["plan path"])    # (its bytecode: untimed)
        for r in range(rounds):
            order = list(WAYS.items()) if r % 2 == 0 else list(WAYS.items())[::-1]
            for s in studies:
                for way, flag in order:
                    times[s][way].append(scene_seconds(s, cache, out, flag))
                echo(f"round {r + 1} {s}: " + ", ".join(
                    f"{w} {times[s][w][-1]:.2f} s" for w in WAYS))
    return times


def table(times, rounds):
    def span(v):
        return f"{min(v):.2f}-{max(v):.2f} s" if len(v) > 1 else f"{v[0]:.2f} s"
    lines = ["# A new mechanism's scene, end to end", "", f"hardware: {hardware()}", "",
             f"`pipeline run STUDY --no-pictures`, each a fresh process, every generated module "
             f"removed first (the library compiled); {rounds} round(s), the two ways alternated.",
             "", "| study | plan path | generated (`PIPELINE_PLAN_PATH=0`) | at most 2 s |",
             "|---|---|---|---|"]
    for s, v in times.items():
        ok = "yes" if max(v["plan path"]) <= 2.0 else "no"
        lines.append(f"| {s} | {span(v['plan path'])} | {span(v['generated'])} | {ok} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--smoke", action="store_true", help="one study, one round")
    ap.add_argument("--study", action="append", choices=SCENES,
                    help="only this scene (repeat for more); default every one")
    ap.add_argument("-o", "--out", default=str(ROOT / "results" / "bench"))
    a = ap.parse_args(argv)
    studies = SCENES[:1] if a.smoke else tuple(a.study or SCENES)
    rounds = 1 if a.smoke else a.rounds
    text = table(measure(studies, rounds), rounds)
    write_table(a.out, "new_mechanism.md", text)
    return text


if __name__ == "__main__":
    main()
