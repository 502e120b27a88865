"""Monte-Carlo sweeps: chunks of candidates evaluated by the compiled kernel,
locally on all cores or on a Dask cluster, written to HDF5 chunk by chunk.

Never losing finished work: every finished chunk is first saved atomically
(write to a temporary name, then rename) in a journal folder ``OUT.h5.parts``
next to the results file, then written into the HDF5 file.  The journal is the
source of truth until the run completes: ``--resume`` rebuilds the HDF5 file
from it (so a file damaged by kill -9 in the middle of a write costs nothing)
and computes only the chunks still missing.  On completion the journal is
removed.  Chunks are deterministic (see ``sweep_spec``), so an interrupted and
resumed run gives exactly the same datasets as an uninterrupted one.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import math
import os
import shutil
import threading
import time
import zipfile
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from .kernels import config as kc
from .kernels import sweep as ks
from .files import RunLock, fault_point, refuse_link, replacing
from .limits import CHUNK_WHY, MAX_CHUNK
from .storage import (COMPRESSION, FORMAT, STATUS_ENUM, ResultsError, attach, attr_text, hdf5_image, hdf5_writing,
                      coordinate, put, status_table, units_attr, write_root_attrs)
from .sweep_spec import METRICS, SweepSpec, draw_candidates, draw_checked, parameter_rows

log = logging.getLogger("pipeline")

JOURNAL_VERSION = 3        # 2: chunks carry the draws rejected before solving; 3: 18 metric columns

# kernel metric column of each stored metric, and a conversion to its units
COLUMN = {
    "dwell_error": (ks.M_DWELL, 1.0),
    "stroke": (ks.M_STROKE, 1.0),
    "singularity_margin": (ks.M_MARGIN, 1.0),
    "dwell_start": (ks.M_DWELL_START, 180.0 / math.pi),
    "newton_iterations": (ks.M_NEWTON_MEAN, 1.0),
    "peak_reaction": (ks.M_PEAK_R, 1.0),
    "peak_joint": (ks.M_PEAK_JOINT, 1.0),
    "peak_phi": (ks.M_PEAK_PHI, 180.0 / math.pi),
    "peak_M_bal": (ks.M_PEAK_MBAL, 1.0),
    "peak_acceleration": (ks.M_PEAK_ACC, 1.0),
    "peak_eps": (ks.M_PEAK_EPS, 1.0),
    "min_transmission_angle": (ks.M_MIN_TRANS, 180.0 / math.pi),
    "law_error": (ks.M_LAW_RMS, 1.0),
    "law_error_max": (ks.M_LAW_MAX, 1.0),
    "law_shift": (ks.M_LAW_SHIFT, 180.0 / math.pi),
}
# metrics derived from a column: (column, factor, offset)
DERIVED = {
    "transmission_deviation": (ks.M_MIN_TRANS, -180.0 / math.pi, 90.0),
}


def metric_values(metrics, name):
    """The stored values (in the metric's units) of metric ``name`` from the
    kernels' metric rows ``metrics`` (n, N_METRICS)."""
    if name in DERIVED:
        col, factor, offset = DERIVED[name]
        return metrics[:, col] * factor + offset
    col, factor = COLUMN[name]
    return metrics[:, col] * factor


# ----------------------------------------------------------------- the problem
@dataclass
class SweepProblem:
    """Everything a worker needs to evaluate a chunk: plain arrays and the spec
    (picklable; no study objects, no expressions)."""
    spec: SweepSpec
    plan: object
    phis: np.ndarray
    phi_close: float
    tols: np.ndarray
    rocker: tuple            # (pivot, point) names of the output rocker
    dwell_w: int
    omega1: float
    eps1: float
    loads: np.ndarray
    work_point: int = -1     # point index of the working point (peak_acceleration)
    law: np.ndarray | None = None   # the motion law at the grid's positions (law_error)
    law_best: bool = True    # the law shifted to fit best (align = "best")
    device: str = "cpu"      # cpu | gpu (resolved: never auto)

    @property
    def kernels(self):
        """The mechanism's generated kernels (compiled on first use, then cached)."""
        from .compiler import kernels_for
        return kernels_for(self.plan, self.rocker)

    def settings(self):
        s = self.spec
        return ks.settings(s.stroke_radius, self.dwell_w, s.wants_forces, s.stroke_bounds[0],
                           s.stroke_bounds[1], s.margin_min, self.omega1, self.eps1,
                           want_peaks=s.wants_peaks, work_point=self.work_point,
                           want_transmission=s.wants_transmission,
                           law=self.law if s.wants_law else None, law_best=self.law_best)

    @property
    def device_name(self):
        """'cpu', or the GPU the kernels run on (pipeline.gpu.describe)."""
        if self.device == "cpu":
            return "cpu"
        from .gpu import describe
        return describe()

    def gpu(self):
        """The sweep's CUDA kernels on this process's GPU (made once; not pickled)."""
        g = self.__dict__.get("_gpu")
        if g is None:
            from .gpu import BATCH, GpuSweep
            # a launch no larger than a chunk: device memory follows --chunk-size
            g = self.__dict__["_gpu"] = GpuSweep(self, batch=min(BATCH, self.spec.chunk_size))
        return g

    def __getstate__(self):
        state = dict(self.__dict__)
        state.pop("_gpu", None)
        return state

    def evaluate_rows(self, pars, parallel=True, n_jobs=None):
        """Status and metric rows (N_METRICS) of the parameter rows ``pars``: on
        the GPU (device 'gpu'), else on ``n_jobs`` threads (all cores by
        default), or on the calling thread only (``parallel=False``: a Dask
        task)."""
        if self.device == "gpu":
            return self.gpu().evaluate_rows(pars)
        from .compiler.parallel import run_rows
        n = pars.shape[0]
        status = np.zeros(n, np.int8)
        metrics = np.full((n, ks.N_METRICS), np.nan)
        run_rows(self.kernels.evaluate, np.ascontiguousarray(pars), self.phis, self.phi_close,
                 self.tols, self.settings(), self.loads, status, metrics,
                 n_jobs=n_jobs if parallel else 1)
        return status, metrics

    def evaluate_chunk(self, chunk, parallel=True, n_jobs=None):
        """(chunk, x, status, metrics, rejected draws per triangle)."""
        x, rejected = draw_checked(self.spec, chunk)
        status, metrics = self.evaluate_rows(parameter_rows(self.plan, self.spec, x), parallel,
                                             n_jobs)
        return chunk, x, status, metrics, rejected

    def draw(self, chunk):
        return draw_candidates(self.spec, chunk)


def _device(spec: SweepSpec, distributed) -> str:
    """The device a run takes ('cpu' or 'gpu'), before anything is written: a
    GPU asked for and missing is an error naming what is missing."""
    if distributed:
        if spec.device == "gpu":
            raise ValueError("--device gpu runs the sweep on this machine's GPU; a Dask "
                             "cluster (--scheduler) runs it on the workers' CPUs: choose one")
        return "cpu"
    if spec.device == "cpu":
        return "cpu"
    try:
        from .gpu import choose
    except Exception as e:     # numba.cuda itself does not import
        if spec.device == "auto":
            log.info("device auto: the CPU (numba.cuda does not import: %s)", e)
            return "cpu"
        raise ValueError(f"--device gpu: numba.cuda does not import ({e}); "
                         "pip install -e '.[gpu]' brings numba-cuda") from None
    return choose(spec.device)


def build_problem(study, spec: SweepSpec, tols=None, device="cpu") -> SweepProblem:
    from .forces import sample_loads
    from .scene import revolution_angles
    mech = study.mechanism
    plan = mech.compile()
    crank = mech.crank
    phis = revolution_angles(crank, spec.positions)
    out = study.output
    law = out.motion_law
    return SweepProblem(
        spec=spec, plan=plan, phis=phis, phi_close=crank.phi0 + crank.rot * 2 * math.pi,
        tols=kc.default_tolerances() if tols is None else tols,
        rocker=(out.rocker[0], out.rocker[1]),
        dwell_w=int(round(out.dwell_deg * spec.positions / 360)),
        omega1=crank.omega1, eps1=crank.eps1,
        loads=sample_loads(mech, phis) if mech.loads else np.zeros((len(phis), 0, 3)),
        work_point=plan.point(out.working_point),
        law=None if law is None else law.on_grid(crank, phis),
        law_best=True if law is None else law.best, device=device)


def evaluate_chunk_task(problem, chunk):
    """Dask task: one chunk on one worker thread."""
    return problem.evaluate_chunk(chunk, parallel=False)


# ----------------------------------------------------------------- constraints, objectives
def _bound_columns(spec: SweepSpec):
    """(name, metric, sign, limit) of every [sweep.constraints] bound: g = sign
    (value - limit) <= 0."""
    out = []
    for m, lo, hi in spec.bounds:
        if math.isfinite(lo):
            out.append((f"{m}_min", m, -1.0, lo))
        if math.isfinite(hi):
            out.append((f"{m}_max", m, 1.0, hi))
    return out


def constraint_names(has_margin: bool, spec: SweepSpec | None = None):
    """The stored constraints, in column order (the margin only for class III
    plans, then the study's bounds on metrics)."""
    return (["stroke_min", "stroke_max"] + (["singularity_margin_min"] if has_margin else [])
            + [b[0] for b in (_bound_columns(spec) if spec is not None else ())])


def constraint_units(has_margin: bool, spec: SweepSpec):
    """The units of each stored constraint, as ``constraint_names``."""
    return (["mm", "mm"] + (["1"] if has_margin else [])
            + [METRICS[m][0] for _, m, _, _ in _bound_columns(spec)])


def constraints(spec: SweepSpec, metrics, status: np.ndarray, has_margin: bool):
    """g <= 0 per constraint (columns as ``constraint_names``) and the summed
    violation CV (NaN where the candidate failed), from the kernels' metric
    rows.  A bounded metric that a candidate with status OK lacks (NaN: a
    stage-2 metric of a candidate already outside the stroke or margin limits,
    or a value that could not be computed) adds no violation of its own, but
    the candidate is not feasible (``bounded_finite``)."""
    stroke, margin = metrics[:, ks.M_STROKE], metrics[:, ks.M_MARGIN]
    g = [spec.stroke_bounds[0] - stroke, stroke - spec.stroke_bounds[1]]
    if has_margin:
        g.append(spec.margin_min - margin)
    for _, m, sign, limit in _bound_columns(spec):
        g.append(sign * (metric_values(metrics, m) - limit))
    G = np.stack(g, axis=1)
    cv = np.where(status == kc.OK, np.nansum(np.maximum(G, 0.0), axis=1), np.nan)
    return G, cv


def bounded_finite(spec: SweepSpec, metrics):
    """Rows whose bounded metrics (``spec.bounds``) are all finite."""
    ok = np.ones(metrics.shape[0], bool)
    for m, _, _ in spec.bounds:
        ok &= np.isfinite(metric_values(metrics, m))
    return ok


# ----------------------------------------------------------------- journal
class Journal:
    """Finished chunks saved atomically next to the results file.

    A run that replaces an earlier file (``--overwrite``) writes its new HDF5
    file inside the journal folder (``working_file``), so that the earlier file
    keeps its own name, untouched, until the new one is complete and renamed
    over it (``finish_run``); a run into a new name writes the results file
    itself as it goes (it can be analysed while unfinished)."""

    def __init__(self, out: Path):
        self.dir = out.with_name(out.name + ".parts")
        refuse_link(self.dir, "a run's journal folder")

    def exists(self):
        return (self.dir / "manifest.json").exists()

    def start(self, manifest):
        self.dir.mkdir(parents=True, exist_ok=True)
        self._atomic(self.dir / "manifest.json", json.dumps(manifest, indent=1).encode())

    def manifest(self):
        p = self.dir / "manifest.json"
        try:
            man = json.loads(p.read_text(encoding="utf-8"))
        except (UnicodeDecodeError, ValueError) as e:
            raise ResultsError(p, f"damaged journal manifest ({type(e).__name__}: "
                                  f"{str(e).splitlines()[0][:80]}); the run cannot be resumed: "
                                  "delete the folder and run again") from None
        if not isinstance(man, dict):
            raise ResultsError(p, "damaged journal manifest (not a JSON object); the run "
                                  "cannot be resumed: delete the folder and run again")
        return man

    def working_file(self, out: Path) -> Path:
        """Where this run writes its HDF5 file: ``out``, or, for a run that
        replaces an earlier file, a file in the journal folder."""
        if self.exists() and self.manifest().get("replaces", False):
            return self.dir / "replacement.h5"
        return out

    def _atomic(self, path, data: bytes):
        with replacing(path) as tmp:    # the one atomic writer (files.replacing)
            tmp.write_bytes(data)

    def save(self, chunk, x, status, metrics, rejected, index=None, counts=None):
        """One chunk's rows; with store = feasible only the rows kept, their
        candidate ``index`` and the chunk's ``counts`` (SweepFile.kept)."""
        import io
        buf = io.BytesIO()
        extra = {} if index is None else {"index": index, "counts": counts}
        np.savez(buf, x=x, status=status, metrics=metrics, rejected=rejected, **extra)
        self._atomic(self.dir / f"chunk_{chunk:07d}.npz", buf.getvalue())

    def done(self):
        out = []
        for p in self.dir.glob("chunk_*.npz"):
            out.append(int(p.stem.split("_")[1]))
        return sorted(out)

    def load(self, chunk):
        p = self.dir / f"chunk_{chunk:07d}.npz"
        try:
            with np.load(p) as z:
                rows = z["x"], z["status"], z["metrics"], z["rejected"]
                if "index" in z:
                    rows += (z["index"], z["counts"])
                return rows
        except (OSError, ValueError, KeyError, zipfile.BadZipFile) as e:
            raise ResultsError(p, f"damaged journal chunk ({e}); delete it and run again with "
                                  "--resume: only that chunk is computed again") from None

    def remove(self):
        shutil.rmtree(self.dir, ignore_errors=True)


def manifest_for(study, spec: SweepSpec):
    return {"journal_version": JOURNAL_VERSION, "study_sha256":
            hashlib.sha256(study.text.encode()).hexdigest(), "study_file": str(study.path),
            "candidates": spec.candidates, "chunk_size": spec.chunk_size, "seed": spec.seed,
            "sampler": spec.sampler, "positions": spec.positions, "store": spec.store}


# what a journal written before a manifest key existed meant by it
MANIFEST_DEFAULTS = {"store": "all"}


# ----------------------------------------------------------------- HDF5 file
# the columns of progress/status_counts: every status, then the feasible candidates
COUNTED = tuple(kc.STATUS_NAMES.values()) + ("feasible",)


def _counts(status, feasible):
    """Candidates per status code, then the feasible ones (COUNTED)."""
    return np.append(np.bincount(status.astype(np.int64), minlength=len(kc.STATUS_NAMES))
                     [:len(kc.STATUS_NAMES)], int(feasible.sum()))


class SweepFile:
    """The results file of a sweep, written chunk by chunk."""

    def __init__(self, path: Path, study, problem: SweepProblem):
        self.path = path
        self.study = study
        self.problem = problem
        self.spec = problem.spec

    @property
    def feasible_only(self):
        """store = feasible: the file keeps the feasible candidates' rows only (their
        sweep indices in the ``candidate`` coordinate) and every chunk's counts."""
        return self.spec.store == "feasible"

    def create(self):
        spec, plan = self.spec, self.problem.plan
        n, nv = spec.candidates, len(spec.variables)
        ch = min(spec.chunk_size, n)
        with replacing(self.path) as tmp, hdf5_image(tmp) as f:
            write_root_attrs(f, "sweep", self.study, seed=spec.seed, sampler=spec.sampler,
                             n_candidates=n, chunk_size=spec.chunk_size,
                             positions_per_revolution=spec.positions,
                             objectives=list(spec.objectives), complete=False,
                             store=spec.store)
            # the dimensions, named (netCDF readers: xarray, h5dump's DIMENSION_LIST);
            # with store = feasible the rows grow chunk by chunk
            if self.feasible_only:
                n = 0
                k = f.create_dataset("candidate", (0,), "i8", maxshape=(None,), chunks=(ch,),
                                     **COMPRESSION)
            else:
                k = f.create_dataset("candidate", (n,), "i8", chunks=(ch,), **COMPRESSION)
                step = ch * max(1, (1 << 20) // ch)     # a million at a time, not n at once
                for lo in range(0, n, step):
                    k[lo:min(lo + step, n)] = np.arange(lo, min(lo + step, n))
            k.attrs.update(units="1", long_name="candidate index (its row of the sweep's draws)")
            k.make_scale("candidate")
            gnames = constraint_names(self.has_margin, spec)
            coordinate(f, "variable", [v.name for v in spec.variables], "1", "design variable")
            coordinate(f, "constraint", gnames, "1", "constraint g <= 0")
            coordinate(f, "chunk", np.arange(spec.n_chunks), "1", "chunk of candidates")
            coordinate(f, "triangle", [t.label for t in spec.triangles], "1",
                       "triangle inequality checked before solving")
            c = f.create_group("candidates")
            grow = {"maxshape": (None,)} if self.feasible_only else {}
            grow2 = {"maxshape": (None, None)} if self.feasible_only else {}
            d = c.create_dataset("params", (n, nv), "f8", chunks=(ch, nv), **COMPRESSION,
                                 fillvalue=np.nan, **grow2)
            attach(d, ("candidate", "variable"))
            d.attrs.update(units=units_attr([v.units for v in spec.variables]),
                           long_name="design variables", names=[v.name for v in spec.variables],
                           params=[v.param for v in spec.variables],
                           low=[v.low for v in spec.variables],
                           high=[v.high for v in spec.variables])
            d = c.create_dataset("status", (n,), STATUS_ENUM, chunks=(ch,), **COMPRESSION,
                                 fillvalue=kc.NOT_EVALUATED, **grow)
            d.attrs.update(units="1", long_name="candidate status", codes=status_table())
            attach(d, ("candidate",))
            for name, units, long in (
                    ("fail_phi", "deg", "crank angle phi1 where the candidate failed"),
                    ("cv", "1", "summed constraint violation (0 = feasible, NaN = failed)")):
                d = c.create_dataset(name, (n,), "f8", chunks=(ch,), **COMPRESSION,
                                     fillvalue=np.nan, **grow)
                d.attrs.update(units=units, long_name=long)
                attach(d, ("candidate",))
            d = c.create_dataset("fail_group", (n,), "i2", chunks=(ch,), **COMPRESSION,
                                 fillvalue=-1, **grow)
            d.attrs.update(units="1", long_name="index of the group that failed first (-1: none, "
                           "or the revolution does not close)", groups=list(plan.group_names))
            attach(d, ("candidate",))
            d = c.create_dataset("feasible", (n,), "?", chunks=(ch,), **COMPRESSION, **grow)
            d.attrs.update(units="1", long_name="status OK, constraints met, objectives and "
                                                "bounded metrics finite")
            attach(d, ("candidate",))
            d = c.create_dataset("forces_evaluated", (n,), "?", chunks=(ch,), **COMPRESSION,
                                 **grow)
            d.attrs.update(units="1", long_name="force stage run: forces, peaks or transmission "
                                                "angles, as asked (skipped for candidates "
                                                "already infeasible)")
            attach(d, ("candidate",))
            d = c.create_dataset("constraints", (n, len(gnames)), "f8",
                                 chunks=(ch, len(gnames)), **COMPRESSION, fillvalue=np.nan,
                                 **grow2)
            d.attrs.update(units=units_attr(constraint_units(self.has_margin, spec)),
                           long_name="constraints g <= 0", names=gnames)
            attach(d, ("candidate", "constraint"))
            m = f.create_group("metrics")
            for name in spec.metrics:
                units, long = METRICS[name][:2]
                d = m.create_dataset(name, (n,), "f8", chunks=(ch,), **COMPRESSION,
                                     fillvalue=np.nan, **grow)
                d.attrs.update(units=units, long_name=long)
                attach(d, ("candidate",))
            joints = list(plan.joint_names)
            m.attrs["joint_names"] = joints
            p = f.create_group("progress")
            d = p.create_dataset("chunk_done", (spec.n_chunks,), "?")
            d.attrs.update(units="1", long_name="chunk written")
            attach(d, ("chunk",))
            coordinate(f, "counted", list(COUNTED), "1", "a status, or the feasible candidates")
            d = p.create_dataset("status_counts", (spec.n_chunks, len(COUNTED)), "i8")
            d.attrs.update(units="1", long_name="candidates of each status, and the feasible "
                                                "ones, per chunk", columns=list(COUNTED))
            attach(d, ("chunk", "counted"))
            d = p.create_dataset("rejected", (spec.n_chunks, len(spec.triangles)), "i8")
            d.attrs.update(units="1", long_name="draws redrawn because they broke a triangle "
                                                "inequality (known before solving), per chunk",
                           triangles=[t.label for t in spec.triangles] or [""])
            if spec.triangles:
                attach(d, ("chunk", "triangle"))
            else:
                attach(d, ("chunk",))
            self._reference(f)

    @property
    def has_margin(self):
        return bool(np.isin(self.problem.plan.codes, kc.CLASS3_GROUPS).any())

    def _reference(self, f):
        """The study's own design (the reference mechanism), evaluated the same way."""
        spec, plan = self.spec, self.problem.plan
        x = np.array([[plan.par[plan.param(v.param)] / v.factor for v in spec.variables]])
        st, met = self.problem.evaluate_rows(np.ascontiguousarray(plan.par[None, :]), False)
        g = f.create_group("reference")
        g.attrs["long_name"] = "the study's reference design, evaluated like every candidate"
        coordinate(g, "design", ["reference"], "1", "the reference design")
        put(g, "params", x[0], [v.units for v in spec.variables], "design variables",
            dims=("variable",), names=[v.name for v in spec.variables])
        put(g, "status", st.astype(STATUS_ENUM), "1", "status", dims=("design",),
            codes=status_table())
        for name, col in self._columns(met).items():
            put(g, name, col, METRICS[name][0], METRICS[name][1], dims=("design",))

    def _columns(self, metrics):
        return {name: metric_values(metrics, name) for name in self.spec.metrics}

    def _rows(self, status, metrics):
        """The stored columns of rows (status, metrics): the metrics in their
        units, constraints G, violation cv and feasibility."""
        cols = self._columns(metrics)
        G, cv = constraints(self.spec, metrics, status, self.has_margin)
        objectives = np.stack([cols[o] for o in self.spec.objectives], axis=1)
        feasible = ((status == kc.OK) & (cv == 0) & np.isfinite(objectives).all(axis=1)
                    & bounded_finite(self.spec, metrics))
        return cols, G, cv, feasible

    def kept(self, chunk, x, status, metrics):
        """With store = feasible: (x, status, metrics, index, counts) of the chunk's
        feasible rows, ``index`` their candidate indices and ``counts`` the
        chunk's candidates per status and feasible (COUNTED); else None."""
        if not self.feasible_only:
            return None
        feasible = self._rows(status, metrics)[3]
        lo, _ = self.spec.chunk_bounds(chunk)
        keep = np.flatnonzero(feasible)
        return x[keep], status[keep], metrics[keep], lo + keep, _counts(status, feasible)

    def write_chunk(self, d, chunk, x, status, metrics, rejected, index=None, counts=None):
        """Write one chunk's rows into the datasets ``d`` (``datasets(f)``): all
        its candidates, or (store = feasible) the rows ``index`` kept, appended,
        with the chunk's ``counts``."""
        cols, G, cv, feasible = self._rows(status, metrics)
        if index is None:
            lo, hi = self.spec.chunk_bounds(chunk)
            counts = _counts(status, feasible)
        else:
            lo = d["candidate"].shape[0]
            hi = lo + len(index)
            for name in self.row_names():
                d[name].resize(hi, axis=0)
            d["candidate"][lo:hi] = index
        if len(rejected):
            d["progress/rejected"][chunk] = rejected
        d["progress/status_counts"][chunk] = counts
        d["candidates/params"][lo:hi] = x
        d["candidates/status"][lo:hi] = status
        d["candidates/fail_phi"][lo:hi] = np.rad2deg(metrics[:, ks.M_FAIL_PHI])
        group = metrics[:, ks.M_FAIL_GROUP]
        d["candidates/fail_group"][lo:hi] = np.where(np.isfinite(group), group, -1).astype("i2")
        d["candidates/forces_evaluated"][lo:hi] = metrics[:, ks.M_FORCES_DONE] == 1.0
        for name, col in cols.items():
            d[f"metrics/{name}"][lo:hi] = col
        d["candidates/constraints"][lo:hi] = G
        d["candidates/cv"][lo:hi] = cv
        d["candidates/feasible"][lo:hi] = feasible
        d["progress/chunk_done"][chunk] = True

    def row_names(self):
        """The datasets with a row per stored candidate."""
        return (["candidate", "candidates/params", "candidates/status", "candidates/fail_phi",
                 "candidates/fail_group", "candidates/forces_evaluated",
                 "candidates/constraints", "candidates/cv", "candidates/feasible"]
                + [f"metrics/{m}" for m in self.spec.metrics])

    def sort_rows(self, f):
        """store = feasible: rows in candidate order, whatever order the chunks
        finished in (Dask, a resume); the kept rows are few by design."""
        if not self.feasible_only:
            return
        index = f["candidate"][()]
        if (np.diff(index) > 0).all():
            return
        order = np.argsort(index, kind="stable")
        for name in self.row_names():
            f[name][...] = f[name][()][order]

    def datasets(self, f):
        """The open file's datasets by path, looked up once (a path lookup costs
        more than writing a chunk's column)."""
        names = self.row_names() + ["progress/chunk_done", "progress/rejected",
                                    "progress/status_counts"]
        return {n: f[n] for n in names}


# ----------------------------------------------------------------- running
@dataclass
class SweepOutcome:
    kind: str
    results: Path
    pictures: list
    summary: dict


def check_existing(out: Path, journal: Journal, resume: bool, overwrite: bool, *,
                   journal_diff, same_results, what: str, other: str):
    """Refuse anything that would overwrite or mix results silently (a sweep's
    or a search's): ``journal_diff(manifest)`` lists what differs in an
    interrupted run's journal (or raises), ``same_results(f)`` says whether a
    finished file holds this run's results; ``what`` names the run ("sweep"),
    ``other`` what else a file may hold."""
    if not resume:
        if journal.exists():
            raise ResultsError(journal.dir, "holds an unfinished run; continue it with --resume "
                                            "(or delete the folder to start again)")
        if out.exists() and not overwrite:
            raise ResultsError(out, "already exists; --overwrite replaces it, -o writes "
                                    "another file, --resume continues an interrupted run")
        return
    if journal.exists():
        diff = journal_diff(journal.manifest())
        if diff:
            raise ResultsError(journal.dir, "belongs to another run (different "
                               + ", ".join(diff) + "); refusing to mix results")
        return
    if out.exists():
        try:
            with h5py.File(out, "r") as f:
                ours = f.attrs.get("format") == FORMAT
                same = ours and same_results(f)
                complete = bool(f.attrs.get("complete", False))
        except OSError:
            raise ResultsError(out, "is truncated or not an HDF5 file and there is no journal "
                                    "to rebuild it from; refusing to touch it") from None
        if not ours:
            raise ResultsError(out, "is not a pipeline results file; refusing to write into it")
        if not same:
            raise ResultsError(out, f"holds another study's results ({other}); "
                                    "refusing to write into it")
        if not complete:
            raise ResultsError(out, f"is an unfinished {what} whose journal is gone; "
                                    "run again into a new file")


def _check_existing(out: Path, journal: Journal, study, spec, resume: bool,
                    overwrite: bool = False):
    want = manifest_for(study, spec)
    check_existing(
        out, journal, resume, overwrite,
        journal_diff=lambda man: [k for k in want if k != "study_file"
                                  and man.get(k, MANIFEST_DEFAULTS.get(k)) != want[k]],
        same_results=lambda f: (f.attrs.get("study_toml") == study.text
                                and int(f.attrs.get("n_candidates", -1)) == spec.candidates),
        what="sweep", other="or another candidate count")


def run_sweep(study, out, *, candidates=None, resume=False, overwrite=False, scheduler=None,
              client=None, n_jobs=None, chunk_size=None, progress=True,
              stop_after_chunks=None, device=None, store=None) -> SweepOutcome:
    """Run (or resume) a sweep study into ``out``.  With ``resume`` the
    candidate count and chunk size come from the interrupted run's journal
    (or the finished file) unless given; ``overwrite`` replaces a finished
    file.  ``device`` (cpu | gpu | auto) and ``store`` (all | feasible)
    override the study's [sweep] device and store."""
    from dataclasses import replace
    from .sweep_spec import DEVICES, STORES
    spec: SweepSpec = study.sweep
    for name, value, allowed in (("device", device, DEVICES), ("store", store, STORES)):
        if value is not None and value not in allowed:
            raise ValueError(f"--{name} must be one of {', '.join(allowed)}, got {value!r}")
    spec = replace(spec, device=device or spec.device, store=store or spec.store)
    if resume:
        n, ch = _run_sizes(Path(out))
        candidates = n if candidates is None else candidates
        chunk_size = ch if chunk_size is None else chunk_size
    if candidates is not None:
        if candidates < 1:
            raise ValueError(f"--candidates must be at least 1, got {candidates}")
        spec = spec.with_candidates(candidates)
    if chunk_size is not None:
        if not 1 <= chunk_size <= MAX_CHUNK:
            raise ValueError(f"--chunk-size must be between 1 and {MAX_CHUNK:,} ({CHUNK_WHY}), "
                             f"got {chunk_size:,}")
        spec = replace(spec, chunk_size=chunk_size)
    scheduler = scheduler or spec.scheduler
    out = Path(out)
    with RunLock(out):
        return _run_locked(study, spec, out, resume, overwrite, scheduler, client, n_jobs,
                           progress, stop_after_chunks)


def _run_sizes(out: Path):
    """(candidates, chunk size) of the run that wrote ``out``: from its journal
    if it was interrupted, else from the file; (None, None) if neither says."""
    journal = Journal(out)
    if journal.exists():
        man = journal.manifest()
        return man.get("candidates"), man.get("chunk_size")
    if out.exists():
        try:
            with h5py.File(out, "r") as f:
                n, ch = f.attrs.get("n_candidates"), f.attrs.get("chunk_size")
                return (int(n) if n is not None else None), (int(ch) if ch is not None else None)
        except OSError:
            pass
    return None, None


def _run_locked(study, spec, out, resume, overwrite, scheduler, client, n_jobs, progress,
                stop_after_chunks):
    journal = Journal(out)
    _check_existing(out, journal, study, spec, resume, overwrite)
    done = aside_or_done(out, journal, resume, overwrite, "chunk", summarize)
    if done is not None:
        return done

    problem = build_problem(study, spec, device=_device(spec, scheduler or client))
    sf = SweepFile(out, study, problem)
    fresh = not journal.exists()
    own = scheduler is not None and client is None
    if own:
        client = _connect(scheduler)     # before anything is written
    try:
        with nothing_left_before_first(out, journal, fresh, "chunk"):
            if fresh:
                journal.start(dict(manifest_for(study, spec), replaces=out.exists()))
            sf.path = journal.working_file(out)
            return _run_chunks(study, spec, out, journal, problem, sf, client, n_jobs,
                               progress, stop_after_chunks)
    finally:
        if own:
            client.close()


@contextlib.contextmanager
def compile_notice():
    """Around the first evaluation of a run (the reference design), which compiles
    a new mechanism's kernels: a notice if it takes more than a second, and how
    long it took (the list it yields holds the seconds afterwards)."""
    t = time.perf_counter()
    took = [0.0]
    notice = threading.Timer(1.0, log.info, ("compiling the kernels of this mechanism "
                                             "(its first run only; about 15 s)...",))
    notice.daemon = True
    notice.start()
    try:
        yield took
    finally:
        notice.cancel()
    took[0] = time.perf_counter() - t
    if took[0] > 1.0:
        log.info("kernels ready after %.1f s", took[0])


def aside_or_done(out: Path, journal: Journal, resume: bool, overwrite: bool, unit: str,
                  summary):
    """Before a run (sweep or search) writes: with --overwrite the finished file
    stays as it is, under its name, until the new run is complete (the new one
    is written in the journal folder, ``Journal.working_file``); a --resume of
    a finished run returns its outcome (``summary(out)``), else None."""
    if overwrite and out.exists() and not resume:
        log.info("replacing %s when the new run is complete (until then it stays as it is)",
                 out)
    if resume and not journal.exists() and out.exists():
        log.info("%s is already complete; nothing to resume", out)
        return SweepOutcome("sweep", out, [], summary(out))
    return None


@contextlib.contextmanager
def nothing_left_before_first(out: Path, journal: Journal, fresh: bool, unit: str):
    """A fresh run (sweep or search) that fails or is stopped before its first
    ``unit`` is saved leaves nothing behind; a file it was to replace
    (``--overwrite``) was never touched."""
    replaces = out.exists()
    try:
        yield
    except BaseException as e:
        if fresh and not journal.done():
            journal.remove()
            if not replaces:
                out.unlink(missing_ok=True)
            if isinstance(e, KeyboardInterrupt):
                raise SweepInterrupted(f"{out}: interrupted before the first {unit} finished; "
                                       "nothing was written") from None
        raise


def _run_chunks(study, spec, out, journal, problem, sf, client, n_jobs, progress,
                stop_after_chunks):
    # the file, fresh or rebuilt from the journal below; its reference design is the
    # first evaluation, which compiles a new mechanism's kernels (once, then cached)
    with compile_notice() as prep:
        sf.create()
    finished = set(journal.done())
    t0 = time.perf_counter()
    work = sf.path
    with hdf5_writing(work, expendable=False) as f:
        d = sf.datasets(f)
        for c in sorted(finished):
            sf.write_chunk(d, c, *journal.load(c))    # kept rows and counts, if any
        f.flush()
    todo = [c for c in range(spec.n_chunks) if c not in finished]
    if finished:
        log.info("resuming: %d of %d chunks already done", len(finished), spec.n_chunks)
    bar = _progress(spec, len(finished), progress)
    computed = 0
    try:
        with hdf5_writing(work, expendable=False) as f:
            d = sf.datasets(f)
            flushed = time.monotonic()
            for c, x, status, metrics, rejected in _chunks(problem, todo, client, n_jobs):
                computed += len(status)
                bar.update(len(status))
                kept = sf.kept(c, x, status, metrics)     # store = feasible: those rows only
                if kept is not None:
                    x, status, metrics, index, counts = kept
                    journal.save(c, x, status, metrics, rejected, index, counts)
                    sf.write_chunk(d, c, x, status, metrics, rejected, index, counts)
                else:
                    journal.save(c, x, status, metrics, rejected)   # the source of truth
                    sf.write_chunk(d, c, x, status, metrics, rejected)
                fault_point("chunk-written", out)
                if time.monotonic() - flushed > 1.0:    # the HDF5 file: once a second
                    f.flush()
                    flushed = time.monotonic()
                if stop_after_chunks is not None and computed >= stop_after_chunks * spec.chunk_size:
                    raise KeyboardInterrupt  # test hook: an interruption at a chunk boundary
    except KeyboardInterrupt:
        bar.close()
        done = len(journal.done())
        raise SweepInterrupted(f"{out}: interrupted with {done} of {spec.n_chunks} chunks "
                               "saved; run again with --resume to continue") from None
    bar.close()
    with hdf5_writing(work, expendable=False) as f:
        sf.sort_rows(f)
    return finish_run(out, journal, client, time.perf_counter() - t0, prep[0], computed,
                      summarize, "candidates", device=problem.device_name)


def finish_run(out: Path, journal: Journal, client, wall: float, compile_s: float,
               computed: int, summary, unit: str, device: str = "cpu") -> SweepOutcome:
    """A run (sweep or search) has written everything: the file is marked
    complete (a replacement is renamed over the file it replaces only now), the
    journal goes, and its outcome says the wall time, the compile time apart
    and the throughput (``summary(out)``: the file's own summary; ``unit``:
    what was computed)."""
    work = journal.working_file(out)
    with hdf5_writing(work, expendable=False) as f:
        f.attrs["complete"] = True
        f.attrs["wall_time_s"] = wall
        f.attrs["engine"] = "dask" if client is not None else "local"
        f.attrs["device"] = device
    if work != out:
        with replacing(out) as tmp:     # the earlier file is replaced whole, now
            os.replace(work, tmp)
    journal.remove()
    res = summary(out)
    res["wall_time"] = f"{wall:.1f} s"
    if compile_s > 1.0:
        res["compile_time"] = f"{compile_s:.1f} s (not in the wall time; cached from now on)"
    if computed:
        res["throughput"] = f"{computed / wall:,.0f} {unit}/s"
    if device != "cpu":
        res["device"] = device
    return SweepOutcome("sweep", out, [], res)


class SweepInterrupted(KeyboardInterrupt):
    """Raised after an interruption, once everything finished is safe."""


def _progress(spec, done, enabled):
    from tqdm import tqdm
    return tqdm(total=spec.candidates, initial=done * spec.chunk_size if done else 0,
                unit="cand", unit_scale=True, disable=not enabled, smoothing=0.1,
                desc="sweep", dynamic_ncols=True)


def _chunks(problem, todo, client, n_jobs):
    """Yield (chunk, x, status, metrics) as chunks finish."""
    if client is not None:
        yield from _dask_chunks(problem, todo, client)
        return
    if n_jobs is not None and n_jobs < 1:
        raise ValueError(f"--jobs must be at least 1, got {n_jobs}")
    # the next chunk is drawn and evaluated while the caller journals and writes
    # this one (the kernels run on the worker threads, HDF5 on this one)
    from concurrent.futures import ThreadPoolExecutor
    with ThreadPoolExecutor(1, thread_name_prefix="pipeline-chunks") as ahead:
        pending = None
        for c in todo:
            nxt = ahead.submit(problem.evaluate_chunk, c, True, n_jobs)
            if pending is not None:
                yield pending.result()
            pending = nxt
        if pending is not None:
            yield pending.result()


CONNECT_TIMEOUT = "20s"     # how long to wait for a Dask scheduler to answer


def _connect(scheduler):
    """A client of the Dask scheduler at ``scheduler``; dask is imported only here."""
    try:
        from dask.distributed import Client
    except ImportError:  # pragma: no cover - depends on the installation
        raise ValueError("--scheduler needs dask: pip install 'pipeline[dask]'") from None
    try:
        return Client(scheduler, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError) as e:
        raise ValueError(f"cannot reach the Dask scheduler {scheduler}: {e}") from None


def _dask_chunks(problem, todo, client):
    """The same kernels on the workers of a Dask ``client``."""
    from dask.distributed import as_completed
    remote = client.scatter(problem, broadcast=True)
    futures = [client.submit(evaluate_chunk_task, remote, c, pure=False) for c in todo]
    for fut in as_completed(futures):
        yield fut.result()


def status_counts(f) -> dict:
    """Candidates per status, OK-but-infeasible and feasible: count and percent."""
    if attr_text(f.attrs.get("store", "all")) == "feasible":
        # only the feasible rows are stored: the counts of every chunk written
        done = f["progress/chunk_done"][()]
        c = f["progress/status_counts"][()][done].sum(axis=0)
        by_status, n_feasible = c[:-1], int(c[-1])
    else:
        st = f["candidates/status"][()].astype(np.int64)
        bad = (st < 0) | (st >= len(kc.STATUS_NAMES))
        if bad.any():
            raise ResultsError(f.filename, f"damaged results file: {int(bad.sum()):,} "
                                           "candidates have a status code outside "
                                           f"0..{len(kc.STATUS_NAMES) - 1}")
        by_status = np.bincount(st, minlength=len(kc.STATUS_NAMES))
        n_feasible = int(f["candidates/feasible"][()].sum())
    n = int(by_status.sum())
    out = {}
    for code, name in kc.STATUS_NAMES.items():
        k = int(by_status[code])
        if k:
            out[name] = {"count": k, "percent": round(100.0 * k / max(n, 1), 2)}
    ok_infeasible = int(by_status[kc.OK]) - n_feasible
    out["OK but constraints violated"] = {"count": ok_infeasible,
                                       "percent": round(100.0 * ok_infeasible / max(n, 1), 2)}
    out["feasible"] = {"count": n_feasible, "percent": round(100.0 * n_feasible / n, 2)
                       if n else 0.0}
    if "progress/rejected" in f and f["progress/rejected"].size:
        k = int(f["progress/rejected"][()].sum())
        if k:   # draws that could not be built, replaced before solving (not candidates)
            out["redrawn before solving"] = {  # percent of all draws, not of the candidates
                "count": k, "percent": round(100.0 * k / max(n + k, 1), 2)}
    return out


def summarize(out) -> dict:
    """Counts by status, feasible fraction, best objective values."""
    with h5py.File(out, "r") as f:
        feas = f["candidates/feasible"][()]
        counts = status_counts(f)
        s = {"candidates": sum(v["count"] for k, v in counts.items()
                               if k in kc.STATUS_NAMES.values())}
        if attr_text(f.attrs.get("store", "all")) == "feasible":
            s["stored"] = f"the feasible candidates only ({len(feas)} rows; store = feasible)"
        for name in kc.STATUS_NAMES.values():
            if name in counts:
                s[f"status {name}"] = f"{counts[name]['count']} ({counts[name]['percent']:.1f}%)"
        s["feasible"] = f"{counts['feasible']['count']} ({counts['feasible']['percent']:.1f}%)"
        def unit(name):
            u = attr_text(f[f"metrics/{name}"].attrs.get("units", ""))
            return "" if u in ("", "1") else f" {u}"
        for o in f.attrs["objectives"]:
            v = f[f"metrics/{o}"][()][feas]
            if v.size:
                s[f"best {o}"] = f"{v.min():.4g}{unit(o)}"
        if "progress/rejected" in f and f["progress/rejected"].size:
            rej = f["progress/rejected"][()].sum(axis=0)
            labels = f["progress/rejected"].attrs["triangles"]
            if rej.sum():
                s["redrawn before solving"] = "; ".join(
                    f"{int(k):,} draws broke the {attr_text(lab)}"
                    for k, lab in zip(rej, labels) if k)
        ref = f["reference"]
        s["reference design"] = ", ".join(
            f"{o} {ref[o][()][0]:.4g}{unit(o)}" for o in f.attrs["objectives"] if o in ref)
    return s
