"""The results file of a sweep, written chunk by chunk (``SweepFile``), and its
summary read back (``status_counts``, ``summarize``)."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np

from ..base.files import replacing
from ..base.units import unit_text
from ..kernels import config as kc
from ..kernels import sweep as ks
from ..study.objectives import Feasibility, constraint_names, constraint_units, constraints_text
from ..model.metric_catalogue import METRICS, metric_values
from .storage import (COMPRESSION, STATUS_ENUM, attach, attr_text, coordinate, hdf5_image,
                      link_coordinates, put, room_for, status_table, units_attr, write_root_attrs,
                      direct_chunk_rows, write_rows)
from ..base.errors import ResultsError

# rows of an HDF5 chunk of a sweep that stores its feasible candidates only: the rows
# arrive appended, a chunk filled by several sweep chunks; HDF5 rewrote a chunk of 10^6
# rows (a GPU's) whole at each append
KEPT_CHUNK_ROWS = 16_384


# the columns of progress/status_counts: every status, then the feasible candidates
COUNTED = tuple(kc.STATUS_NAMES.values()) + ("feasible",)


def full_counts(counts):
    """A chunk's counts (COUNTED) in today's columns: a journal or a file
    written before a status was added (FRICTION_LOCK, the 8th) has fewer
    status columns before its feasible one; the statuses it did not know it
    never gave, so they count 0."""
    counts = np.asarray(counts, np.int64)
    missing = len(COUNTED) - counts.shape[-1]
    if missing < 0:
        raise ValueError(f"{counts.shape[-1]} counts where there are {len(COUNTED)} columns "
                         f"({', '.join(COUNTED)})")
    if not missing:
        return counts
    zeros = np.zeros(counts.shape[:-1] + (missing,), np.int64)
    return np.concatenate([counts[..., :-1], zeros, counts[..., -1:]], axis=-1)


def counted(status, feasible):
    """Candidates per status code, then the feasible ones (COUNTED)."""
    return np.append(np.bincount(status.astype(np.int64), minlength=len(kc.STATUS_NAMES))
                     [:len(kc.STATUS_NAMES)], int(feasible.sum()))


class SweepFile:
    """The results file of a sweep, written chunk by chunk."""

    def __init__(self, path: Path, study, problem):
        self.path = path
        self.study = study
        self.problem = problem
        self.spec = problem.spec
        self._direct = {}

    @property
    def feasible_only(self):
        """store = feasible: the file keeps the feasible candidates' rows only (their
        sweep indices in the ``candidate`` coordinate) and every chunk's counts."""
        return self.spec.store == "feasible"

    def create(self):
        spec, plan = self.spec, self.problem.plan
        n, nv = spec.candidates, len(spec.variables)
        ch = min(spec.chunk_size, n)
        if self.feasible_only:     # rows appended: chunks that fill (a GPU's sweep chunk is
            ch = min(ch, KEPT_CHUNK_ROWS)   # 10^6 candidates; its kept rows ~10^5)
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
            # each group holds its coordinates (links to the root's scales), so that
            # xarray.open_dataset(path, group="candidates")["params"].sel(variable="L12")
            link_coordinates(c, ("candidate", "variable", "constraint"))
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
                d.attrs.update(units=units_attr(units), long_name=long)
                attach(d, ("candidate",))
            d = c.create_dataset("fail_group", (n,), "i2", chunks=(ch,), **COMPRESSION,
                                 fillvalue=-1, **grow)
            groups, why = list(plan.group_names), ""
            if getattr(self.problem, "friction", None) is not None:
                groups += list(self.problem.friction.names)
                why = "; a FRICTION_LOCK's: the joint or slide, after the groups"
            d.attrs.update(units="1", long_name="index of the group that failed first (-1: none, "
                           f"or the revolution does not close{why})", groups=groups)
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
            link_coordinates(m, ("candidate",))
            for name in spec.metrics:
                units, long = METRICS[name][:2]
                d = m.create_dataset(name, (n,), "f8", chunks=(ch,), **COMPRESSION,
                                     fillvalue=np.nan, **grow)
                d.attrs.update(units=units_attr(units), long_name=long)
                attach(d, ("candidate",))
            joints = list(plan.joint_names)
            m.attrs["joint_names"] = joints
            p = f.create_group("progress")
            d = p.create_dataset("chunk_done", (spec.n_chunks,), "?")
            d.attrs.update(units="1", long_name="chunk written")
            attach(d, ("chunk",))
            coordinate(f, "counted", list(COUNTED), "1", "a status, or the feasible candidates")
            link_coordinates(p, ("chunk", "counted") + (("triangle",) if spec.triangles else ()))
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
        return self.problem.has_margin

    def _reference(self, f):
        """The study's own design (the reference mechanism), evaluated the same way."""
        spec, plan = self.spec, self.problem.plan
        x = np.array([[plan.par[plan.param(v.param)] / v.factor for v in spec.variables]])
        st, met = self.problem.evaluate_rows(np.ascontiguousarray(plan.par[None, :]), False)
        g = f.create_group("reference")
        g.attrs["long_name"] = "the study's reference design, evaluated like every candidate"
        coordinate(g, "design", ["reference"], "1", "the reference design")
        link_coordinates(g, ("variable",))
        put(g, "params", x[0], [v.units for v in spec.variables], "design variables",
            dims=("variable",), names=[v.name for v in spec.variables])
        put(g, "status", st.astype(STATUS_ENUM), "1", "status", dims=("design",),
            codes=status_table())
        for name, col in self._columns(met).items():
            put(g, name, col, METRICS[name][0], METRICS[name][1], dims=("design",))

    def _columns(self, metrics):
        return {name: metric_values(metrics, name) for name in self.spec.metrics}

    def write_chunk(self, d, chunk, x, status, metrics, judged: Feasibility, rejected,
                    index=None, counts=None):
        """Write one chunk's rows into the datasets ``d`` (``datasets(f)``): all
        its candidates, or (store = feasible) the rows ``index`` kept, appended,
        with the chunk's ``counts``; ``judged``: the rows' constraints and
        feasibility (``study.objectives.feasibility``)."""
        if index is None:
            self.write_chunks(d, range(chunk, chunk + 1), x, status, metrics, judged,
                              [rejected])
            return
        room_for(self.path, 2 * (x.nbytes + metrics.nbytes) + status.nbytes)
        lo = d["candidate"].shape[0]
        hi = lo + len(index)
        for name in self.row_names():
            d[name].resize(hi, axis=0)
        d["candidate"][lo:hi] = index
        self._write_rows(d, lo, x, status, metrics, judged)
        if len(rejected):
            d["progress/rejected"][chunk] = rejected
        d["progress/status_counts"][chunk] = full_counts(counts)  # (an older journal's, too)
        d["progress/chunk_done"][chunk] = True

    def write_chunks(self, d, chunks, x, status, metrics, judged: Feasibility, rejected):
        """Write the consecutive chunks ``chunks`` (a range) at once: their rows
        one after the other in ``x``, ``status``, ``metrics`` and ``judged``,
        and one row of ``rejected`` per chunk (every candidate stored)."""
        room_for(self.path, 2 * (x.nbytes + metrics.nbytes) + status.nbytes)
        bounds = [self.spec.chunk_bounds(c) for c in chunks]
        lo = bounds[0][0]
        self._write_rows(d, lo, x, status, metrics, judged)
        feasible = judged.feasible
        first, end = chunks[0], chunks[-1] + 1
        rejected = np.asarray(rejected, np.int64).reshape(len(bounds), -1)
        if rejected.shape[1]:
            d["progress/rejected"][first:end] = rejected
        d["progress/status_counts"][first:end] = np.stack(
            [counted(status[a - lo:b - lo], feasible[a - lo:b - lo]) for a, b in bounds])
        d["progress/chunk_done"][first:end] = True

    def _write_rows(self, d, lo, x, status, metrics, judged: Feasibility):
        """Rows from ``lo`` on of every per-candidate dataset (``storage.write_rows``:
        whole chunks filtered here)."""
        group = metrics[:, ks.M_FAIL_GROUP]
        columns = {"candidates/params": x, "candidates/status": status,
                   "candidates/fail_phi": np.rad2deg(metrics[:, ks.M_FAIL_PHI]),
                   "candidates/fail_group": np.where(np.isfinite(group), group, -1).astype("i2"),
                   "candidates/forces_evaluated": metrics[:, ks.M_FORCES_DONE] == 1.0}
        columns.update({f"metrics/{name}": col for name, col in self._columns(metrics).items()})
        columns.update({"candidates/constraints": judged.g, "candidates/cv": judged.cv,
                        "candidates/feasible": judged.feasible})
        for name, values in columns.items():
            if name not in self._direct:        # (datasets() forgets them with the file)
                self._direct[name] = direct_chunk_rows(d[name])
            write_rows(d[name], lo, values, self._direct[name])

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
        room_for(self.path, sum(f[name].nbytes for name in self.row_names()))
        order = np.argsort(index, kind="stable")
        for name in self.row_names():
            f[name][...] = f[name][()][order]

    def datasets(self, f):
        """The open file's datasets by path, looked up once (a path lookup costs
        more than writing a chunk's column)."""
        names = self.row_names() + ["progress/chunk_done", "progress/rejected",
                                    "progress/status_counts"]
        self._direct = {}       # each dataset's rows per chunk written here (write_rows)
        return {n: f[n] for n in names}


