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
# run by benchmarks/gpu_session.sh, whose smoke run is below (under numba's CUDA simulator)
IN_SESSION = {"bench_gpu.py"}
# run below as a user runs them: the script, its smoke flag, and what it writes
SMOKE = {
    "bench_sweep.py": (["--smoke"], None),
    "bench_kernels.py": (["--smoke"], None),
    "bench_dynamics.py": (["--smoke"], None),
    "bench_friction.py": (["--smoke"], None),
    "bench_watch.py": (["--smoke"], None),
    "bench_search.py": (["--smoke", "-o", "{tmp}"], "search.md"),
    "bench_compiler.py": (["--smoke", "-o", "{tmp}"], "compiler.md"),
    "agreement.py": (["--smoke", "--out", "{tmp}"], "agreement.md"),
    "bench_yardstick.py": (["--smoke", "-o", "{tmp}"], "yardstick.md"),
    "bench_host.py": (["--smoke", "-o", "{tmp}"], "host.md"),
    "bench_new_mechanism.py": (["--smoke", "-o", "{tmp}"], "new_mechanism.md"),
    "bench_new_sweep.py": (["--smoke", "-o", "{tmp}"], "new_sweep.md"),
    "bench_profile.py": (["--smoke", "-o", "{tmp}"], "profile.md"),
    "bench_plan_lanes.py": (["--smoke", "-o", "{tmp}"], "plan_lanes.md"),
    # (its kernels compiled only where numba-cuda, NVVM and ptxas are: not in CI)
    "gpu_ptx.py": (["--smoke", "-o", "{tmp}"], "gpu_ptx.md"),
}


def test_every_benchmark_script_has_a_smoke_run_in_the_suite():
    """A new script in benchmarks/ must be named here with the way the suite runs it."""
    scripts = {p.name for p in BENCHMARKS.glob("*.py")}
    named = IN_PROCESS | LIBRARIES | IN_SESSION | set(SMOKE)
    assert scripts == named, scripts ^ named


@pytest.mark.parametrize("script", sorted(SMOKE))
def test_benchmark_script_smoke_mode_runs(script, tmp_path):
    """The script in a fresh process at tiny sizes: exit 0 (agreement.py exits 1
    where the kernels disagree with the interpreter), no traceback, its table
    written where it was told (never into results/bench/)."""
    argv, written = SMOKE[script]
    env = child_env()
    before = snapshot(BENCH_OUT)
    r = subprocess.run([sys.executable, str(BENCHMARKS / script)]
                       + [a.format(tmp=tmp_path) for a in argv],
                       env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    assert "Traceback" not in r.stderr and r.stdout.strip(), r.stderr[-3000:]
    if written:
        assert (tmp_path / written).read_text().startswith("#")
    assert snapshot(BENCH_OUT) == before


def test_the_gpu_session_script_smoke_run_writes_its_table(tmp_path):
    """benchmarks/gpu_session.sh, the one call a lent GPU machine gets (issue 54), at
    smoke size under numba's CUDA simulator: both steps pass (the real-GPU test
    skipped, saying why; bench_gpu.py to its end to end row) and the table says
    so, with each step's log beside it."""
    before = snapshot(BENCH_OUT)
    r = subprocess.run(["bash", str(BENCHMARKS / "gpu_session.sh"), "--smoke", "--out",
                        str(tmp_path)], env=child_env(PYTHON=sys.executable),
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    table = (tmp_path / "gpu_session.md").read_text()
    assert table.startswith("# GPU session under numba's CUDA simulator"), table
    assert "| pytest -m gpu | passed" in table and "skipped" in table, table
    assert "| bench_gpu.py | passed" in table and "| bench_gpu.py | end to end" in table, table
    assert "| bench_host.py | passed" in table and "| bench_host.py | host alone" in table, table
    assert "| machine | numba |" in table, table
    for log in ("machine.log", "tests.log", "bench.log", "host.log", "host.md"):
        assert (tmp_path / log).stat().st_size > 0, log
    assert snapshot(BENCH_OUT) == before


def test_the_gpu_session_script_refuses_an_unknown_option(tmp_path):
    r = subprocess.run(["bash", str(BENCHMARKS / "gpu_session.sh"), "--fast"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "unknown option --fast" in r.stderr


def test_gpu_ptx_tells_code_from_numbering():
    """benchmarks/gpu_ptx.py --against: two kernels' PTX are "the same" where only
    the numbers numba gives its modules, functions, constant-memory symbols and
    environments differ (and the environments' declaration order), never where
    one instruction or constant does."""
    import runpy
    same_code = runpy.run_path(str(BENCHMARKS / "gpu_ptx.py"))["same_code"]
    a = "\n".join([
        ".common .global .align 8 .u64 _ZN08NumbaEnv34pipeline_mech_0123456789abcdef0123"
        "5watchB3v12B56abcE;",
        ".common .global .align 8 .u64 _ZN08NumbaEnv8pipeline7kernels7metrics5dwellB3v7B5xE;",
        ".const .align 8 .b8 _cudapy_cmem$97[16] = {8, 0, 0, 0, 0, 0, 0, 0, 9};",
        "\tmov.u64 \t%rd17, _cudapy_cmem$97;",
        "\tadd.f64 \t%fd3, %fd1, %fd2;",
        "\tcall.uni _ZN34pipeline_mech_0123456789abcdef01235settleB3v68B56abcE, (param0);"])
    b = "\n".join([
        ".common .global .align 8 .u64 _ZN08NumbaEnv8pipeline7kernels7metrics5dwellB3v9B5xE;",
        ".common .global .align 8 .u64 _ZN08NumbaEnv34pipeline_mech_fedcba98765432100123"
        "5watchB3v14B56abcE;",
        ".const .align 8 .b8 _cudapy_cmem$101[16] = {8, 0, 0, 0, 0, 0, 0, 0, 9};",
        "\tmov.u64 \t%rd17, _cudapy_cmem$101;",
        "\tadd.f64 \t%fd3, %fd1, %fd2;",
        "\tcall.uni _ZN34pipeline_mech_fedcba98765432100123" "5settleB3v70B56abcE, (param0);"])
    assert same_code(a, b)
    assert not same_code(a, b.replace("add.f64", "sub.f64"))
    assert not same_code(a, b.replace("8, 0, 0, 0, 0, 0, 0, 0, 9}", "8, 0, 0, 0, 0, 0, 0, 0, 7}"))
    assert not same_code(a, b.replace("5watch", "5watcH"))
