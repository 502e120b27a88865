"""Sweeps on a GPU (pipeline.gpu, pipeline.compiler.gpu) and store = feasible.

CI has no GPU: the CUDA kernels run under numba's CUDA simulator
(NUMBA_ENABLE_CUDASIM=1, which must be set before numba is imported, so in a
child process) against the CPU kernels.  The simulator runs the same kernel
function, thread by thread, calling the same generated functions; what it
cannot show is NVVM's code generation, checked by the tests marked ``gpu``
on a real device (skipped, with the reason, where there is none).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from pipeline.kernels import sweep as ks
from pipeline.study.reader import load_study
from pipeline.runs.sweep import run_sweep
from support.tolerances import (FAIL_ANGLE_TRIAD_RAD, GPU_AGREEMENT_REL,
                                GPU_FAIL_PHI_STEPS as FAIL_PHI_STEPS)
from pipeline.results.storage import variables

HERE = Path(__file__).resolve().parents[1]   # tests/
STUDIES = HERE.parent / "studies"
SIM = {**os.environ, "NUMBA_ENABLE_CUDASIM": "1"}
# metrics defined differently on the two CPU paths (pipeline.gpu's docstring):
# the lanes count a fixed number of Newton steps per position
PATH_DEFINED = {ks.M_NEWTON_MEAN}
REL = GPU_AGREEMENT_REL     # the README's figure


def _run(code, env=SIM, timeout=600):
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                       timeout=timeout, cwd=HERE.parent)
    assert r.returncode == 0, r.stderr[-3000:]
    return r.stdout


def _check_agreement(res):
    """Both GPU paths, the whole kernel and the split ones, held to the CPU; under
    the simulator the split kernels give the whole kernel's numbers bit for bit."""
    for case, v in res.items():
        if case == "simulator":
            continue
        for path, w in (("whole kernel", v), ("split kernels", v.get("split"))):
            if w is not None:   # (on a GPU the main job's alone: their compile's time)
                _agrees(f"{case}, {path}", w, res["simulator"])
        if res["simulator"]:
            assert v["split"]["status_vs_whole"] == 0, (case, "split kernels' statuses")
            assert v["split"]["bits_vs_whole"] == 0, (case, "split kernels' metrics")
    # the comparison saw what it is about: OK candidates with forces, and failures
    syn = res["ov7_synthesis.toml"]
    assert syn["statuses"][0] > 0 and syn["forces_done"] > 0 and "split" in syn
    assert sum(res["near-singular triads"]["statuses"][1:]) > 0


def _agrees(case, v, simulator):
    """One GPU path's statuses and metrics against the CPU's (``compare``)."""
    if "ulp" in v and not simulator:
        _within_conditioning(case, v)
    else:
        assert v["status_vs_cpu"] == 0, (case, "statuses differ from the CPU's")
        assert v["status_vs_careful"] == 0, case
        for c, (d, one) in v["vs_careful"].items():
            assert one == 0 and d <= REL, (case, "careful", c, d, one)
        for c, (d, one) in v["vs_cpu"].items():
            if int(c) not in PATH_DEFINED:
                assert one == 0 and d <= REL, (case, "cpu", c, d, one)


