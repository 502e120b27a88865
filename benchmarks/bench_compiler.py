"""The mechanism compiler against the yardstick, the old interpreter and NumPy.

    python benchmarks/bench_compiler.py [--quick | --smoke] [-o DIR]

--smoke (the test suite: that it runs): 256 candidates, timed once, the
whole process on 2,000; no yardstick, no interpreter, no compile times and no
mechanism A positions stage (each of those compiles or runs something else
for seconds to minutes; the suite runs the interpreter in agreement.py's smoke
mode, and the Stage code with B's and the four-bar's).

Every figure is steady state (each kernel runs once before it is timed) in
million candidate-positions per second, per core (1 thread) and on all cores,
and is held as a ratio against:

* the yardstick (``../shared/yardstick/run.sh``: hand-written SIMD C on the
  same jobs, run here, on this machine, before the measurements);
* the plan interpreter the product used before the compiler (a frozen copy in
  ``benchmarks/interpreter/``), on the same candidates, in the same process;
* the NumPy-vectorised baseline (four-bar positions).

Compile time is measured apart, each study in a fresh process: the default
study first with numba's cache and the generated modules' both empty (the first
run after installing), then scenes of mechanisms new to the cache, then each
again, cached.  Then where the default study's first compile goes, kernel by
kernel and phase by phase of numba's compiler (``CompileProfile``: one process,
nothing beside it; --smoke: a scene's, its library kernels from numba's cache).

Jobs (360 positions per revolution):
  B positions stage   dwell-only sweep stage of mechanism B (class III Newton to 1e-12,
                      rocker swing, dwell window): the default study's candidates, and
                      the assembled ones only (as the yardstick's triad_simd)
  A positions stage   the same stage for mechanism A (crank + 3 RRR), +-5 % candidates
  A full kinematics   positions and both analogs of every point (batch kernel)
  four-bar positions  the positions stage of the warp let-off four-bar, +-10 % candidates
  default study       the sweep's full metrics (positions, dwell, forces where feasible)
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from pipeline.base.files import write_text

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from common import ROOT, STUDIES, beside_done, best_of, hardware  # noqa: E402

YARDSTICK = ROOT.parent / "shared" / "yardstick" / "run.sh"


def yardstick():
    """{job: {threads: M cand-pos/s}} from the yardstick run on this machine."""
    if not YARDSTICK.exists():
        return {}
    out = subprocess.run(["bash", str(YARDSTICK)], capture_output=True, text=True,
                         timeout=600).stdout
    res = {}
    for line in out.splitlines():
        m = re.match(r"^(\w+)\s+(\d+)\s+([\d.]+)\s*$", line)
        if m:
            res.setdefault(m.group(1), {})[int(m.group(2))] = float(m.group(3))
    return res


def _perturbed(plan, n, spread, seed=1):
    """``n`` rows around the plan's reference row: every length and fixed
    coordinate that is not zero scaled by U(1 - spread, 1 + spread)."""
    rng = np.random.default_rng(seed)
    rows = np.repeat(plan.par[None, :], n, axis=0)
    for j, name in enumerate(plan.par_names):
        key = name.rsplit(".", 1)[1]
        if (key in ("x", "y", "length", "L_AB", "L_CB") or key.startswith("L")) \
                and not name.startswith("S[") and plan.par[j] != 0.0:
            rows[:, j] *= 1.0 + spread * rng.uniform(-1.0, 1.0, n)
    return np.ascontiguousarray(rows)


class Stage:
    """The sweep's positions stage (dwell only) of a mechanism with an output rocker."""

    def __init__(self, study_file, rocker, positions=360, forces=False, problem=None):
        from pipeline.compiler import kernels_for
        from pipeline.kernels import config as kc
        from pipeline.kernels import sweep as ks
        from pipeline.solve.scene import revolution_angles
        from pipeline.study.reader import load_study
        self.study = load_study(study_file)
        mech = self.study.mechanism
        self.plan = mech.compile()
        crank = mech.crank
        self.phis = revolution_angles(crank, positions)
        self.phi_close = crank.phi0 + crank.rot * 2.0 * math.pi
        self.tols = kc.default_tolerances()
        self.rocker = rocker
        self.kernels = kernels_for(self.plan, rocker)
        dwell_w = int(round(self.study.output.dwell_deg * positions / 360))
        self.settings = ks.settings(1.0, dwell_w, forces, -math.inf, math.inf, -math.inf,
                                    crank.omega1, crank.eps1)
        if problem is not None:
            self.settings = problem.settings()
        self.loads = np.zeros((positions, len(mech.loads), 3))
        self.dwell_w = dwell_w

    def run(self, pars, n_jobs):
        from pipeline.compiler.parallel import run_rows
        from pipeline.kernels import sweep as ks
        n = pars.shape[0]
        status = np.zeros(n, np.int8)
        metrics = np.full((n, ks.N_METRICS), np.nan)
        run_rows(self.kernels.evaluate, pars, self.phis, self.phi_close, self.tols,
                 self.settings, self.loads, status, metrics, n_jobs=n_jobs)
        return status, metrics

    def interpreter(self, pars, parallel):
        """The same stage on the frozen interpreter (status, metrics)."""
        from interpreter import sweep as isw
        from pipeline.kernels import sweep as ks
        p, s = self.plan, self.settings
        n = pars.shape[0]
        status = np.zeros(n, np.int8)
        metrics = np.full((n, ks.N_METRICS), np.nan)
        fn = isw.evaluate_batch_parallel if parallel else isw.evaluate_batch_serial
        fn(pars, p.codes, p.n_kinematic, p.gidx, p.goff, p.fixed_idx, p.fixed_off, p.n_points,
           self.phis, self.phi_close, self.tols, p.point(self.rocker[0]),
           p.point(self.rocker[1]), s[ks.SET_STROKE_RADIUS], int(s[ks.SET_DWELL_W]),
           bool(s[ks.SET_WANT_FORCES]), s[ks.SET_STROKE_LO], s[ks.SET_STROKE_HI],
           s[ks.SET_MARGIN_MIN], s[ks.SET_OMEGA1], s[ks.SET_EPS1], p.gravity, p.body_com,
           p.body_turn, p.body_mass_off, p.joint_point, p.joint_bodies, p.slide_bodies,
           p.slide_dir, p.slide_angle, p.crank_body, p.load_body, p.load_point, self.loads,
           status, metrics)
        return status, metrics


