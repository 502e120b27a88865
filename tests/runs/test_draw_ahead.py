"""A local sweep's draws in a forked process (pipeline.runs.draw_ahead): the
run's own draws to the bit, whoever draws them and in whatever order; a child
that ends leaves the draws to the run, one that no run takes is ended; the
command line's run writes the same file with it and without it."""

import subprocess
import textwrap

from pipeline.base.processes import module_command
from support.sweep_helpers import assert_same_results

from conftest import STUDIES

# in an interpreter of its own: a test session has threads, where the run does not fork
CHILD = textwrap.dedent("""
    import os, signal, sys
    import numpy as np
    from dataclasses import replace
    from pipeline.study.reader import load_study
    from pipeline.study.sampling import draw_checked
    from pipeline.runs import draw_ahead
    study, search, scene = sys.argv[1:4]
    for other in (search, scene):       # forked for a sweep's run only
        draw_ahead.prefork(other)
        assert not draw_ahead._WAITING, other
    draw_ahead.prefork(study)           # a run that does not take it: ended, waited for
    pid = draw_ahead._WAITING[0].pid
    draw_ahead.let_go()
    assert not draw_ahead._WAITING
    try:
        os.waitpid(pid, os.WNOHANG)
        raise AssertionError("the child was not waited for")
    except ChildProcessError:
        pass
    draw_ahead.prefork(study)           # before the study is read, as `pipeline run` does
    ahead = draw_ahead._WAITING.pop()
    spec = replace(load_study(study).sweep, candidates=6000, chunk_size=1000)
    ahead.begin(spec)
    def same(c):
        x, rejected = ahead.draw(c)
        x0, rejected0 = draw_checked(spec, c)
        assert np.array_equal(x, x0) and np.array_equal(rejected, rejected0), c
    for c in (2, 0, 1, 5):          # out of order, as a resumed run asks
        same(c)
    assert not ahead.failed
    os.kill(ahead.pid, signal.SIGKILL)
    os.waitpid(ahead.pid, 0)
    same(3)                        # the child gone: this process draws, the same
    assert ahead.failed
    ahead.close()
    print("ok")
""")


def test_forked_draws_are_the_runs_own_and_survive_the_child():
    argv, env = module_command("pipeline")      # (the package's python and path)
    studies = [str(STUDIES / f"{s}.toml") for s in ("ov7_synthesis", "ov7_search", "ov7_base")]
    r = subprocess.run([argv[0], "-c", CHILD, *studies], env=env, capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr[-3000:]


def test_the_command_line_run_writes_the_same_file_with_and_without(tmp_path):
    study = str(STUDIES / "ov7_synthesis.toml")
    outs = {}
    for ahead in ("1", "0"):
        out = tmp_path / f"ahead_{ahead}.h5"
        argv, env = module_command("pipeline.cli", "run", study, "--candidates", "3000",
                                   "--chunk-size", "1000", "-o", str(out), "-q",
                                   "--no-pictures", "-v")
        env["PIPELINE_DRAW_AHEAD"] = ahead
        r = subprocess.run(argv, env=env, capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stderr[-3000:]
        outs[ahead] = (out, "the draws in process" in r.stderr)
    assert outs["1"][1] and not outs["0"][1]        # forked where asked, not where not
    assert_same_results(outs["1"][0], outs["0"][0])