def _within_conditioning(case, v):
    """The near-singular candidates on a real GPU.  NVVM contracts a*b + c into
    FMA and libdevice rounds sin, cos and atan2 its own way: last-digit
    differences, which candidates built within 1e-10..1e-1 of a singular
    position magnify as much as any change of their input.  On an H100 (numba-cuda
    0.30.4) 4 of 10,000 statuses differed from the CPU's and 4,478 failure
    angles, by up to 1.0 rad; with every parameter one ulp up (down), the CPU's
    own answers changed 6 (4) statuses and 4,587 (4,560) angles, by up to 1.0
    (0.43) rad.  So the GPU may differ from the CPU by no more than the CPU
    differs from itself under those two one-ulp changes: statuses and angles
    counted (each step of FAIL_PHI_STEPS), metrics by their largest spread.  The
    same group must fail.  Under the simulator (the CPU's arithmetic) the check
    stays exact."""
    u = v["ulp"]
    assert v["status_vs_cpu"] <= sum(u["status"]), (case, "statuses", v["status_vs_cpu"],
                                                    u["status"])
    assert v["status_vs_careful"] <= sum(u["status"]), (case, "statuses vs careful")
    assert v["fail_group_vs_cpu"] == 0, (case, "a different group fails")
    for step, gpu, cpu in zip(FAIL_PHI_STEPS, v["fail_phi_over_vs_cpu"], u["fail_phi_over"]):
        assert gpu <= cpu, (case, f"failure angles over {step} rad apart", gpu, cpu)
    for c, (d, one) in v["vs_cpu"].items():
        if int(c) in PATH_DEFINED | {ks.M_FAIL_PHI, ks.M_FAIL_GROUP}:
            continue
        assert one == 0 and d <= max(REL, u["metrics"][c]), (case, c, d, u["metrics"][c])


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    out = tmp_path_factory.mktemp("gpu") / "agreement.json"
    _run(f"import runpy, sys; sys.argv = ['x', {str(out)!r}, '60']; "
         f"runpy.run_path({str(HERE / 'support' / 'gpu_agreement.py')!r}, run_name='__main__')")
    return json.loads(out.read_text())


def test_simulated_gpu_kernels_agree_with_the_cpu(simulated):
    """Every shipped sweep study and the near-singular stress candidates: the
    same statuses (failures at the same crank angle, in the same group) and
    metrics within 1e-12 relative, from the CPU's default path and from its
    careful path."""
    assert simulated["simulator"] is True
    _check_agreement(simulated)


def test_the_newton_count_is_the_one_path_defined_difference(simulated):
    """The lanes report their fixed Newton steps; a GPU thread counts its own,
    like the CPU's careful path (exactly)."""
    v = simulated["ov7_synthesis.toml"]
    assert v["vs_careful"][str(ks.M_NEWTON_MEAN)] == [0.0, 0]
    assert v["vs_cpu"][str(ks.M_NEWTON_MEAN)][0] > 0.0


def test_generated_cuda_module_is_imported_not_executed():
    """The kernel module is a file in the cache folder that calls the CPU
    module's own ``settle``: one source of the mechanism's numbers."""
    out = _run(
        "from pipeline.study.reader import load_study\n"
        "from pipeline.runs.sweep import build_problem\n"
        "from pipeline.compiler import gpu_kernels_for\n"
        "s = load_study('studies/ov7_synthesis.toml'); pb = build_problem(s, s.sweep)\n"
        "m = gpu_kernels_for(pb.plan, pb.rocker)\n"
        "print(m.SOURCE_PATH); print(m.CPU_MODULE); print(pb.kernels.__name__)\n")
    path, cpu, expected = out.split()
    assert cpu == expected
    text = Path(path).read_text()
    assert f"from {cpu} import" in text and "settle(" in text
    assert "exec(" not in text and "eval(" not in text


