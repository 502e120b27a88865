"""Agreement check: the generated kernels (pipeline.compiler) against the frozen
plan interpreter (benchmarks/interpreter), on the same candidates.

Cases:
  1. the stress suite's 100,000 constructed near-singular class III candidates
     (built as tests/kernels/test_stress.py builds them: seed 11, 72 positions, stroke and
     margin constraints that never fail so the force stage runs for every
     assembled candidate) through the sweep evaluation of ov7_synthesis;
  2. N Monte-Carlo candidates of studies/ov7_synthesis.toml (its own sampler,
     chunks 0, 1, ...) through the same sweep evaluation, with its own settings;
  3. per scene study: N candidates = the reference row with every length-like
     parameter scaled by 1 +- 5% (uniform, seeded), through the batch kernel
     (order 2, forces when the study has bodies), and the first 200 of them as
     full curves (``revolution`` against the interpreter's ``solve_revolution``).

A case passes when the statuses are identical for every candidate, no metric
is NaN in one path and a number in the other, and every compared metric
agrees within 1e-12 relative (|gen - ref| / max(|ref|, tiny)); positions are
compared relative to the mechanism's size (the larger side of the bounding
box of every point over the reference revolution), analogs relative to their
largest magnitude over the revolution.  ``newton_iterations`` is a solver
diagnostic that differs by design (the fast lane path takes a fixed 2 Newton
steps per position): reported, never counted.  Statuses: the generated kernels
watch between positions (pipeline/kernels/watch.py) and locate a failure where
it happens, so they report failures the interpreter does not see and name a
fold it met as SINGULAR at the dead position; a mismatch is a candidate the
generated kernels call OK where the interpreter failed, or a failure they
locate beyond the position where the interpreter met it (in the crank's
direction of travel).

Notes under the table diagnose every disagreement: the status pairs and the
first candidates, and for metric differences above the threshold where they
sit (the smallest singularity margin of those candidates, and the worst
difference over the well-conditioned ones); sweep candidates that disagree
are evaluated again on the generated careful path alone, which separates the
lane path's fixed Newton count (solutions equal within the Newton tolerance)
from rounding amplified near a singular position.  Both paths are compiled
with the project's floating-point flags (pipeline.kernels.config); to compare
them under strict IEEE, run with PIPELINE_FASTMATH=strict and fresh
NUMBA_CACHE_DIR and PIPELINE_CACHE_DIR (numba's cache key ignores the flags).

    python benchmarks/agreement.py [--candidates N] [--out DIR] [--smoke]
                                   [--positions 360] [--stress-candidates 100000]

Writes DIR/agreement.md (default results/bench/) and prints the same table;
exits 1 when a case fails.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
from numba import njit, prange

from pipeline.base.files import write_text

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))                 # interpreter, common
sys.path.insert(0, str(ROOT / "tests"))       # support.stress_cases

from common import STUDIES, hardware  # noqa: E402

# --smoke (the test suite's check that this script runs) runs the frozen
# interpreter as plain Python: numba's DISABLE_JIT while it (and _min_margins,
# which calls it) is defined, after every pipeline kernel has been (those stay
# compiled).  Compiling the interpreter is 60-80 s of a cold suite on 2 cores and
# tells the smoke nothing; its wall times then mean nothing either.
INTERPRETED = "--smoke" in sys.argv[1:]
if INTERPRETED:
    import importlib
    import pkgutil

    import numba

    import pipeline.group_types  # noqa: E402
    import pipeline.kernels  # noqa: E402
    for _m in pkgutil.iter_modules(pipeline.kernels.__path__):
        importlib.import_module(f"pipeline.kernels.{_m.name}")
    # the group types' kernels too: a generated module compiled later (a cold cache)
    # calls them, and one the interpreter imported first would be plain Python
    for _m in pkgutil.walk_packages(pipeline.group_types.__path__, "pipeline.group_types."):
        importlib.import_module(_m.name)
    numba.config.DISABLE_JIT = True
from interpreter.assembly import solve_revolution  # noqa: E402

THRESHOLD = 1e-12
WELL_CONDITIONED = 0.1            # margin (|sin| of a transmission angle, class III |det|)
TINY = np.finfo(float).tiny
EPS = np.finfo(float).eps
SCENES = ("ov7_base", "ov7_class3", "warp_feed_fourbar", "takeup_dynamics")
CURVES = 200
STRESS_N = 100_000
STRESS_SEED = 11
STRESS_POSITIONS = 72
SPREAD = 0.05
SEED = 2024
# sweep metrics compared (name -> kernel column), in table order
SWEEP_METRICS = ("dwell_error", "stroke", "singularity_margin", "peak_reaction", "peak_M_bal",
                 "dwell_start")
COLUMNS = ("dwell_error", "stroke", "singularity_margin", "peak_reaction", "peak_M_bal",
           "dwell_start", "peak_acc", "pos", "d1", "d2")
LENGTH_SUFFIXES = (".x", ".y", ".length", ".guide_length", ".offset")


# ----------------------------------------------------------------- comparisons
@dataclasses.dataclass
class Diff:
    """Largest relative difference of one quantity over a set of candidates."""
    value: float = 0.0            # max relative difference (0 when all identical)
    where: int = -1               # candidate index of the maximum
    ref: float = math.nan
    gen: float = math.nan
    nan_mismatch: int = 0         # NaN in one path, a number in the other
    nan_where: tuple = ()
    compared: int = 0             # candidates compared
    over: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, np.int64))

    @property
    def ok(self):
        return self.nan_mismatch == 0 and self.value <= THRESHOLD

    def cell(self):
        if self.compared == 0:
            return "n/a"
        s = f"{self.value:.1e}" if self.value else "0"
        if self.nan_mismatch:
            s += f" ({self.nan_mismatch} NaN!)"
        return s


def rel_diff(ref, gen, idx):
    """Diff of ref/gen (1-D) over candidate indices ``idx``."""
    r, g = ref[idx], gen[idx]
    d = Diff(compared=len(idx))
    rn, gn = np.isnan(r), np.isnan(g)
    bad = rn != gn
    d.nan_mismatch = int(bad.sum())
    d.nan_where = tuple(int(i) for i in idx[bad][:10])
    both = ~rn & ~gn & (r != g)               # equal values (infinities too) differ by 0
    if both.any():
        rel = np.abs(g[both] - r[both]) / np.maximum(np.abs(r[both]), TINY)
        rel = np.where(np.isnan(rel), np.inf, rel)   # inf against a different inf/number
        k = int(np.argmax(rel))
        d.value = float(rel[k])
        d.where = int(idx[both][k])
        d.ref, d.gen = float(ref[d.where]), float(gen[d.where])
        d.over = idx[both][rel > THRESHOLD]
    return d


@njit(cache=True, parallel=True)
def _min_margins(pars, codes, gidx, goff, fixed_idx, fixed_off, n_points, phis, tols, out):
    """Smallest singularity margin over every group and position of each
    candidate's revolution (the interpreter, positions only): how close it
    passes to a toggle or a class III singular position."""
    n = phis.shape[0]
    for i in prange(pars.shape[0]):
        pos = np.empty((n, n_points, 2))
        d = np.empty((1, 1, 2))
        st = np.zeros(n, np.int8)
        margin = np.zeros((n, codes.shape[0]))
        iters = np.zeros(n)
        solve_revolution(codes, gidx, goff, pars[i], fixed_idx, fixed_off, phis, math.nan, 0,
                         tols, pos, d, d, st, margin, iters)
        m = math.inf
        for k in range(n):
            for g in range(codes.shape[0]):
                m = min(m, margin[k, g])
        out[i] = m


if INTERPRETED:
    import interpreter.batch  # noqa: F401,E402
    import interpreter.dynamics  # noqa: F401,E402
    import interpreter.sweep  # noqa: F401,E402
    numba.config.DISABLE_JIT = False


def min_margins(plan, pars, phis, tols):
    out = np.empty(pars.shape[0])
    _min_margins(np.ascontiguousarray(pars), plan.codes, plan.gidx, plan.goff, plan.fixed_idx,
                 plan.fixed_off, plan.n_points, phis, tols, out)
    return out


def conditioning_note(case, diffs, margin, ok, what, worst):
    """Where the differences above the threshold sit: the largest ``what`` among
    those candidates, and (``worst(indices)`` -> {name: Diff}) the worst
    differences over the candidates whose margin is at least WELL_CONDITIONED."""
    over = np.unique(np.concatenate([d.over for d in diffs.values()] + [np.zeros(0, np.int64)]))
    if not len(over):
        return
    well = ok[margin[ok] >= WELL_CONDITIONED]
    case.notes.append(
        f"{len(over)} of {len(ok)} both-OK candidates differ by more than {THRESHOLD:g} in some "
        f"quantity; their {what}: at most {np.max(margin[over]):.3g} (median "
        f"{np.median(margin[over]):.3g}); over the {len(well)} candidates with {what} >= "
        f"{WELL_CONDITIONED:g}: " + ", ".join(f"{m} {d.cell()}" for m, d in worst(well).items()))


def status_pairs(ref, gen):
    from pipeline.kernels import config as kc
    bad = np.flatnonzero(ref != gen)
    pairs = Counter((kc.STATUS_NAMES[int(ref[i])], kc.STATUS_NAMES[int(gen[i])]) for i in bad)
    return bad, pairs


@dataclasses.dataclass
class Case:
    name: str
    kernel: str
    candidates: int
    both_ok: int
    status_ref: np.ndarray
    status_gen: np.ndarray
    diffs: dict
    newton: str
    t_ref: float
    t_gen: float
    notes: list = dataclasses.field(default_factory=list)
    extra_mismatches: int = 0     # curves: candidates whose per-position statuses differ only

    @property
    def mismatches(self):
        """Candidates the generated kernels call OK where the interpreter failed (a
        failure the generated kernels would miss).  The other way round is by design:
        the generated kernels watch between positions and locate a failure where it
        happens (pipeline/kernels/watch.py); the interpreter saw only the positions."""
        from pipeline.kernels import config as kc
        missed = (self.status_gen == kc.OK) & (self.status_ref != kc.OK)
        return int(missed.sum()) + self.extra_mismatches

    @property
    def found(self):
        """Status differences by design (see ``mismatches``)."""
        return int((self.status_ref != self.status_gen).sum()) - self.mismatches

    @property
    def passed(self):
        return self.mismatches == 0 and all(d.ok for d in self.diffs.values())


def timed(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def log(msg):
    print(msg, file=sys.stderr, flush=True)


# ----------------------------------------------------------------- sweep cases
def sweep_case(name, pb, pars, context=None):
    """Interpreter evaluate_batch_parallel against problem.evaluate_rows on ``pars``."""
    from interpreter import sweep as isw
    from pipeline.kernels import config as kc
    from pipeline.kernels import sweep as ks
    from pipeline.study.objectives import COLUMN

    plan, s = pb.plan, pb.spec
    n = pars.shape[0]

    def interp(rows):
        st = np.zeros(rows.shape[0], np.int8)
        met = np.full((rows.shape[0], isw.N_METRICS), np.nan)
        isw.evaluate_batch_parallel(
            rows, plan.codes, plan.n_kinematic, plan.gidx, plan.goff, plan.fixed_idx,
            plan.fixed_off, plan.n_points, pb.phis, pb.phi_close, pb.tols,
            plan.point(pb.rocker[0]), plan.point(pb.rocker[1]), s.stroke_radius, pb.dwell_w,
            s.wants_forces, s.stroke_bounds[0], s.stroke_bounds[1], s.margin_min, pb.omega1,
            pb.eps1, plan.gravity, plan.body_com, plan.body_turn, plan.body_mass_off,
            plan.joint_point, plan.joint_bodies, plan.slide_bodies, plan.slide_dir,
            plan.slide_angle, plan.crank_body, plan.load_body, plan.load_point, pb.loads, st,
            met)
        return st, met

    # the interpreter's metric columns at the same places (it is frozen: check); the
    # generated row has more after them (the failing group, ...)
    assert (isw.M_STROKE, isw.M_DWELL, isw.M_DWELL_START, isw.M_MARGIN, isw.M_PEAK_R,
            isw.M_PEAK_JOINT, isw.M_PEAK_PHI, isw.M_PEAK_MBAL, isw.M_FAIL_PHI,
            isw.M_NEWTON_MEAN, isw.M_FORCES_DONE) == \
        (ks.M_STROKE, ks.M_DWELL, ks.M_DWELL_START, ks.M_MARGIN, ks.M_PEAK_R,
         ks.M_PEAK_JOINT, ks.M_PEAK_PHI, ks.M_PEAK_MBAL, ks.M_FAIL_PHI, ks.M_NEWTON_MEAN,
         ks.M_FORCES_DONE) and ks.N_METRICS >= isw.N_METRICS

    warm = np.ascontiguousarray(pars[:64])
    interp(warm)                               # compile / load both before timing
    pb.evaluate_rows(warm, parallel=True)
    out = {}
    t_ref = timed(lambda: out.__setitem__("ref", interp(pars)))
    t_gen = timed(lambda: out.__setitem__("gen", pb.evaluate_rows(pars, parallel=True)))
    sr, mr = out["ref"]
    sg, mg = out["gen"]

    ok = np.flatnonzero((sr == kc.OK) & (sg == kc.OK))
    diffs = {}
    for m in SWEEP_METRICS:
        col = COLUMN[m][0]
        diffs[m] = rel_diff(mr[:, col], mg[:, col], ok)
    # a failure both see: located at or before the position where the interpreter met it
    both = np.flatnonzero((sr != kc.OK) & (sg != kc.OK) & np.isfinite(mr[:, ks.M_FAIL_PHI])
                          & np.isfinite(mg[:, ks.M_FAIL_PHI]))
    rot = math.copysign(1.0, pb.phis[-1] - pb.phis[0])
    ahead = rot * (mg[both, ks.M_FAIL_PHI] - mr[both, ks.M_FAIL_PHI])
    late = both[ahead > 1e-9]

    def worst(well):
        return {m: rel_diff(mr[:, COLUMN[m][0]], mg[:, COLUMN[m][0]], well)
                for m in SWEEP_METRICS if m != "fail_phi"}
    nd = rel_diff(mr[:, ks.M_NEWTON_MEAN], mg[:, ks.M_NEWTON_MEAN], ok)
    newton = nd.cell()
    case = Case(name, "evaluate", n, len(ok), sr, sg, diffs, newton, t_ref, t_gen,
                extra_mismatches=len(late))
    if len(both):
        moved = np.rad2deg(-ahead)
        case.notes.append(f"fail_phi: {len(both)} candidates fail in both; the generated kernels "
                          f"locate the failure {np.median(moved):.3g} deg (median) before the "
                          f"interpreter's failing position, up to {moved.max():.3g} deg; "
                          f"{len(late)} after it")

    # notes: what the comparison covers, and every disagreement
    forced_r = mr[:, ks.M_FORCES_DONE] == 1.0
    forced_g = mg[:, ks.M_FORCES_DONE] == 1.0
    case.notes.append(f"status counts (interpreter): {_counts(sr)}; force stage run for "
                      f"{int(forced_r.sum())} (interpreter) / {int(forced_g.sum())} (generated), "
                      f"{int((forced_r != forced_g).sum())} differ")
    for m in ("peak_joint", "peak_phi"):
        col = COLUMN[m][0]
        a, b = mr[ok, col], mg[ok, col]
        k = int((~((a == b) | (np.isnan(a) & np.isnan(b)))).sum())
        case.notes.append(f"{m} (not counted): {k} of {len(ok)} both-OK candidates differ")
    if nd.value:
        case.notes.append(f"newton_iterations (not counted): mean per position differs for "
                          f"{int((mr[ok, ks.M_NEWTON_MEAN] != mg[ok, ks.M_NEWTON_MEAN]).sum())} "
                          f"of {len(ok)} both-OK candidates; largest: candidate {nd.where} "
                          f"interpreter {nd.ref:.4g}, generated {nd.gen:.4g}")
    _status_notes(case, context, mr, mg)
    for m, d in diffs.items():
        _diff_notes(case, m, d, context, mr)
    conditioning_note(case, {m: d for m, d in diffs.items() if m != "fail_phi"},
                      mr[:, ks.M_MARGIN], ok, "singularity_margin", worst)
    careful_note(case, pb, pars, sr, mr, diffs)
    return case


def careful_note(case, pb, pars, sr, mr, diffs):
    """The disagreeing candidates again, every one on the generated careful path
    (the lane path vouches for no lane: settings[SET_MARGIN_SAFE] = inf): tells
    a difference of the lane path's fixed Newton count (gone on the careful
    path) from one of rounding (FMA contraction) amplified near a singular
    position (still there)."""
    import copy

    from pipeline.kernels import config as kc
    from pipeline.kernels import sweep as ks
    from pipeline.study.objectives import COLUMN
    if not hasattr(ks, "SET_MARGIN_SAFE"):
        return
    over = np.unique(np.concatenate(
        [d.over for m, d in diffs.items() if m != "fail_phi"] + [np.zeros(0, np.int64)]))
    bad = np.flatnonzero(case.status_ref != case.status_gen)
    sel = np.union1d(over, bad)
    if not len(sel):
        return
    careful = copy.copy(pb)
    base = pb.settings

    def settings():
        s = base()
        s[ks.SET_MARGIN_SAFE] = math.inf
        return s
    careful.settings = settings
    sc, mc = careful.evaluate_rows(np.ascontiguousarray(pars[sel]), parallel=True)
    line = (f"the {len(sel)} disagreeing candidates on the generated careful path only "
            f"(SET_MARGIN_SAFE = inf): ")
    if len(bad):
        same = int((sc[np.isin(sel, bad)] == sr[bad]).sum())
        line += f"statuses as the interpreter's for {same} of the {len(bad)} mismatches; "
    okc = np.flatnonzero((sc == kc.OK) & (sr[sel] == kc.OK))
    cols = [COLUMN[m][0] for m, d in diffs.items() if m != "fail_phi" and len(d.over)]
    if len(okc) and cols:
        a, b = mr[sel][okc][:, cols], mc[okc][:, cols]
        same = (a == b) | (np.isnan(a) & np.isnan(b))
        rel = np.where(same, 0.0, np.abs(b - a) / np.maximum(np.abs(a), TINY))
        worst = np.nanmax(np.where(np.isnan(rel), np.inf, rel), axis=1)
        still = okc[worst > THRESHOLD]
        iters = mc[still, ks.M_NEWTON_MEAN] != mr[sel[still], ks.M_NEWTON_MEAN]
        line += (f"{len(okc) - len(still)} of {len(okc)} OK in both agree within "
                 f"{THRESHOLD:g} there (their difference is the lane path's fixed Newton "
                 f"count: solutions equal within the Newton tolerance, not to rounding)")
        if len(still):
            line += (f"; {len(still)} still differ (largest {worst.max():.1e}, singularity_margin "
                     f"at most {np.max(mr[sel[still], ks.M_MARGIN]):.3g}, the difference at most "
                     f"{np.max(worst[worst > THRESHOLD] * mr[sel[still], ks.M_MARGIN] ** 2) / EPS:.2g}"
                     f" eps / margin^2: rounding amplified near a singular position; "
                     f"{int(iters.sum())} of them with another Newton "
                     "iteration count than the interpreter's)")
    case.notes.append(line)


def _counts(st):
    from pipeline.kernels import config as kc
    return ", ".join(f"{kc.STATUS_NAMES[int(c)]} {int((st == c).sum())}" for c in np.unique(st))


def _context(i, context, mr):
    from pipeline.kernels import sweep as ks
    bits = []
    if context is not None:
        for k, v in context.items():
            bits.append(f"{k} {v[i]:.3g}")
    if mr is not None and np.isfinite(mr[i, ks.M_MARGIN]):
        bits.append(f"singularity_margin {mr[i, ks.M_MARGIN]:.3g}")
    return ", ".join(bits)


def _status_notes(case, context, mr=None, mg=None):
    from pipeline.kernels import sweep as ks
    bad, pairs = status_pairs(case.status_ref, case.status_gen)
    if not len(bad):
        return
    case.notes.append("STATUS MISMATCHES (interpreter -> generated): "
                      + ", ".join(f"{a} -> {b}: {k}" for (a, b), k in pairs.most_common()))
    for i in bad[:10]:
        line = f"  candidate {i}: {_context(i, context, mr)}"
        if mr is not None:
            line += (f"; fail_phi interpreter {np.rad2deg(mr[i, ks.M_FAIL_PHI]):.6g} deg, "
                     f"generated {np.rad2deg(mg[i, ks.M_FAIL_PHI]):.6g} deg")
        case.notes.append(line)


def _diff_notes(case, m, d, context, mr=None):
    if d.nan_mismatch:
        case.notes.append(f"{m}: NaN in one path only for {d.nan_mismatch} candidates, e.g. "
                          f"{list(d.nan_where)}")
    if d.value > THRESHOLD:
        vals = (f"interpreter {d.ref!r}, generated {d.gen!r}" if np.isfinite(d.ref) else
                "largest over the revolution")
        ctx = _context(d.where, context, mr)
        case.notes.append(f"{m}: {d.value:.3e} relative at candidate {d.where} ({vals}"
                          + (f"; {ctx})" if ctx else ")"))


def stress_case(synthesis, n=STRESS_N):
    from pipeline.runs.sweep import build_problem
    from support.stress_cases import near_singular_triads
    spec = dataclasses.replace(synthesis.sweep, positions=STRESS_POSITIONS,
                               stroke_bounds=(-np.inf, np.inf), margin_min=-np.inf)
    pb = build_problem(synthesis, spec)
    pars, offset = near_singular_triads(pb.plan, n, seed=STRESS_SEED)
    log(f"case 1: {n:,} near-singular class III candidates, {STRESS_POSITIONS} positions")
    c = sweep_case("stress: near-singular class III (ov7_synthesis sweep, 72 pos.)", pb, pars,
                   {"offset": offset})
    return c


def montecarlo_case(synthesis, n):
    from pipeline.runs.sweep import build_problem
    from pipeline.study.sweep_spec import parameter_rows
    from pipeline.study.sampling import draw_candidates
    spec = synthesis.sweep.with_candidates(n)
    pb = build_problem(synthesis, spec)
    x = np.concatenate([draw_candidates(spec, c) for c in range(spec.n_chunks)])[:n]
    pars = parameter_rows(pb.plan, spec, x)
    log(f"case 2: {n:,} Monte-Carlo candidates of ov7_synthesis ({spec.sampler}, "
        f"{spec.positions} positions)")
    return sweep_case(f"ov7_synthesis Monte-Carlo ({spec.sampler}, {spec.positions} pos.)", pb,
                      pars)


# ----------------------------------------------------------------- scene cases
def length_like(plan):
    """Indices of the length-like parameters: link lengths, offsets, centre-of-mass
    arms and fixed point coordinates (not masses, inertias, angles, W,
    orientation, a0/b0, phi_start)."""
    out = []
    for i, name in enumerate(plan.par_names):
        last = name.rsplit(".", 1)[-1]
        if name.endswith(LENGTH_SUFFIXES) or (last.startswith("L") and last[1:2] in "0123456789_"):
            out.append(i)
    return out


def scene_cases(study_name, n, positions):
    import interpreter.assembly as ia
    from interpreter.batch import revolutions_batch
    from pipeline.solve.reactions import sample_loads
    from pipeline.kernels import config as kc
    from pipeline.compiler import kernels_for
    from pipeline.solve.scene import batch_revolutions, revolution_angles
    from pipeline.study.reader import load_study

    study = load_study(STUDIES / f"{study_name}.toml")
    mech = study.mechanism
    plan = mech.compile()
    idx = length_like(plan)
    rng = np.random.default_rng([SEED, SCENES.index(study_name)])
    pars = np.repeat(plan.par[None, :], n, axis=0)
    pars[:, idx] *= 1.0 + rng.uniform(-SPREAD, SPREAD, (n, len(idx)))
    pars = np.ascontiguousarray(pars)
    phis = revolution_angles(mech.crank, positions)
    tols = kc.default_tolerances()
    loads = sample_loads(mech, phis) if mech.loads else np.zeros((positions, 0, 3))
    point = plan.point(study.output.working_point)
    forces = len(plan.body_names) > 0
    order = kc.ACCELERATIONS
    log(f"case 3: {study_name}: {n:,} candidates x {positions} positions, order {order}, "
        f"forces {forces}; perturbed: {', '.join(plan.par_names[i] for i in idx)}")

    def interp(rows):
        m = rows.shape[0]
        st, acc, peak = np.zeros(m, np.int8), np.zeros(m), np.zeros(m)
        revolutions_batch(rows, plan.codes, plan.gidx, plan.goff, plan.fixed_idx,
                          plan.fixed_off, plan.n_points, phis, order, tols, point, forces,
                          mech.crank.omega1, mech.crank.eps1, plan.gravity, plan.body_com,
                          plan.body_turn, plan.body_mass_off, plan.joint_point,
                          plan.joint_bodies, plan.slide_bodies, plan.slide_dir,
                          plan.slide_angle, plan.crank_body, plan.load_body, plan.load_point,
                          loads, st, acc, peak)
        return st, acc, peak

    def generated(rows):
        # the product's entry point (the generated ``batch`` on all cores)
        return batch_revolutions(study, rows, positions, order, forces, tols)

    warm = np.ascontiguousarray(pars[:16])
    interp(warm)
    generated(warm)
    out = {}
    t_ref = timed(lambda: out.__setitem__("ref", interp(pars)))
    t_gen = timed(lambda: out.__setitem__("gen", generated(pars)))
    (sr, ar, pr), (sg, ag, pg) = out["ref"], out["gen"]
    ok = np.flatnonzero((sr == kc.OK) & (sg == kc.OK))
    diffs = {"peak_acc": rel_diff(ar, ag, ok)}
    if forces:
        diffs["peak_reaction"] = rel_diff(pr, pg, ok)
    batch = Case(f"{study_name}: lengths +-5%, {positions} pos.", "batch", n, len(ok), sr, sg,
                 diffs, "n/a", t_ref, t_gen)
    batch.notes.append(f"status counts (interpreter): {_counts(sr)}")
    _status_notes(batch, None)
    for m, d in diffs.items():
        _diff_notes(batch, m, d, None)
    if any(len(d.over) for d in diffs.values()):
        margin = np.full(n, np.nan)
        margin[ok] = min_margins(plan, pars[ok], phis, tols)
        pairs = {"peak_acc": (ar, ag), "peak_reaction": (pr, pg)}
        conditioning_note(batch, diffs, margin, ok, "smallest margin over the revolution",
                          lambda well: {m: rel_diff(*pairs[m], well) for m in diffs})

    # full curves of the first CURVES candidates
    m = min(CURVES, n)
    close = mech.crank.phi0 + mech.crank.rot * 2 * math.pi
    npnt, ng = plan.n_points, plan.n_groups

    def curves(fn, i):
        pos = np.full((positions, npnt, 2), np.nan)
        d1, d2 = np.full_like(pos, np.nan), np.full_like(pos, np.nan)
        st = np.zeros(positions, np.int8)
        margin = np.zeros((positions, ng))
        iters = np.zeros(positions)
        overall = fn(pars[i], pos, d1, d2, st, margin, iters)
        return overall, pos, d1, d2, st, margin, iters

    def ref_fn(par, pos, d1, d2, st, margin, iters):
        return ia.solve_revolution(plan.codes, plan.gidx, plan.goff, par, plan.fixed_idx,
                                   plan.fixed_off, phis, close, order, tols, pos, d1, d2, st,
                                   margin, iters)

    revolution = kernels_for(plan).revolution
    fail = np.empty(2)        # where a failure is (the interpreter has no such output)

    def gen_fn(par, pos, d1, d2, st, margin, iters):
        return revolution(par, phis, close, order, tols, pos, d1, d2, st, margin, iters, fail)

    curves(ref_fn, 0)
    curves(gen_fn, 0)
    res = {}
    t_cref = timed(lambda: res.__setitem__("ref", [curves(ref_fn, i) for i in range(m)]))
    t_cgen = timed(lambda: res.__setitem__("gen", [curves(gen_fn, i) for i in range(m)]))
    osr = np.array([r[0] for r in res["ref"]], np.int8)
    osg = np.array([g[0] for g in res["gen"]], np.int8)
    per_pos = [i for i in range(m) if not np.array_equal(res["ref"][i][4], res["gen"][i][4])]
    rel = {"pos": np.zeros(m), "d1": np.zeros(m), "d2": np.zeros(m)}
    nanbad = {"pos": [], "d1": [], "d2": []}
    iters_differ = margin_max = 0
    cmargin = np.full(m, np.nan)
    for i in range(m):
        r, g = res["ref"][i], res["gen"][i]
        if not (r[0] == kc.OK and g[0] == kc.OK):
            rel["pos"][i] = rel["d1"][i] = rel["d2"][i] = np.nan
            continue
        size = max(np.ptp(r[1][:, :, 0]), np.ptp(r[1][:, :, 1]))
        for key, a, b, scale in (("pos", r[1], g[1], size),
                                 ("d1", r[2], g[2], np.abs(r[2]).max()),
                                 ("d2", r[3], g[3], np.abs(r[3]).max())):
            if not np.array_equal(np.isnan(a), np.isnan(b)):
                nanbad[key].append(i)
            rel[key][i] = np.nanmax(np.abs(b - a)) / max(scale, TINY)
        cmargin[i] = np.min(r[5])
        iters_differ += int(not np.array_equal(r[6], g[6]))
        fin = np.isfinite(r[5]) & np.isfinite(g[5])
        if fin.any():
            margin_max = max(margin_max, float(np.max(np.abs(g[5][fin] - r[5][fin]))))
    cok = np.flatnonzero((osr == kc.OK) & (osg == kc.OK))

    def curve_diffs(sel):
        out = {}
        for key in ("pos", "d1", "d2"):
            bad = [i for i in nanbad[key] if i in set(sel)]
            d = Diff(compared=len(sel), nan_mismatch=len(bad), nan_where=tuple(bad[:10]))
            if len(sel):
                k = int(np.argmax(rel[key][sel]))
                d.value, d.where = float(rel[key][sel][k]), int(sel[k])
                d.over = sel[rel[key][sel] > THRESHOLD]
            out[key] = d
        return out

    cdiffs = curve_diffs(cok)
    cur = Case(f"{study_name}: first {m}, full curves", "revolution", m, len(cok), osr, osg,
               cdiffs, f"{iters_differ} differ", t_cref, t_cgen)
    cur.notes.append(f"overall status counts (interpreter): {_counts(osr)}; per-position "
                     f"status arrays differ for {len(per_pos)} candidates"
                     + (f" {per_pos[:10]}" if per_pos else "")
                     + f"; largest abs difference of the margins {margin_max:.2e}")
    cur.extra_mismatches = sum(1 for i in per_pos if osr[i] == osg[i])
    _status_notes(cur, None)
    for key, d in cdiffs.items():
        _diff_notes(cur, key, d, None)
    conditioning_note(cur, cdiffs, cmargin, cok, "smallest margin over the revolution",
                      curve_diffs)
    return [batch, cur]


# ----------------------------------------------------------------- the table
def table(cases):
    head = (["case", "kernel", "candidates", "both OK", "status mismatches"] + list(COLUMNS)
            + ["newton_iterations (info)", "interpreter s", "generated s", "verdict"])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for c in cases:
        row = [c.name, c.kernel, f"{c.candidates:,}", f"{c.both_ok:,}", str(c.mismatches)]
        row += [c.diffs[k].cell() if k in c.diffs else "-" for k in COLUMNS]
        row += [c.newton, f"{c.t_ref:.2f}", f"{c.t_gen:.2f}", "PASS" if c.passed else "FAIL"]
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def _jobs():
    try:
        from pipeline.compiler.parallel import default_jobs
    except ImportError:       # kernels parallel in numba (prange)
        import numba
        return numba.get_num_threads()
    return default_jobs()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", type=int, default=100_000,
                    help="Monte-Carlo and scene candidates per case (default 100000)")
    ap.add_argument("--positions", type=int, default=360,
                    help="positions per revolution of the scene cases (default 360)")
    ap.add_argument("--stress-candidates", type=int, default=STRESS_N,
                    help="near-singular candidates of case 1 (default: the stress suite's 100000)")
    ap.add_argument("--out", default=str(ROOT / "results" / "bench"))
    ap.add_argument("--smoke", action="store_true",
                    help="that it runs (the test suite): 20 candidates per case, 36 "
                         "positions, one scene study (mechanism B's: each scene compiles "
                         "its own kernels, 25-30 s cold), the interpreter as plain Python "
                         "(numba compiles none of it; its times mean nothing)")
    a = ap.parse_args(argv)
    if a.smoke:
        a.candidates, a.stress_candidates, a.positions = 20, 20, 36
    if a.candidates < 1:
        ap.error("--candidates must be at least 1")
    import numba

    from pipeline.kernels.config import FASTMATH
    from pipeline.study.reader import load_study

    t0 = time.perf_counter()
    synthesis = load_study(STUDIES / "ov7_synthesis.toml")
    cases = [stress_case(synthesis, a.stress_candidates), montecarlo_case(synthesis, a.candidates)]
    for s in ("ov7_class3",) if a.smoke else SCENES:
        cases += scene_cases(s, a.candidates, a.positions)
    total = time.perf_counter() - t0

    cmd = "python benchmarks/agreement.py " + " ".join(sys.argv[1:] if argv is None else argv)
    md = [
        "# Generated kernels against the frozen plan interpreter",
        "",
        f"`{cmd.strip()}` on {hardware()}; floating-point flags "
        f"{sorted(FASTMATH) if FASTMATH else 'strict IEEE'} (both paths); "
        f"interpreter on {numba.get_num_threads()} numba threads, generated kernels on "
        f"{_jobs()} threads; total {total:.0f} s.",
        "",
        "Acceptance: no candidate OK in the generated kernels that the interpreter failed, "
        "no failure located after the position where the interpreter met it (the generated "
        "kernels watch between positions and locate a failure where it happens: they find "
        "failures the interpreter cannot see and name a fold it met SINGULAR at the dead "
        f"position, by design), and every compared quantity within {THRESHOLD:g} relative "
        "(|generated - interpreter| / max(|interpreter|, tiny), the maximum over the "
        "candidates OK in both paths). "
        "`pos`: positions relative to the mechanism's size (larger side of the "
        "bounding box of every point over the revolution); `d1`, `d2`: analogs relative to their "
        "largest magnitude over the revolution. `newton_iterations`: max relative difference of "
        "the mean iterations per position (sweep) or candidates whose per-position counts differ "
        "(curves): a solver diagnostic that differs by design, not counted. Wall times: the "
        "whole case after a warm-up call (compiled), both paths on the same threads; curves: one "
        "`revolution` call per candidate from Python.",
        "",
        table(cases),
        "",
        "## Notes",
        "",
    ]
    for c in cases:
        md.append(f"* **{c.name}** ({c.kernel}): {'PASS' if c.passed else 'FAIL'}")
        md += [f"  * {n.strip()}" for n in c.notes]
    text = "\n".join(md) + "\n"
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "agreement.md", text)
    print(text)
    print(f"written {out / 'agreement.md'}", file=sys.stderr)
    return 0 if all(c.passed for c in cases) else 1


if __name__ == "__main__":
    sys.exit(main())
