"""The CUDA kernels against the CPU kernels, on the same candidates: run as a
script (``python tests/support/gpu_agreement.py OUT.json [N [STUDY.toml ...]]``) in a process where
numba.cuda is the simulator (NUMBA_ENABLE_CUDASIM=1, set before numba is
imported) or a real GPU.  For every study named (default: the shipped sweep
studies of ``STUDIES``; ``all``: every study of ``studies/`` with a sweep; N drawn candidates,
constraints opened so the force stage runs for every assembled one) and for
the near-singular class III stress candidates, it writes per case: the
status disagreements, the failure angles located apart by more than each of
``FAIL_PHI_STEPS``, and per metric column the largest relative difference
of the GPU's numbers from the CPU's default path (lanes + careful; its spliced
lanes apart) and from
the CPU's careful path alone (``evaluate_careful``, the function every GPU
thread runs); the absolute difference for a column the catalogue calls
rounding-level (a residual: already relative, and at rounding level any path's
last bits change it entirely).  For the near-singular candidates it also writes
how far the CPU's own answers move when every input moves by one ulp
(``one_ulp``): on real hardware those candidates are judged against that scale
(tests/runs/test_gpu.py)."""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))     # tests/: the support package

from support.lanes import spliced_rows  # noqa: E402
from support.stress_cases import near_singular_triads  # noqa: E402
from support.tolerances import GPU_FAIL_PHI_STEPS as FAIL_PHI_STEPS  # noqa: E402

from pipeline.runs.gpu import GpuSweep  # noqa: E402
from pipeline.compiler.cuda_device import SIMULATOR  # noqa: E402
from pipeline.kernels import sweep as ks  # noqa: E402
from pipeline.model.metric_catalogue import CATALOGUE  # noqa: E402
from pipeline.study.reader import load_study  # noqa: E402
from pipeline.runs.sweep import build_problem  # noqa: E402
from pipeline.study.sampling import draw_checked  # noqa: E402
from pipeline.study.sweep_spec import parameter_rows  # noqa: E402

STUDIES = ("ov7_synthesis.toml", "ov7_synthesis_law.toml", "ov7_search.toml",
           "slotted_rocker_prp_sweep.toml", "cam_rocker_input_sweep.toml",
           "ov7_class3_slider_sweep.toml")
BATCH = 24      # small launches: several batches on both streams
ROUNDING = {m.column for m in CATALOGUE if m.rounding}     # compared absolutely


def careful(pb, pars):
    """The CPU's careful path, one candidate at a time."""
    k = pb.kernels
    n, w = len(pb.phis), pb.dwell_w
    status = np.zeros(len(pars), np.int8)
    metrics = np.full((len(pars), ks.N_METRICS), np.nan)
    col, trail = np.empty(n), np.empty((n + 1, 4))
    qmax, qmin = np.empty(n + w + 1, np.int64), np.empty(n + w + 1, np.int64)
    s = pb.settings()
    for i, row in enumerate(pars):
        status[i] = k.evaluate_careful(row, pb.phis, pb.phi_close, pb.tols, s, pb.loads, col,
                                       trail, qmax, qmin, metrics[i])
    return status, metrics


def rel(a, b, absolute=False):
    """Largest |a - b| / |b| (|a - b| if ``absolute``) where both are finite,
    and the count of rows where exactly one is finite."""
    both = np.isfinite(a) & np.isfinite(b)
    one = int((np.isfinite(a) != np.isfinite(b)).sum())
    if not both.any():
        return 0.0, one
    d = np.abs(a[both] - b[both])
    if not absolute:
        d = d / np.maximum(np.abs(b[both]), 1e-300)
    return float(d.max()), one


def located(a_st, a_m, b_st, b_m):
    """Of the candidates that fail with the same status on both sides, how many
    locate the failure more than each of ``FAIL_PHI_STEPS`` apart."""
    same = (a_st != 0) & (a_st == b_st)
    d = np.abs(a_m[same, ks.M_FAIL_PHI] - b_m[same, ks.M_FAIL_PHI])
    return [int((d > t).sum()) for t in FAIL_PHI_STEPS]


def one_ulp(pb, pars, st, m):
    """How far the CPU's own answers move when every parameter moves by one ulp
    (up, then down; counts summed, spreads the larger): the scale of an
    ill-conditioned candidate's answer, against which last-digit differences of
    another machine's arithmetic are judged."""
    out = {"status": [], "metrics": {}, "fail_phi_over": [0] * len(FAIL_PHI_STEPS)}
    for direction in (np.inf, -np.inf):
        st2, m2 = pb.evaluate_rows(np.nextafter(pars, direction))
        out["status"].append(int((st2 != st).sum()))
        ok = (st == 0) & (st2 == 0)
        for c in range(ks.N_METRICS):
            d = rel(m2[ok, c], m[ok, c], c in ROUNDING)[0]
            out["metrics"][c] = max(out["metrics"].get(c, 0.0), d)
        out["fail_phi_over"] = [a + b for a, b in
                                zip(out["fail_phi_over"], located(st2, m2, st, m))]
    return out