def _rate(fn, n_cand, positions, repeat):
    fn()                                       # warm-up: compile, caches
    beside_done()      # (a new module's process beside would share the cores)
    return n_cand * positions / best_of(fn, repeat) / 1e6


def measure(quick=False, n=None, interpreter=True, with_stage_a=True):
    import numba

    from pipeline.compiler.parallel import default_jobs
    from pipeline.runs.sweep import build_problem
    from pipeline.study.sweep_spec import parameter_rows
    from pipeline.study.sampling import draw_candidates, draw_unit
    cores = default_jobs()
    numba.set_num_threads(cores)
    n = n or (4096 if quick else 32768)
    rep = 1 if n < 1024 else 2 if quick else 3
    rows = []

    def row(job, yard_job, project_1, project_all, interp_1=None, numpy_1=None, note=""):
        rows.append(dict(job=job, yard=yard_job, p1=project_1, pall=project_all,
                         interp1=interp_1, numpy1=numpy_1, note=note))

    # ---- mechanism B positions stage: the default study's candidates
    syn_file = STUDIES / "ov7_synthesis.toml"
    from pipeline.study.reader import load_study
    syn = load_study(syn_file)
    spec = dataclasses.replace(syn.sweep, metrics=("dwell_error", "stroke",
                                                    "singularity_margin"),
                               objectives=("dwell_error",), chunk_size=1024)
    pb = build_problem(syn, spec)
    chunks = max(1, n // spec.chunk_size)
    x = np.concatenate([draw_candidates(spec, c) for c in range(chunks)])
    pars_b = parameter_rows(pb.plan, spec, x)
    # the draws as issue 11 measured them: before the sweep redrew impossible ternary
    # triangles (a third of the draws, BAD_GEOMETRY at no cost)
    lo = np.array([v.low for v in spec.variables])
    hi = np.array([v.high for v in spec.variables])
    raw = np.concatenate([lo + draw_unit(spec, c) * (hi - lo) for c in range(chunks)])
    pars_raw = parameter_rows(pb.plan, spec, raw)
    stage_b = Stage(syn_file, tuple(syn.output.rocker), problem=pb)
    status, _ = stage_b.run(pars_b, 1)
    status_raw, _ = stage_b.run(pars_raw, 1)
    beside_done()
    ok_b = np.ascontiguousarray(pars_b[status == 0])
    for label, pars, note in (
            ("B positions stage, the default study's raw draws (as issue 11 measured)",
             pars_raw, f"{100 * np.mean(status_raw == 5):.0f} % impossible triangles "
                       "(BAD_GEOMETRY, no cost; the sweep now redraws them)"),
            ("B positions stage, default study's candidates", pars_b,
             f"{100 * np.mean(status == 0):.0f} % assemble; failures redone on the careful path"),
            ("B positions stage, assembled candidates", ok_b, "as the yardstick's candidates")):
        r1 = _rate(lambda: stage_b.run(pars, 1), len(pars), 360, rep)
        ra = _rate(lambda: stage_b.run(pars, cores), len(pars), 360, rep)
        ri = _rate(lambda: stage_b.interpreter(pars, False), len(pars), 360, rep) \
            if interpreter else None
        row(label, "triad_simd", r1, ra, ri, note=note)

    # ---- mechanism A positions stage and full kinematics
    base = load_study(STUDIES / "ov7_base.toml")
    pars_a = _perturbed(base.mechanism.compile(), n, 0.05)
    if with_stage_a:
        stage_a = Stage(STUDIES / "ov7_base.toml", tuple(base.output.rocker))
        r1 = _rate(lambda: stage_a.run(pars_a, 1), n, 360, rep)
        ra = _rate(lambda: stage_a.run(pars_a, cores), n, 360, rep)
        ri = _rate(lambda: stage_a.interpreter(pars_a, False), n, 360, rep) \
            if interpreter else None
        row("A positions stage", "ov7_pos", r1, ra, ri)
    from pipeline.solve.scene import batch_revolutions
    nk = n // 4
    r1 = _rate(lambda: batch_revolutions(base, pars_a[:nk], 360, 2, False, n_jobs=1), nk, 360,
               rep)
    ra = _rate(lambda: batch_revolutions(base, pars_a[:nk], 360, 2, False, n_jobs=cores), nk,
               360, rep)
    row("A full kinematics (every point, both analogs)", "ov7_kin", r1, ra,
        note="careful path (libm), no lanes yet")

    # ---- four-bar positions stage
    fb = STUDIES / "warp_feed_fourbar.toml"
    stage_f = Stage(fb, ("P4", "P3"))
    pars_f = _perturbed(stage_f.plan, 4 * n, 0.10)
    r1 = _rate(lambda: stage_f.run(pars_f, 1), 4 * n, 360, rep)
    ra = _rate(lambda: stage_f.run(pars_f, cores), 4 * n, 360, rep)
    ri = _rate(lambda: stage_f.interpreter(pars_f, False), 4 * n, 360, rep) \
        if interpreter else None
    from baselines import fourbar_params, fourbar_positions_numpy
    fp = fourbar_params(stage_f.plan, pars_f[:n // 4])

    def numpy_fourbar():
        p = fourbar_positions_numpy(fp, stage_f.phis)
        np.arctan2(p[:, :, 1, 1], p[:, :, 1, 0] - fp[:, 3:4])    # the rocker angle
    rn = _rate(numpy_fourbar, n // 4, 360, rep)
    row("four-bar positions stage", "fourbar_pos", r1, ra, ri, rn,
        note="the product's stage: setup per candidate, positions, rocker angle, dwell window")
    # the same job as the yardstick's fourbar_pos and the NumPy baseline: positions and
    # the rocker angle of every candidate (the lane walk), blocks set up beforehand
    walk_rate = _walk_rate(stage_f, pars_f[:n], rep)
    row("four-bar positions (the lane walk: positions + rocker angle)", "fourbar_pos",
        walk_rate, float("nan"), None, rn, note="the yardstick's and NumPy's job")

    # ---- the default study, full metrics (kernel only; whole process below)
    pb_full = build_problem(syn, syn.sweep)
    nf = len(pars_b)
    t1 = _rate(lambda: pb_full.evaluate_rows(pars_b, n_jobs=1), nf, 1, rep) * 1e6
    ta = _rate(lambda: pb_full.evaluate_rows(pars_b, n_jobs=cores), nf, 1, rep) * 1e6
    ti = _rate(lambda: stage_b_full_interp(pb_full, pars_b), nf, 1, rep) * 1e6 \
        if interpreter else math.nan
    # the force stage in lanes against the scalar force stage (the same module, its
    # settings asking for the scalar stage), the same candidates, 1 core, alternated
    from pipeline.compiler.parallel import run_rows
    from pipeline.kernels import sweep as ks
    scalar_settings = pb_full.settings().copy()
    scalar_settings[ks.SET_SCALAR_FORCES] = 1.0

    def scalar_rows():
        st = np.zeros(nf, np.int8)
        met = np.full((nf, ks.N_METRICS), np.nan)
        run_rows(pb_full.kernels.evaluate, pars_b, pb_full.phis, pb_full.phi_close,
                 pb_full.tols, scalar_settings, pb_full.loads, st, met, n_jobs=1)
        return met
    forced = float(np.mean(scalar_rows()[:, ks.M_FORCES_DONE] == 1.0))
    lanes_1, scalar_1 = [], []
    for _ in range(rep):
        lanes_1.append(_rate(lambda: pb_full.evaluate_rows(pars_b, n_jobs=1), nf, 1, 1))
        scalar_1.append(_rate(scalar_rows, nf, 1, 1))
    return rows, dict(full_1=t1, full_all=ta, full_interp_all=ti, cores=cores,
                      force_lanes=max(lanes_1) / max(scalar_1), forced=forced)


def _walk_rate(stage, pars, rep):
    """M candidate-positions/s of the generated lane walk alone over ``pars``."""
    from pipeline.kernels.continuation import work
    k = stage.kernels
    L = k.LANES
    npos = len(stage.phis)
    blocks = []
    pos, d1, d2, m, state, _ = work(k.N_POINTS, k.N_GROUPS, k.N_TRIADS)
    phis = np.asarray(stage.phis)
    close = stage.phi_close if math.isfinite(stage.phi_close) else phis[0]
    called = k.callees()        # (the addresses of the kernels they call)
    for b in range(len(pars) // L):
        S = np.empty((k.N_LANE_ROWS, L))
        # the walk's rows: the positions, the closing one and two past it (as the
        # sweep's evaluate allocates them; walk_angle in the generated module)
        th = np.empty((npos + 3, L * k.THETA_COLS))
        for lane in range(L):
            k.setup_lane(pars, b * L + lane, lane, stage.phis, close, stage.tols, S, th, pos, d1,
                         d2, m, state, called)
        blocks.append((S, th))
    ext = np.concatenate([phis, close + (phis[:3] - phis[0])])
    c, s = np.cos(ext), np.sin(ext)

    def run():
        for S, th in blocks:
            k.block_walk(S, th, c, s, stage.phis, stage.tols, stage.settings, called)
    return _rate(run, len(blocks) * L, npos, rep)


def stage_b_full_interp(pb, pars):
    st = Stage(STUDIES / "ov7_synthesis.toml", tuple(pb.rocker), problem=pb)
    return st.interpreter(pars, True)


def whole_process(candidates):
    """`pipeline run` of the default study in a fresh process (kernels cached):
    candidates/s as the run reports it (compile excluded)."""
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "syn.h5"
        cmd = [sys.executable, "-m", "pipeline.cli", "run", str(STUDIES / "ov7_synthesis.toml"),
               "--candidates", str(candidates), "-o", str(out), "-q", "--format", "json"]
        t = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True, text=True, cwd=ROOT)
        wall = time.perf_counter() - t
        import h5py
        with h5py.File(out) as f:
            inner = float(f.attrs["wall_time_s"])
    return candidates / inner, wall


def compile_times(studies):
    """Seconds per study, each in a fresh process (`pipeline compile STUDY`), with
    both caches empty at the start: numba's (the library kernels' as well) and
    the generated modules'.  The first study is therefore compiled as on the
    first run after installing; each later one as a new mechanism afterwards
    (the library kernels it shares with the ones before load from the cache);
    then each study once more, cached.  Returns {study: (new, cached)}."""
    with tempfile.TemporaryDirectory() as d, tempfile.TemporaryDirectory() as nb:
        env = dict(os.environ, PIPELINE_CACHE_DIR=d, NUMBA_CACHE_DIR=nb)

        def once(s):
            p = subprocess.run([sys.executable, "-m", "pipeline.cli", "compile", str(s),
                                "--format", "json"], env=env, capture_output=True,
                               text=True, check=True, cwd=ROOT)
            beside_done()
            return float(re.search(r"(\d+\.\d+) s", p.stdout).group(1))
        new = {s.stem: once(s) for s in studies}
        return {s.stem: (new[s.stem], once(s)) for s in studies}


class CompileProfile:
    """Where a process's compile time goes: exclusive seconds per kernel and per
    phase of numba's compiler (numba's event API: ``numba:compile`` per kernel,
    ``numba:run_pass`` per compiler pass, ``numba:llvm_lock`` around every call
    into LLVM).  Phases: ``typing`` (type inference), ``lowering`` (numba's
    LLVM IR, without the LLVM calls in it), ``llvm`` (LLVM's optimisation and
    machine code, and IR parsing: where a kernel links its callees, LLVM
    optimises and emits their code once more in it) and ``other`` (numba's other
    passes: bytecode, SSA, inlining).  Exclusive: a kernel compiled while
    another is typed counts for itself, not for the one that calls it."""

    PHASES = {"nopython_type_inference": "typing", "native_lowering": "lowering"}
    KINDS = ("numba:compile", "numba:run_pass", "numba:llvm_lock")

    def __init__(self):
        self.stack = []     # [kind, name, start, seconds of the frames within]
        self.kernels = []   # the kernels being compiled, innermost last
        self.seconds = {}   # (kernel, phase): exclusive seconds

    def install(self):
        from numba.core import event

        profile = self

        class Listener(event.Listener):
            def on_start(self, ev):
                profile.start(ev)

            def on_end(self, ev):
                profile.end(ev)

        listener = Listener()
        for kind in self.KINDS:
            event.register(kind, listener)
        return self

    def start(self, ev):
        if ev.kind == "numba:compile":
            name = getattr(ev.data["dispatcher"], "py_func", ev.data["dispatcher"]).__name__
            self.kernels.append(name)
        elif ev.kind == "numba:run_pass":      # (its name: "PASS [function]")
            name = self.PHASES.get(ev.data["name"].split(" [")[0], "other")
        else:
            name = "llvm"
        self.stack.append([ev.kind, name, time.perf_counter(), 0.0])

    def end(self, ev):
        kind, name, t0, within = self.stack.pop()
        took = time.perf_counter() - t0
        if self.stack:
            self.stack[-1][3] += took
        if kind == "numba:compile":
            self.kernels.pop()
            key = (name, "other")
        elif self.kernels:
            key = (self.kernels[-1], name)
        else:
            return          # LLVM outside any compile (numba's start-up)
        self.seconds[key] = self.seconds.get(key, 0.0) + took - within

    def table(self, top=12):
        """{"phases": {phase: s}, "kernels": [[kernel, total, typing, lowering,
        llvm, other], ...] the ``top`` slowest, "n": kernels compiled}."""
        phases = ("typing", "lowering", "llvm", "other")
        per = {}
        for (k, ph), s in self.seconds.items():
            per.setdefault(k, dict.fromkeys(phases, 0.0))[ph] += s
        rows = sorted(([k, sum(v.values())] + [v[ph] for ph in phases]
                       for k, v in per.items()), key=lambda r: -r[1])
        return {"phases": {ph: sum(v[ph] for v in per.values()) for ph in phases},
                "kernels": rows[:top], "n": len(per)}


def _profile_child(study):
    """(In a process of its own: --profile-child.)  Compile ``study`` as `pipeline
    compile` does, every kernel in this process, and print its CompileProfile."""
    import json
    from pipeline.compile import compile_study
    from pipeline.study.reader import load_study
    profile = CompileProfile().install()
    t = time.perf_counter()
    compile_study(load_study(study))
    print(json.dumps(dict(profile.table(), seconds=time.perf_counter() - t)))


def compile_profile(study, empty_numba_cache=True):
    """CompileProfile of ``study``'s compile in a fresh process, the generated
    modules' cache empty and (``empty_numba_cache``) numba's: the first run after
    installing, all in that one process (no process beside it: every kernel is
    timed where it compiles).  Table lines."""
    import json
    with tempfile.TemporaryDirectory() as d, tempfile.TemporaryDirectory() as nb:
        env = dict(os.environ, PIPELINE_CACHE_DIR=d, PIPELINE_COMPILE_BESIDE="0")
        if empty_numba_cache:
            env["NUMBA_CACHE_DIR"] = nb
        p = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--profile-child",
                            str(study)], env=env, capture_output=True, text=True, check=True,
                           cwd=ROOT)
    r = json.loads(p.stdout.strip().splitlines()[-1])
    ph = r["phases"]
    if r["n"] and not (ph["typing"] > 0 and ph["lowering"] > 0):
        # (a numba whose passes are named otherwise: say so, never a table of zeros)
        raise RuntimeError(f"compile profile of {study}: {r['n']} kernels compiled but no "
                           f"time in numba's {', '.join(CompileProfile.PHASES)} passes")
    lines = [f"Where the compile of `{Path(study).stem}` goes: one process, nothing beside "
             f"it, {r['seconds']:.1f} s for {r['n']} kernels (numba's compile events; "
             "exclusive seconds, a kernel's callees apart): typing "
             f"{ph['typing']:.1f} s, lowering {ph['lowering']:.1f} s, LLVM {ph['llvm']:.1f} s "
             f"(optimisation and machine code, its callees' code again in each caller), other "
             f"passes {ph['other']:.1f} s.", "",
             "| kernel | s | typing | lowering | LLVM | other |", "|---|---|---|---|---|---|"]
    for k, tot, *rest in r["kernels"]:
        lines.append(f"| {k} | {tot:.2f} | " + " | ".join(f"{x:.2f}" for x in rest) + " |")
    return lines + [""]


# the sweeps issue 27 holds to half the default study's rate per candidate-position
OTHER_SWEEPS = ("cam_rocker_input_sweep", "ov7_class3_slider_sweep",
                "slotted_rocker_prp_sweep", "ppr_cross_slide_sweep")


def other_sweeps(names, n, reference_rate, cores, rep):
    """Table lines: each of the sweep studies ``names``' full evaluation (its own draws, metrics and
    constraints) on all cores, per candidate-position against the default study's
    ``reference_rate`` (candidates/s at its positions), whether its groups have
    lane forms, and the share of its candidates that reach the force stage."""
    from pipeline.kernels import sweep as ks
    from pipeline.runs.sweep import build_problem
    from pipeline.study.reader import load_study
    from pipeline.study.sweep_spec import parameter_rows
    from pipeline.study.sampling import draw_candidates
    ref = load_study(STUDIES / "ov7_synthesis.toml").sweep.positions
    lines = ["| sweep | candidates/s, all cores | positions | per candidate-position / "
             "ov7_synthesis | lanes | force stage for |", "|---|---|---|---|---|---|"]
    for name in names:
        study = load_study(STUDIES / f"{name}.toml")
        pb = build_problem(study, study.sweep)
        spec = dataclasses.replace(study.sweep, candidates=n, chunk_size=n)
        pars = np.ascontiguousarray(parameter_rows(pb.plan, spec, draw_candidates(spec, 0)))
        _, met = pb.evaluate_rows(pars)      # compiles (or loads) the kernels; the shares
        rate = _rate(lambda: pb.evaluate_rows(pars, n_jobs=cores), n, 1, rep) * 1e6
        share = np.mean(met[:, ks.M_FORCES_DONE] == 1.0)
        lines.append(f"| {name} | {rate:,.0f} | {spec.positions} | "
                     f"{rate * spec.positions / (reference_rate * ref):.2f} | "
                     f"{'yes' if pb.kernels.HAS_LANES else 'no'} | {100 * share:.0f} % |")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--smoke", action="store_true", help="that it runs, at tiny sizes")
    ap.add_argument("-o", "--out", default=str(ROOT / "results" / "bench"))
    ap.add_argument("--profile-child", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.profile_child:
        _profile_child(a.profile_child)
        return ""
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    lines = ["# Mechanism compiler: speed against the yardstick", "",
             f"hardware: {hardware()}", ""]
    yard = {} if a.smoke else yardstick()
    # the smoke run leaves mechanism A's positions stage out: a module of its own (25-30 s
    # of a cold suite), run by the same Stage code as B's and the four-bar's
    rows, full = measure(a.quick, 256 if a.smoke else None, interpreter=not a.smoke,
                         with_stage_a=not a.smoke)
    cores = full["cores"]
    lines += ["M candidate-positions/s; ratios against the yardstick (hand-written SIMD C, "
              "run here first) and against the old interpreter and NumPy on the same "
              "candidates, in this process.", "",
              "| job | project, 1 core | project, all cores | yardstick job, 1 core | "
              "project / yardstick | project / interpreter | project / NumPy | note |",
              "|---|---|---|---|---|---|---|---|"]
    def ratio(a, b, digits):
        return f"{a / b:.{digits}f}x" if b else ""
    for r in rows:
        # (where the yardstick cannot run here, its columns stay empty, the rest not)
        y = yard.get(r["yard"], {}).get(1)
        lines.append(
            f"| {r['job']} | {r['p1']:.1f} | {r['pall']:.1f} | {r['yard']} "
            f"{y if y else 'n/a'} | {ratio(r['p1'], y, 2)} | "
            f"{ratio(r['p1'], r['interp1'], 1)} | {ratio(r['p1'], r['numpy1'], 1)} | "
            f"{r['note']} |")
    interp = full["full_interp_all"]
    lines += ["", f"Default study, full metrics (kernels only): {full['full_1']:,.0f} "
              f"candidates/s on 1 core, {full['full_all']:,.0f} on {cores} cores"
              + (f"; the interpreter {interp:,.0f} on {cores} cores "
                 f"(x{full['full_all'] / interp:.1f})." if math.isfinite(interp) else ".")]
    lines += ["", f"The force stage in lanes (`pipeline/compiler/lane_forces.py`), the default "
              f"study's full metrics on 1 core, alternated with the same module whose force stage "
              f"is scalar (the same numbers to the bit): x{full['force_lanes']:.2f} the candidates/s "
              f"({100 * full['forced']:.0f} % of the candidates reach the force stage)."]
    lines += ["", "The other sweeps against the default study's full metrics on "
              f"{cores} cores (their own draws; the default study runs the force stage for "
              "the candidates that meet its stroke and margin, these for every candidate "
              "their constraints let through):", ""]
    # (the smoke run: one of them, whose kernels the test suite compiles anyway)
    lines += other_sweeps(OTHER_SWEEPS[:1] if a.smoke else OTHER_SWEEPS,
                          256 if a.smoke else 4096 if a.quick else 16384, full["full_all"],
                          cores, 1 if a.smoke else 2)
    lines.append("")
    n_whole = 2_000 if a.smoke else 50_000 if a.quick else 1_000_000
    # the yardstick again just before: the machine's speed drifts over minutes
    yard_now = {} if a.smoke else yardstick()
    rate, wall = whole_process(n_whole)
    from pipeline.study.reader import load_study
    positions = load_study(STUDIES / "ov7_synthesis.toml").sweep.positions
    y2 = yard_now.get("triad_simd", {}).get(cores)
    against = (f"; {rate * positions / 1e6:.1f} M candidate-positions/s, "
               f"{rate * positions / 1e6 / y2:.3f}x triad_simd on {cores} cores "
               f"({y2} M, run just before)" if y2 else "")
    lines += [f"Default study, whole process with HDF5 (`pipeline run`, {n_whole:,} "
              f"candidates, kernels cached): {rate:,.0f} candidates/s, {wall:.1f} s wall "
              f"for the process{against}.", ""]
    # the main job first (every cache empty: the first run after installing), then
    # scenes of mechanisms no study before them has (ov7_class3 is the default
    # study's own mechanism: its kernels are that study's, not a new mechanism's):
    # closed-form groups, crank dynamics, then (not --quick) group types the
    # studies before them do not have (PRP, a cam's rotary input, RPP, the class
    # III group with a slider)
    studies = [STUDIES / f"{s}.toml" for s in (
        "ov7_synthesis", "ov7_base", "warp_feed_fourbar", "takeup_dynamics",
        "slotted_rocker_prp", "cam_rocker_input", "scotch_yoke_rpp", "ov7_class3_slider")]
    ct = {} if a.smoke else compile_times(studies[:4] if a.quick else studies)
    if ct:
        lines += ["Compile time, each in a fresh process, numba's cache and the generated "
                  "modules' empty at the start (issue 27: the main job <= 8 s, a new "
                  "scene <= 3 s):", "",
                  "| study | new | cached |", "|---|---|---|"]
        for i, (k, v) in enumerate(ct.items()):
            what = ("the first run after installing" if i == 0 else
                    "a new mechanism afterwards")
            lines.append(f"| {k} ({what}) | {v[0]:.1f} s | {v[1]:.2f} s |")
        lines.append("")
    # the smoke run: a scene whose library kernels the suite has compiled (numba's
    # cache kept), so only its mechanism's own kernels compile
    lines += compile_profile(STUDIES / ("ov7_base.toml" if a.smoke else "ov7_synthesis.toml"),
                             empty_numba_cache=not a.smoke)
    text = "\n".join(lines) + "\n"
    print(text)
    write_text(out / "compiler.md", text)
    return text


if __name__ == "__main__":
    main()