def test_sweep_on_the_simulated_gpu_writes_the_cpu_file(tmp_path):
    """`pipeline run --device gpu` end to end (chunks, journal, HDF5) gives the
    CPU run's file: statuses identical, metrics 1e-12; failure angles within the
    location figures (a CPU lane that flags itself is walked on the careful path
    from two positions before its flag, a GPU thread from the start: the same
    boundary located twice)."""
    cpu, gpu = tmp_path / "cpu.h5", tmp_path / "gpu.h5"
    args = ["run", "studies/ov7_synthesis.toml", "--candidates", "120", "--chunk-size", "50",
            "-q"]
    for out, extra, env in ((cpu, [], os.environ), (gpu, ["--device", "gpu"], SIM)):
        r = subprocess.run([sys.executable, "-m", "pipeline.cli", *args, "-o", str(out),
                            *extra], env=env, cwd=HERE.parent, capture_output=True, text=True,
                           timeout=600)
        assert r.returncode == 0, r.stderr[-2000:]
    with h5py.File(cpu) as a, h5py.File(gpu) as b:
        assert a.attrs["device"] == "cpu" and "simulator" in b.attrs["device"]
        np.testing.assert_array_equal(a["candidates/status"][()], b["candidates/status"][()])
        np.testing.assert_allclose(a["candidates/fail_phi"][()], b["candidates/fail_phi"][()],
                                   rtol=0, atol=2 * FAIL_ANGLE_TRIAD_RAD)
        np.testing.assert_array_equal(a["candidates/fail_group"][()],
                                      b["candidates/fail_group"][()])
        np.testing.assert_array_equal(a["candidates/feasible"][()], b["candidates/feasible"][()])
        np.testing.assert_array_equal(a["progress/status_counts"][()],
                                      b["progress/status_counts"][()])
        for m in variables(a["metrics"]):
            if m == "newton_iterations":
                continue
            np.testing.assert_allclose(b["metrics"][m][()], a["metrics"][m][()], rtol=REL,
                                       atol=0, err_msg=m)


def test_device_draws_are_the_cpus_to_the_bit(env=SIM):
    """Issue 54: a Sobol sweep's chunks drawn on the device (``runs.gpu_draws``:
    each point from its index, the triangles checked there, the broken rows
    redrawn on the host, the parameter rows written there) are the host's draws
    bit for bit: the design variables, the rejections per triangle and the
    parameter rows; for the first chunk, later ones drawn without those before
    them and the short last one.  A GPU sweep takes them where nothing reads its
    rows on the host (another sampler's, robust metrics' and friction's draws
    stay there)."""
    out = _run("""
import json
from dataclasses import replace
from pathlib import Path
from pipeline.study.reader import load_study
from pipeline.runs.sweep import build_problem
from pipeline.runs.gpu_draws import DeviceDraws
study = load_study(Path("studies/ov7_synthesis.toml"))
spec = replace(study.sweep.with_candidates(1000), chunk_size=300)
problem = build_problem(study, spec)
host = build_problem(study, spec)
draws, res = DeviceDraws(problem), []
for c in (3, 2, 0, 1):
    x, rejected, pars = draws.draw(c)
    x0, rejected0, pars0 = host.draw_chunk(c)
    res.append([c, len(x), x.tobytes() == x0.tobytes(), rejected.tolist(), rejected0.tolist(),
                pars.copy_to_host().tobytes() == pars0.tobytes()])
gpu = build_problem(study, spec, device="gpu")
uniform = build_problem(study, replace(spec, sampler="uniform"), device="gpu")
print(json.dumps({"chunks": res, "gpu": gpu._device_draws() is not None,
                  "uniform": uniform._device_draws() is None,
                  "cpu": problem._device_draws() is None}))
""", env=env)
    res = json.loads(out.strip().splitlines()[-1])
    for c, n, same_x, rejected, rejected0, same_pars in res["chunks"]:
        assert n == (100 if c == 3 else 300)
        assert same_x and same_pars and rejected == rejected0 and sum(rejected) > 0, c
    assert res["gpu"] and res["uniform"] and res["cpu"]


