"""One design of a sweep results file: which stored row a user's candidate
(a number, 'knee' or 'reference') is, what its status means, and the design
re-run through the scene path (declared mechanism -> plan) with its curves and,
if asked, its reactions.  Browse, show, report and animate all use it."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from types import SimpleNamespace

import numpy as np

from .fronts import variable_units
from ..kernels import config as kc
from .ranking import ranking
from .refined import design_scene
from ..results.storage import attr_text, candidate_ids, open_results, row_of
from ..base.errors import ResultsError
from ..study.reader import stored_study

STATUS_HELP = {
    kc.OK: "assembles over the whole revolution",
    kc.NO_ASSEMBLY: "cannot be assembled (cosine-law argument outside [-1, 1])",
    kc.NEWTON_MAXITER: "the class III Newton solver did not converge",
    kc.SINGULAR: "passes a toggle (singular) position",
    kc.BRANCH_JUMP: "jumps assembly branch, or the revolution does not close on its start",
    kc.BAD_GEOMETRY: "impossible ternary triangle or non-positive length",
    kc.NOT_EVALUATED: "not evaluated (unfinished sweep)",
    kc.FRICTION_LOCK: "a joint or slide locks by friction, or the friction does not converge",
}


def resolve_candidate(f, cid):
    """The stored row of ``cid``, or the string 'reference': a text is what a
    user types (a candidate number of the sweep, 'knee' or 'reference'); an
    integer is a stored row (the package's own callers).  Rows and candidate
    numbers are the same unless the sweep kept only its feasible candidates
    (store = feasible: ``storage.row_of`` maps them)."""
    n = f["candidates/status"].shape[0]
    if isinstance(cid, (int, np.integer)) and not isinstance(cid, bool):
        if not 0 <= cid < n:
            raise ValueError(f"row {cid} does not exist: the file holds {n} rows")
        return int(cid)
    s = str(cid).strip().lower()
    if s in ("reference", "ref"):
        if "reference" not in f:
            raise ResultsError(f.filename, "has no reference design")
        return "reference"
    if s == "knee":
        k = ranking(f).knee
        if k < 0:
            raise ValueError("there is no knee: no feasible candidate")
        return int(k)
    try:
        i = int(s)
    except ValueError:
        raise ValueError(f"--candidate expects a candidate number, 'knee' or 'reference', "
                         f"got {cid!r}") from None
    return row_of(f, i)


# ----------------------------------------------------------------- re-running a design
@dataclass
class CandidateRun:
    """One design re-run through the scene path (declared mechanism -> plan)."""
    label: str
    index: object               # int or "reference"
    study: object               # the study with the candidate's mechanism
    plan: object
    x: np.ndarray
    names: list
    units: list
    table: object               # Curves at ``n_table`` positions (drawing)
    dense: object               # Curves at the study's positions (with forces if asked)
    theta: np.ndarray           # rocker angle from its first position, rad
    dwell_error: float
    dwell_start: int            # index into dense of the best window's start
    dwell_w: int                # intervals per window
    status: int
    fail_phi: float             # deg: first crank angle where the re-run failed (NaN: none)

    @property
    def scene(self):
        """What ``plots.draw_positions`` reads."""
        return SimpleNamespace(plan=self.plan, study=self.study, dense=self.dense)


def load_study_from_results(f):
    """The study rebuilt from the TOML stored verbatim in the results file."""
    study = stored_study(f.attrs, f.filename)
    if study is None:
        raise ResultsError(f.filename, "has no stored study (attribute study_toml)")
    return study


def rerun_candidate(path, cid, *, forces=True, n_table=12, positions=None) -> CandidateRun:
    """Re-run one candidate (index, 'knee' or 'reference') as a scene: the study
    rebuilt from the file, the design applied, curves at the study's positions
    and, if ``forces``, the reactions at the operating speed."""
    from ..kernels.metrics import dwell_error
    from ..solve.scene import revolution_angles, solve_curves
    from ..study.sweep_spec import apply_design
    with open_results(path, "sweep") as f:
        i = resolve_candidate(f, cid)
        study = load_study_from_results(f)
        p = f["candidates/params"]
        names = [str(attr_text(x)) for x in p.attrs["names"]]
        units = variable_units(p)
        x = f["reference/params"][()] if i == "reference" else p[i]
        number = i if i == "reference" else int(candidate_ids(f)[i])
    if not np.isfinite(x).all():
        raise ValueError(f"candidate {i} was never evaluated (unfinished sweep)")
    spec = study.sweep
    mech = apply_design(study.mechanism, spec, x)
    plan = mech.compile()
    crank = mech.crank
    n = positions or spec.positions
    close = crank.phi0 + crank.rot * 2.0 * math.pi
    dense = solve_curves(plan, revolution_angles(crank, n), kc.ACCELERATIONS, close_at=close)
    table = solve_curves(plan, revolution_angles(crank, n_table), kc.POSITIONS)
    if forces and dense.overall == kc.OK and mech.bodies:
        # with the design's [mechanism.friction], as its scene would have them
        from ..solve.friction import scene_forces_with_friction
        dense.forces = scene_forces_with_friction(
            mech, plan, dense, lambda phis: solve_curves(plan, phis, kc.ACCELERATIONS))
    a, b = (plan.point(q) for q in study.output.rocker)
    v = dense.pos[:, b] - dense.pos[:, a]
    ang = np.arctan2(v[:, 1], v[:, 0])
    theta = np.full(n, np.nan)
    bad = np.flatnonzero((dense.status != kc.OK) | ~np.isfinite(ang))
    k = int(bad[0]) if bad.size else n          # solved positions before the failure
    if k:
        theta[:k] = np.unwrap(ang[:k]) - ang[0]
    fail_phi = float(np.rad2deg(dense.fail_phi)) if dense.overall != kc.OK else math.nan
    if k < n:   # draw no table position beyond the failure of the revolution
        past = crank.rot * (table.phi - dense.phi[k]) >= 0
        table.pos[past] = np.nan
    w = int(round(study.output.dwell_deg * n / 360))
    q = np.empty(n + w + 1, np.int64)
    err, start, _ = dwell_error(np.ascontiguousarray(theta), w, q, q.copy())
    label = "reference design" if i == "reference" else f"candidate #{number}"
    return CandidateRun(label, i, replace(study, mechanism=mech), plan, np.asarray(x, float),
                        names, units, table, dense, theta, float(err), int(start), w,
                        int(dense.overall), fail_phi)


def tolerance_design(source, candidate=None):
    """(study, design mechanism, label, sweep spec or None, origin attrs) of a
    design: a scene's results file or study file, or a sweep's candidate
    (``candidate``: a number, 'knee' or 'reference'; a sweep study file: its
    reference design)."""
    from ..results.storage import attr_text, open_results
    from ..base.errors import ResultsError
    from pathlib import Path
    source = Path(source)
    if source.suffix.lower() == ".toml":
        from ..study.reader import load_study
        study = load_study(source)
        if candidate not in (None, "reference"):
            raise ValueError(f"{source}: --candidate picks a design of a sweep's results "
                             "file; a study file has its own design only")
        label = "reference design" if study.kind == "sweep" else (study.name or "design")
        return study, study.mechanism, label, study.sweep, {"source": str(source)}
    with open_results(source) as f:
        kind = attr_text(f.attrs.get("kind"))
    if kind == "scene":
        if candidate is not None:
            raise ValueError(f"{source} is a scene result: it has one design, no --candidate")
        with open_results(source, "scene") as f:
            study = load_study_from_results(f)
        return study, study.mechanism, study.name or "design", None, {"source": str(source)}
    if kind != "sweep":
        raise ResultsError(source, f"is a {kind} result; give a scene or a sweep result")
    if candidate is None:
        raise ValueError(f"{source} is a sweep: say which design with --candidate ID (a "
                         "number, 'knee' or 'reference')")
    from ..study.sweep_spec import apply_design
    with open_results(source, "sweep") as f:
        i = resolve_candidate(f, candidate)
        study = load_study_from_results(f)
        x = f["reference/params"][()] if i == "reference" else f["candidates/params"][i]
        number = "reference" if i == "reference" else int(candidate_ids(f)[i])
    if not np.isfinite(x).all():
        raise ValueError(f"{source}: candidate {number} was never evaluated (unfinished sweep)")
    mech = apply_design(study.mechanism, study.sweep, x)
    label = "reference design" if number == "reference" else f"candidate #{number}"
    return study, mech, label, study.sweep, {"source": str(source), "candidate": str(number)}


def candidate_scene(source, candidate):
    """A sweep's design (``candidate``: a number, 'knee' or 'reference') as a
    scene study: the sweep's study with the design's mechanism, analysed as a
    scene at the sweep's positions per revolution and operating speed (with
    the force analysis where the mechanism has mass data), so that its peaks,
    pins, dwell and stroke are a scene's.  Returns (scene study, label,
    candidate number or 'reference')."""
    study, mech, label, sweep, origin = tolerance_design(source, candidate)
    if sweep is None:
        raise ValueError(f"{source} is not a sweep: --candidate picks a design of a sweep's "
                         "results file")
    return design_scene(study, mech), label, origin.get("candidate", "reference")
