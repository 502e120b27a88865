"""A sweep's peak metrics refined between the positions, as a scene refines them.

A sweep's peaks (/metrics/peak_reaction, peak_M_bal, ...) are the largest of
the grid's positions: up to a few 1e-3 below the peak between two positions.
The design re-run as a scene (``candidate.design_scene``: the sweep's study
with the design's mechanism, at the sweep's positions and operating speed)
refines each peak between the positions (``solve.peaks.scene_peaks``).
``design_peaks`` gives a design's peak metrics from those refined peaks, by
the same functions in the same order as the scene, so `pipeline show
--candidate`, the scene of an exported design and `pipeline analyze` (which
refines fronts 1-3 and ranks them on these values) print the same numbers.

A refined maximum is never below the grid's (the refinement starts from the
largest sample and keeps only a larger one), so a peak objective's refined
value is the grid's or larger.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..kernels import config as kc
from ..kernels.pareto import nondominated_rank
from ..results.storage import coordinate, put

REFINED_FRONTS = 3            # fronts whose peaks are refined between positions

# a sweep's peak metric -> (the scene's peak quantity it is the extreme of, its items:
# None every item, "working point" the study's working point only); the refined value is
# the largest of those peaks (the smallest for min_transmission_angle)
PEAK_METRICS = {
    "peak_reaction": ("reaction", None),
    "peak_M_bal": ("M_bal", None),
    "peak_acceleration": ("acceleration", "working point"),
    "peak_shaking_force": ("shaking_force", None),
    "peak_shaking_moment": ("shaking_moment", None),
    "transmission_deviation": ("min_transmission_angle", None),
    "min_transmission_angle": ("min_transmission_angle", None),
    "peak_pv": ("bearing_pv", None),
}
# where the refined peak reaction is: its joint (index into the force analysis' joints,
# as the sweep's peak_joint) and crank angle (deg, as the sweep's peak_phi)
LOCATIONS = ("peak_joint", "peak_phi")
# the scene's peak quantities as scene_peaks' filter names them (a transmission angle is
# refined as its deviation from 90 deg)
_SCENE_KEY = {"min_transmission_angle": "transmission_deviation"}


def peak_metrics_of(names) -> tuple:
    """The metrics among ``names`` that are peaks a scene refines."""
    return tuple(m for m in names if m in PEAK_METRICS)


@dataclass
class RefinedPeaks:
    """A design's peak metrics refined between positions (``values``), the
    largest samples of the scene's own grid (``grid``), and the status of its
    scene (a design that does not assemble over the revolution has none)."""
    status: int
    values: dict = field(default_factory=dict)    # metric -> value (with LOCATIONS)
    grid: dict = field(default_factory=dict)      # metric -> the grid's value


def design_peaks(scene_study, metrics) -> RefinedPeaks:
    """The peak metrics ``metrics`` (of PEAK_METRICS) of the scene study
    ``scene_study`` (``candidate.design_scene``), refined between positions
    as its scene refines them (``solve.scene.run_scene``, ``scene_peaks``)."""
    from ..solve.peaks import scene_peaks
    from ..solve.scene import run_scene
    res = run_scene(scene_study)
    if res.dense.overall != kc.OK:
        return RefinedPeaks(int(res.dense.overall))
    wp = scene_study.output.working_point
    wanted = {}
    for m in metrics:
        quantity, items = PEAK_METRICS[m]
        wanted.setdefault(_SCENE_KEY.get(quantity, quantity), set()).add(items)

    def keep(quantity, item):
        which = wanted.get(quantity)
        return which is not None and (None in which or item == wp)
    peaks = scene_peaks(res, keep)
    out = RefinedPeaks(kc.OK)
    for m in metrics:
        quantity, items = PEAK_METRICS[m]
        of = [p for p in peaks if p.quantity == quantity and (items is None or p.item == wp)]
        if not of:          # not computed for this design (no forces, no friction, ...)
            continue
        if quantity == "min_transmission_angle":
            p = min(of, key=lambda q: q.value)
            value, grid = p.value, min(q.grid_value for q in of)
            if m == "transmission_deviation":
                value, grid = 90.0 - value, 90.0 - grid
        else:
            p = max(of, key=lambda q: q.value)
            value, grid = p.value, max(q.grid_value for q in of)
        out.values[m], out.grid[m] = value, grid
        if m == "peak_reaction":
            out.values["peak_joint"] = float(res.dense.forces.joint_names.index(p.item))
            out.values["peak_phi"] = p.phi1
    return out


def refine_designs(study, params, metrics, progress=None, jobs=1) -> tuple[np.ndarray,
                                                                          np.ndarray]:
    """The refined peak metrics of the designs ``params`` (rows of design
    variables) of the sweep study ``study``: (values (n, len(metrics) + 2),
    the last two columns LOCATIONS; NaN where a design's scene fails), status
    (n,) int8 of each design's scene.  ``progress(k)`` after each design (or
    slice of them).  On ``jobs`` processes where there are enough designs to
    pay for their start (``_in_processes``): the same numbers, each design's
    its own."""
    if jobs > 1 and len(params) >= PROCESSES_FROM:
        return _in_processes(study, params, metrics, progress, jobs)
    from ..study.sweep_spec import apply_design
    cols = tuple(metrics) + LOCATIONS
    values = np.full((len(params), len(cols)), math.nan)
    status = np.zeros(len(params), np.int8)
    for k, x in enumerate(params):
        r = design_peaks(design_scene(study, apply_design(study.mechanism, study.sweep, x)),
                         metrics)
        status[k] = r.status
        for j, m in enumerate(cols):
            values[k, j] = r.values.get(m, math.nan)
        if progress is not None:
            progress(k + 1)
    return values, status


# designs from which a refinement runs on several processes: each process starts in
# about a second (the interpreter, the imports, its kernels from numba's cache), a design
# takes 20-40 ms (main job, 2-core AMD EPYC)
PROCESSES_FROM = 128
SLICE = 16              # designs per task (the progress moves by slices)


def _in_processes(study, params, metrics, progress, jobs):
    """``refine_designs`` on ``jobs`` worker processes (``_Worker``: a fresh
    interpreter each, so nothing of the script or notebook that runs this one is
    imported again there, as multiprocessing's spawn would), slices of the
    designs handed out in turn by a thread per worker; the rows back in order.
    An error or an interruption stops every worker at once."""
    import queue
    import threading
    n = len(params)
    values = np.full((n, len(metrics) + len(LOCATIONS)), math.nan)
    status = np.zeros(n, np.int8)
    tasks = queue.SimpleQueue()
    for lo in range(0, n, SLICE):
        tasks.put(lo)
    lock, done, failures, stop = threading.Lock(), [0], [], threading.Event()

    def serve(worker):
        try:
            while not stop.is_set():
                try:
                    lo = tasks.get_nowait()
                except queue.Empty:
                    return
                v, st = worker.refine(params[lo:lo + SLICE])
                with lock:
                    values[lo:lo + len(st)], status[lo:lo + len(st)] = v, st
                    done[0] += len(st)
                    if progress is not None:
                        progress(done[0])
        except BaseException as e:      # (raised by the caller)
            failures.append(e)
            stop.set()

    workers, threads = [], []
    try:
        for _ in range(min(jobs, -(-n // SLICE))):
            workers.append(_Worker(study, metrics))
        threads = [threading.Thread(target=serve, args=(w,), daemon=True) for w in workers]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        stop.set()
        if failures or any(t.is_alive() for t in threads):
            for w in workers:       # (first: a thread may be waiting on its answer)
                w.kill()
            for t in threads:
                t.join(timeout=10.0)
        for w in workers:
            w.close()
    if failures:
        raise failures[0]
    return values, status


class _Worker:
    """A process that refines slices of designs (``_serve``): the study and the
    metrics once, then each slice's rows in, (values, status) out, pickled over
    its pipes; its error output kept for the error it ends with.  It runs the
    package this process runs (``base.processes``)."""

    def __init__(self, study, metrics):
        import pickle
        import subprocess
        import tempfile

        from ..base.processes import module_command
        argv, env = module_command("pipeline.analysis.refined")
        self.err = tempfile.TemporaryFile()
        try:
            self.proc = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                         stderr=self.err, env=env)
        except BaseException:
            self.err.close()
            raise
        try:
            pickle.dump((study, tuple(metrics)), self.proc.stdin)
        except BaseException:
            self.kill()
            self.close()
            raise

    def refine(self, rows):
        import pickle
        try:
            pickle.dump(np.ascontiguousarray(rows), self.proc.stdin)
            self.proc.stdin.flush()
            return pickle.load(self.proc.stdout)
        except Exception:
            self.err.seek(0)
            text = self.err.read().decode(errors="replace").strip().splitlines()
            raise RuntimeError("a process refining the fronts' peaks ended: " + (
                text[-1] if text else "no answer, no error")) from None

    def kill(self):
        if self.proc.poll() is None:
            self.proc.kill()

    def close(self):
        """Its input ended: it exits (else, after 10 s, it is stopped)."""
        import subprocess
        for f in (self.proc.stdin, self.proc.stdout):
            try:
                f.close()
            except OSError:
                pass
        try:
            self.proc.wait(timeout=10.0)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.err.close()


def _serve(stdin, stdout) -> None:
    """A worker's loop (``_Worker``): the study and metrics, then slices of
    designs until its input ends."""
    import pickle
    study, metrics = pickle.load(stdin)
    while True:
        try:
            rows = pickle.load(stdin)
        except EOFError:
            return
        pickle.dump(refine_designs(study, rows, metrics), stdout)
        stdout.flush()


def design_scene(study, mech):
    """The sweep study ``study`` with the design's mechanism ``mech`` as a scene
    study, at the sweep's positions per revolution and operating speed (with
    the force analysis where the mechanism has mass data): what
    ``candidate_scene`` gives and ``analysis.refined`` refines the peaks of."""
    output = replace(study.output, dense_positions=int(study.sweep.positions),
                     analysis="forces" if mech.bodies else "accelerations")
    return replace(study, kind="scene", mechanism=mech, output=output, sweep=None, search=None)


def refine_fronts(data, study, stage=None, jobs=1) -> tuple[np.ndarray, dict]:
    """The objectives the fronts are ranked on, and the refined peaks
    (``analysis.refined``) of the candidates of fronts 1-3.

    Every peak metric the file stores is refined between positions for the
    members of fronts 1-3, and a peak objective takes its refined value there
    (the grid's elsewhere).  Refining raises a peak objective (a refined peak
    is never below the grid's), which may let a candidate not yet refined into
    front 3: the fronts are ranked again and its peaks refined, until every
    member of fronts 1-3 carries refined values.  Fronts 1-3 are then those a
    refinement of every candidate would give (a candidate outside them, once
    refined, would only rise further).  ``stage.set(text)``: progress; ``jobs``:
    processes for the designs (``refine_designs``)."""
    metrics = peak_metrics_of(data.metric_units)
    F = data.F.copy()
    cols = [(j, metrics.index(o)) for j, o in enumerate(data.objectives) if o in metrics]
    out = {"metrics": metrics, "columns": metrics + LOCATIONS, "ranked_on": [
        data.objectives[j] for j, _ in cols], "rows": np.zeros(0, np.int64),
           "values": np.zeros((0, len(metrics) + len(LOCATIONS))), "status": np.zeros(0, np.int8)}
    if not metrics or study is None:
        out["ranked_on"] = []
        return F, out
    rows, values, status = [], [], []
    done = np.zeros(data.n, bool)
    while True:
        rank = nondominated_rank(F, data.feasible)
        todo = np.flatnonzero((rank >= 1) & (rank <= REFINED_FRONTS) & ~done)
        if not todo.size:
            break
        total = done.sum() + todo.size

        def progress(k, base=int(done.sum()), total=int(total)):
            if stage is not None:
                stage.set(f"refining the peaks of fronts 1-{REFINED_FRONTS}: "
                          f"{base + k}/{total} designs")
        v, st = refine_designs(study, data.params[todo], metrics, progress, jobs)
        done[todo] = True
        for j, k in cols:     # a design whose scene fails keeps the grid's value (its status)
            F[todo, j] = np.where(np.isfinite(v[:, k]), v[:, k], F[todo, j])
        rows.append(todo), values.append(v), status.append(st)
    if rows:
        rows = np.concatenate(rows)
        order = np.argsort(rows)
        out.update(rows=rows[order], values=np.concatenate(values)[order],
                   status=np.concatenate(status)[order])
    return F, out


def refined_reference(data, study, refined, ref_obj):
    """The reference design's objectives with its peak objectives refined as
    the fronts' are (the grid's where its scene fails or nothing is refined)."""
    params = data.reference.get("params")
    if not refined["ranked_on"] or params is None or not np.isfinite(params).all() or \
            int(np.ravel(data.reference.get("status", [kc.NOT_EVALUATED]))[0]) != kc.OK:
        return ref_obj
    v, _ = refine_designs(study, np.atleast_2d(params), refined["metrics"])
    refined["reference"] = v[0]
    out = ref_obj.copy()
    for j, o in enumerate(data.objectives):
        if o in refined["metrics"] and np.isfinite(v[0, refined["metrics"].index(o)]):
            out[j] = v[0, refined["metrics"].index(o)]
    return out


def write_refined(f, g, data, r: dict):
    """``/analysis/refined``: the peak metrics of fronts 1-3 refined between
    positions, beside the grid's in /metrics (whose attribute ``refined``
    says where the refined ones are)."""
    rg = g.create_group("refined")
    rg.attrs["long_name"] = (
        f"peak metrics of the candidates of fronts 1-{REFINED_FRONTS} refined between the "
        "grid's positions as the design's scene refines them (pipeline show --candidate); "
        "/metrics keeps the grid's values (the largest of the sweep's positions)")
    rg.attrs["fronts"] = REFINED_FRONTS
    rg.attrs["ranked_on"] = list(r["ranked_on"])
    rows = r["rows"]
    coordinate(rg, "design", np.arange(len(rows)), "1", "refined design")
    put(rg, "index", rows.astype(np.int64), "1", "candidate index (row of /candidates)",
        dims=("design",))
    put(rg, "candidate", np.array([data.id(i) for i in rows], np.int64), "1",
        "candidate number of the sweep", dims=("design",))
    put(rg, "status", r["status"].astype(np.int8), "1",
        "status of the design's scene (0 = OK; elsewhere no refined value: the grid's ranks)",
        dims=("design",))
    for j, m in enumerate(r["columns"]):
        of = "peak_reaction" if m in LOCATIONS else m
        units = _refined_units(data, m)
        what = {"peak_joint": "joint (index) of the refined peak reaction",
                "peak_phi": "crank angle phi1 of the refined peak reaction"}.get(
                    m, f"{m} refined between the grid's positions")
        put(rg, m, r["values"][:, j], units,
            f"{what}, as the design's scene refines it (the grid's: /metrics/{of})",
            dims=("design",))
        if m in r["metrics"] and f"metrics/{m}" in f:
            f[f"metrics/{m}"].attrs["refined"] = (
                f"the largest of the grid's positions; fronts 1-{REFINED_FRONTS} refined "
                f"between them in {g.name}/refined/{m}")
    if "reference" in r:
        coordinate(rg, "column", list(r["columns"]), "1", "refined metric")
        put(rg, "reference", r["reference"], [_refined_units(data, m) for m in r["columns"]],
            "the reference design's peak metrics refined between positions",
            dims=("column",), names=list(r["columns"]))


def _refined_units(data, m) -> str:
    return {"peak_phi": "deg", "peak_joint": "1"}.get(m) or data.metric_units.get(m, "1")


if __name__ == "__main__":      # a worker of ``_in_processes``
    import os
    import sys
    # the answers on a copy of the standard output; anything else written there (a
    # print, a library's note) goes to the error output, which the parent keeps
    answers = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    from ..base.processes import collect_seldom
    collect_seldom()
    try:
        _serve(sys.stdin.buffer, answers)
    except KeyboardInterrupt:   # (the terminal's Ctrl-C reaches the workers too)
        raise SystemExit(130) from None