def test_device_keeps_exactly_the_feasible_rows(tmp_path, env=SIM):
    """Issue 54: with store = feasible the device judges each row
    (``runs.gpu_kept``, from ``objectives.feasibility_rules``) and only the
    feasible rows' metrics come back: their indices are those ``feasibility``
    finds in every row's metrics, with bounds on metrics that cut (a derived
    metric's factor among them) and rows that fail, and their metrics the
    same bits; a store-feasible sweep on the device keeps the CPU's rows and
    every chunk's counts."""
    out = _run("""
import json
import numpy as np
from dataclasses import replace
from pathlib import Path
from pipeline.study.reader import load_study
from pipeline.study.objectives import feasibility
from pipeline.runs.sweep import build_problem
study = load_study(Path("studies/ov7_synthesis.toml"))
spec = replace(study.sweep.with_candidates(600), chunk_size=600, store="feasible",
               bounds=(("peak_reaction", -np.inf, 1200.0), ("dwell_start", -225.0, np.inf)))
problem = build_problem(study, spec, device="gpu")
x, rejected, pars = problem.draw_chunk(0)
status, metrics = problem.gpu().evaluate_rows(pars)
st2, kept_metrics, kept = problem.gpu().evaluate_kept(pars)
judged = feasibility(spec, status, metrics, problem.has_margin)
print(json.dumps({"same_status": bool((status == st2).all()),
                  "kept": kept.tolist(), "host": np.flatnonzero(judged.feasible).tolist(),
                  "rows": kept_metrics.tobytes() == metrics[kept].tobytes(),
                  "ok": int((status == 0).sum()), "n": len(status)}))
""", env=env)
    res = json.loads(out.strip().splitlines()[-1])
    assert res["same_status"] and res["rows"]
    assert res["kept"] == res["host"]
    assert 0 < len(res["kept"]) < res["ok"] < res["n"]     # the bounds cut OK rows
    if env is not SIM:      # on a GPU its statuses may differ from the CPU's (see below)
        return
    cpu, gpu = tmp_path / "cpu.h5", tmp_path / "gpu.h5"
    args = ["run", "studies/ov7_synthesis.toml", "--candidates", "150", "--chunk-size", "50",
            "--store", "feasible", "-q"]
    for path, extra, env in ((cpu, [], os.environ), (gpu, ["--device", "gpu"], SIM)):
        r = subprocess.run([sys.executable, "-m", "pipeline.cli", *args, "-o", str(path),
                            *extra], env=env, cwd=HERE.parent, capture_output=True, text=True,
                           timeout=600)
        assert r.returncode == 0, r.stderr[-2000:]
    with h5py.File(cpu) as a, h5py.File(gpu) as b:
        assert len(a["candidate"]) > 0
        for name in ("candidate", "candidates/status", "candidates/feasible",
                     "candidates/params", "progress/status_counts"):
            np.testing.assert_array_equal(a[name][()], b[name][()], err_msg=name)
        for m in variables(a["metrics"]):
            if m != "newton_iterations":
                np.testing.assert_allclose(b["metrics"][m][()], a["metrics"][m][()], rtol=REL,
                                           atol=0, err_msg=m)


def test_gpu_asked_for_without_one_names_what_is_missing(tmp_path):
    study = load_study(STUDIES / "ov7_synthesis.toml")
    out = tmp_path / "x.h5"
    code = ("from pipeline.runs.gpu import probe; import json; print(json.dumps(probe()['missing']))")
    missing = json.loads(_run(code, env={k: v for k, v in os.environ.items()
                                         if k != "NUMBA_ENABLE_CUDASIM"}))
    if missing is None:
        pytest.skip("this machine has a usable GPU")
    with pytest.raises(ValueError, match="--device gpu: no usable GPU; missing"):
        run_sweep(study, out, candidates=10, device="gpu", progress=False)
    assert not out.exists()      # refused before anything is written
    res = run_sweep(study, out, candidates=10, device="auto", progress=False)
    assert "device" not in res.summary      # auto took the CPU
    with pytest.raises(ValueError, match="Dask cluster"):
        run_sweep(study, tmp_path / "y.h5", candidates=10, device="gpu",
                  scheduler="tcp://127.0.0.1:1", progress=False)
    with pytest.raises(ValueError, match="--device must be one of"):
        run_sweep(study, tmp_path / "z.h5", candidates=10, device="tpu", progress=False)