def _stored_counts(d):
    """progress/status_counts in today's columns (COUNTED), by the names of its
    ``columns``: a file written before a status was added has its count as 0."""
    c = d[()].astype(np.int64)
    names = [str(attr_text(x)) for x in d.attrs.get("columns", ())]
    if len(names) != c.shape[1]:
        return full_counts(c)
    unknown = [x for x in names if x not in COUNTED]
    if unknown:
        raise ResultsError(d.file.filename, f"progress/status_counts counts {unknown[0]!r}, "
                                            "which this version does not know; a newer "
                                            "version of the package wrote it")
    out = np.zeros((c.shape[0], len(COUNTED)), np.int64)
    out[:, [COUNTED.index(x) for x in names]] = c
    return out


def status_counts(f) -> dict:
    """Candidates per status, OK-but-infeasible and feasible: count and percent."""
    if attr_text(f.attrs.get("store", "all")) == "feasible":
        # only the feasible rows are stored: the counts of every chunk written
        done = f["progress/chunk_done"][()]
        c = _stored_counts(f["progress/status_counts"])[done].sum(axis=0)
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
        said = _constraints_said(f, out)
        if said:
            s["constraints"] = said
        if _has_friction(f, out):
            s["friction"] = ("[mechanism.friction]: the force peaks with friction, on the "
                             "careful path (Newton at every position of each candidate of "
                             "the force stage, not in lanes: benchmarks/bench_friction.py)")
        def unit(name):
            u = unit_text(attr_text(f[f"metrics/{name}"].attrs.get("units", "")))
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


def _has_friction(f, path) -> bool:
    """Whether the stored study's mechanism has [mechanism.friction]."""
    from ..study.reader import stored_study
    try:
        study = stored_study(f.attrs, path)
    except ValueError:
        return False
    return study is not None and study.mechanism.friction is not None


def _constraints_said(f, path) -> str:
    """The constraints the stored study states, in words ("" where the file
    keeps no study this version reads)."""
    from ..study.reader import stored_study
    try:
        study = stored_study(f.attrs, path)
    except ValueError:
        return ""
    if study is None or study.sweep is None:
        return ""
    names = [attr_text(n) for n in f["candidates/constraints"].attrs.get("names", [])]
    return constraints_text(study.sweep, "singularity_margin_min" in names)