def compare(pb, pars, conditioning=False, split=True):
    """The GPU's whole kernel against the CPU (``against``), and where ``split``
    its split kernels (``split``: the same comparisons, and how many statuses and
    metric values differ from the whole kernel's, bit for bit)."""
    cpu_st, cpu_m = pb.evaluate_rows(pars)
    car_st, car_m = careful(pb, pars)
    gpu_st, gpu_m = GpuSweep(pb, batch=BATCH).evaluate_rows(pars)
    out = against(pb, pars, cpu_st, cpu_m, car_st, car_m, gpu_st, gpu_m, conditioning)
    if not split:
        return out
    spl_st, spl_m = GpuSweep(pb, batch=BATCH, stages="split").evaluate_rows(pars)
    out["split"] = against(pb, pars, cpu_st, cpu_m, car_st, car_m, spl_st, spl_m, False)
    out["split"]["status_vs_whole"] = int((spl_st != gpu_st).sum())
    out["split"]["bits_vs_whole"] = int((spl_m.view(np.uint64) != gpu_m.view(np.uint64)).sum())
    if conditioning:
        out["split"]["ulp"] = out["ulp"]
    return out


def against(pb, pars, cpu_st, cpu_m, car_st, car_m, gpu_st, gpu_m, conditioning):
    """One GPU path's statuses and metrics against the CPU's default path and
    its careful path (and, with ``conditioning``, the CPU's one-ulp spread)."""
    out = {"n": len(pars), "statuses": np.bincount(cpu_st, minlength=7).tolist(),
           "status_vs_cpu": int((gpu_st != cpu_st).sum()),
           "status_vs_careful": int((gpu_st != car_st).sum()),
           "forces_done": int((cpu_m[:, ks.M_FORCES_DONE] == 1).sum()),
           "vs_cpu": {}, "vs_careful": {}}
    ok = (cpu_st == 0) & (gpu_st == 0)
    failed = (cpu_st != 0) & (gpu_st != 0)
    # a lane the CPU spliced (its careful window solved to near rounding) differs from
    # the careful path every GPU thread runs by that path's own closure error, and
    # is held to the exact numbers by the lane tests (support.lanes.assert_lanes_agree)
    spliced = spliced_rows(pb, pars, cpu_st, cpu_m)
    out["spliced"] = int(spliced.sum())
    for c in range(ks.N_METRICS):
        # where it is defined
        rows = failed if c in (ks.M_FAIL_PHI, ks.M_FAIL_GROUP) else ok & ~spliced
        out["vs_cpu"][c] = rel(gpu_m[rows, c], cpu_m[rows, c], c in ROUNDING)
        out["vs_careful"][c] = rel(gpu_m[:, c], car_m[:, c], c in ROUNDING)
    out["fail_phi_over_vs_cpu"] = located(gpu_st, gpu_m, cpu_st, cpu_m)
    out["fail_group_vs_cpu"] = int((gpu_m[failed, ks.M_FAIL_GROUP]
                                    != cpu_m[failed, ks.M_FAIL_GROUP]).sum())
    if conditioning:
        out["ulp"] = one_ulp(pb, pars, cpu_st, cpu_m)
    return out


def main(path, n, names=STUDIES):
    studies = HERE.parent.parent / "studies"      # the checkout's studies/
    if list(names) == ["all"]:
        names = [p.name for p in sorted(studies.glob("*.toml"))
                 if load_study(p).sweep is not None]
    res = {"simulator": SIMULATOR}
    for name in names:
        study = load_study(studies / name)
        spec = dataclasses.replace(study.sweep, stroke_bounds=(-np.inf, np.inf),
                                   margin_min=-np.inf)
        pb = build_problem(study, spec)
        x, _ = draw_checked(spec, 0)
        # the split kernels: every study under the simulator; on a GPU, where each
        # compile takes its time, the main job's (and its near-singular triads')
        res[name] = compare(pb, np.ascontiguousarray(parameter_rows(pb.plan, spec, x)[:n]),
                            split=SIMULATOR or name == "ov7_synthesis.toml")
    if "ov7_synthesis.toml" in names:       # with the main job: its near-singular triads
        study = load_study(studies / "ov7_synthesis.toml")
        spec = dataclasses.replace(study.sweep, stroke_bounds=(-np.inf, np.inf),
                                   margin_min=-np.inf)
        pb = build_problem(study, spec)
        pars, _ = near_singular_triads(pb.plan, 5 * n, seed=11)   # a fifth of them assemble
        res["near-singular triads"] = compare(pb, pars, conditioning=True)
    Path(path).write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 60, sys.argv[3:] or STUDIES)