# ----------------------------------------------------------------- store = feasible
def test_store_feasible_keeps_the_feasible_rows_and_every_count(tmp_path):
    study = load_study(STUDIES / "ov7_synthesis.toml")
    full, kept = tmp_path / "all.h5", tmp_path / "feasible.h5"
    run_sweep(study, full, candidates=900, chunk_size=300, progress=False)
    run_sweep(study, kept, candidates=900, chunk_size=300, progress=False, store="feasible")
    with h5py.File(full) as a, h5py.File(kept) as b:
        feas = a["candidates/feasible"][()]
        assert 0 < feas.sum() < len(feas)
        assert b.attrs["store"] == "feasible" and b.attrs["n_candidates"] == 900
        np.testing.assert_array_equal(b["candidate"][()], np.flatnonzero(feas))
        for name in ("candidates/params", "candidates/status", "candidates/constraints",
                     "candidates/cv", "candidates/feasible", "metrics/dwell_error",
                     "metrics/peak_reaction"):
            np.testing.assert_array_equal(b[name][()], a[name][()][feas], err_msg=name)
        np.testing.assert_array_equal(a["progress/status_counts"][()],
                                      b["progress/status_counts"][()])
        counts = a["progress/status_counts"][()].sum(axis=0)
        assert counts[:-1].sum() == 900 and counts[-1] == feas.sum()
    from pipeline.views.browse import browse
    from pipeline.results.sweep_file import summarize
    sa, sb = summarize(full), summarize(kept)
    assert sa["candidates"] == sb["candidates"] == 900
    assert sa["feasible"] == sb["feasible"] and sa["status OK"] == sb["status OK"]
    first = int(np.flatnonzero(feas)[0])
    assert f"candidate {first}: OK" in browse(kept, candidate=str(first))
    missing = int(np.flatnonzero(~feas)[0])
    with pytest.raises(ValueError, match="kept only its feasible candidates"):
        browse(kept, candidate=str(missing))


def test_store_feasible_resumes_to_the_same_file(tmp_path):
    from pipeline.runs.lifecycle import SweepInterrupted
    from support.sweep_helpers import assert_same_results
    study = load_study(STUDIES / "ov7_synthesis.toml")
    once, twice = tmp_path / "once.h5", tmp_path / "twice.h5"
    run_sweep(study, once, candidates=600, chunk_size=200, progress=False, store="feasible")
    with pytest.raises(SweepInterrupted):
        run_sweep(study, twice, candidates=600, chunk_size=200, progress=False,
                  store="feasible", stop_after_chunks=1)
    with pytest.raises(Exception, match="different store"):
        run_sweep(study, twice, resume=True, progress=False, store="all")
    run_sweep(study, twice, resume=True, progress=False, store="feasible")
    assert_same_results(once, twice)


# ----------------------------------------------------------------- a real GPU
def _real_gpu_missing():
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
    r = subprocess.run([sys.executable, "-c", "from pipeline.runs.gpu import probe; import json; "
                        "print(json.dumps(probe()['missing']))"], env=env,
                       capture_output=True, text=True, timeout=120)
    if r.returncode != 0:
        return "numba.cuda does not import"
    return json.loads(r.stdout.strip().splitlines()[-1])


@pytest.mark.gpu
def test_real_gpu_kernels_agree_with_the_cpu(tmp_path):
    missing = _real_gpu_missing()
    if missing:
        pytest.skip(f"no usable GPU here (missing {missing})")
    out = tmp_path / "agreement.json"
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
    _run(f"import runpy, sys; sys.argv = ['x', {str(out)!r}, '2000']; "
         f"runpy.run_path({str(HERE / 'support' / 'gpu_agreement.py')!r}, run_name='__main__')", env=env,
         timeout=1800)
    res = json.loads(out.read_text())
    assert res["simulator"] is False
    _check_agreement(res)


@pytest.mark.gpu
def test_real_gpu_draws_and_kept_rows_are_the_hosts(tmp_path):
    """On a GPU: its draws are the CPU's bit for bit (the roundings kept apart),
    and the rows it keeps are those ``feasibility`` finds in its own metrics."""
    missing = _real_gpu_missing()
    if missing:
        pytest.skip(f"no usable GPU here (missing {missing})")
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
    test_device_draws_are_the_cpus_to_the_bit(env)
    test_device_keeps_exactly_the_feasible_rows(tmp_path, env)
