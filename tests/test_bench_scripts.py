"""Every script in benchmarks/ runs in the suite at smoke size, so none can rot
(issue 27): the ones tests/test_bench.py runs in its own process, and the rest
here as a user runs them, each in a fresh process with its --smoke flag.  Sizes
are tiny and the timings mean nothing; what is checked is that each runs to the
end and writes its table where it was told.  (A file of its own: pytest-xdist
deals out files, and these compile the frozen interpreter and the watch-free
kernels, about two minutes cold.)"""

import subprocess
import sys

import pytest

from support.checkout import BENCH_OUT, BENCHMARKS, child_env, snapshot


# ---- every script in benchmarks/ runs in the suite at smoke size, so none can rot
# run in tests/test_bench.py, in its process: `pipeline bench --quick` (run_all: bench_accuracy and
# bench_throughput), bench_tolerance, bench_robust, bench_report
IN_PROCESS = {"run_all.py", "bench_accuracy.py", "bench_throughput.py", "bench_tolerance.py",
              "bench_robust.py", "bench_report.py"}
LIBRARIES = {"common.py", "baselines.py"}       # imported by the scripts, not run
# run below as a user runs them: the script, its smoke flag, and what it writes
SMOKE = {
    "bench_sweep.py": (["--smoke"], None),
    "bench_kernels.py": (["--smoke"], None),
    "bench_dynamics.py": (["--smoke"], None),
    "bench_friction.py": (["--smoke"], None),
    "bench_watch.py": (["--smoke"], None),
    "bench_gpu.py": (["--smoke"], None),         # under numba's CUDA simulator
    "bench_search.py": (["--smoke", "-o", "{tmp}"], "search.md"),
    "bench_compiler.py": (["--smoke", "-o", "{tmp}"], "compiler.md"),
    "agreement.py": (["--smoke", "--out", "{tmp}"], "agreement.md"),
    "bench_yardstick.py": (["--smoke", "-o", "{tmp}"], "yardstick.md"),
}


def test_every_benchmark_script_has_a_smoke_run_in_the_suite():
    """A new script in benchmarks/ must be named here with the way the suite runs it."""
    scripts = {p.name for p in BENCHMARKS.glob("*.py")}
    assert scripts == IN_PROCESS | LIBRARIES | set(SMOKE), scripts ^ (IN_PROCESS | LIBRARIES
                                                                     | set(SMOKE))


@pytest.mark.parametrize("script", sorted(SMOKE))
def test_benchmark_script_smoke_mode_runs(script, tmp_path):
    """The script in a fresh process at tiny sizes: exit 0 (agreement.py exits 1
    where the kernels disagree with the interpreter), no traceback, its table
    written where it was told (never into results/bench/)."""
    argv, written = SMOKE[script]
    env = child_env(**({"NUMBA_ENABLE_CUDASIM": "1"} if script == "bench_gpu.py" else {}))
    before = snapshot(BENCH_OUT)
    r = subprocess.run([sys.executable, str(BENCHMARKS / script)]
                       + [a.format(tmp=tmp_path) for a in argv],
                       env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    assert "Traceback" not in r.stderr and r.stdout.strip(), r.stderr[-3000:]
    if written:
        assert (tmp_path / written).read_text().startswith("#")
    if script == "bench_gpu.py":
        assert "end to end" in r.stdout, r.stdout     # it ran, not "no usable GPU"
    assert snapshot(BENCH_OUT) == before
