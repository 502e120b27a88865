"""One design's cycle for the report's explorer, as data the page draws
(templates/explorer.js): the mechanism at its table positions with the paths of
its points, the output rocker's angle and the working point's displacement
against the crank angle, and |R| of every joint against the crank angle with
its peak.  Each design is re-run as a scene (``analysis.candidate.
rerun_candidate``, reactions included); no picture is rendered here, which is
what keeps dozens of designs within a second or two."""

from __future__ import annotations

import logging
import math
import time

import numpy as np

from ..analysis.candidate import STATUS_HELP, rerun_candidate
from ..base.progress import on_terminal, shown
from ..kernels import config as kc
from .page import json_number, json_numbers
from .plots import joint_descriptions

log = logging.getLogger("pipeline")

CURVE_POINTS = 180      # at most this many positions per curve (the peaks use them all)


def _every(n):
    return max(1, math.ceil(n / CURVE_POINTS))


def dwell_spans(phi, start, w) -> list:
    """The best dwell window (``w`` intervals from position ``start``) as spans
    of the crank angles ``phi`` (deg, one revolution in the crank's sense): one
    span, or two where the window runs past the end of the revolution."""
    n = len(phi)
    step = (phi[1] - phi[0]) if n > 1 else 0.0
    a, b = phi[start], phi[start] + step * w
    end = phi[0] + step * n                     # the revolution closes here
    if (b - end) * step <= 0:
        return [[json_number(a), json_number(b)]]
    return [[json_number(a), json_number(end)],
            [json_number(phi[0]), json_number(phi[0] + (b - end))]]


def design_cycle(run) -> dict:
    """The drawing, motion and reactions of one re-run design (a CandidateRun)."""
    from .plots import _links_to_draw
    plan, study = run.plan, run.study
    mech = study.mechanism
    nv = plan.n_visible
    table, dense = run.table, run.dense
    step = _every(dense.phi.shape[0])
    phi = np.rad2deg(dense.phi)
    iwp = plan.point(study.output.working_point)
    fixed = sorted({plan.point(p) for p in mech.fixed})
    moving = [i for i in range(nv) if i not in fixed]
    mechanism = {
        "names": list(plan.point_names[:nv]),
        "fixed": fixed,
        "segments": [[int(a), int(b)] for a, b in _links_to_draw(plan, study)],
        "phi": json_numbers(np.rad2deg(table.phi)),
        "x": [json_numbers(table.pos[k, :nv, 0]) for k in range(table.pos.shape[0])],
        "y": [json_numbers(table.pos[k, :nv, 1]) for k in range(table.pos.shape[0])],
        "paths": {str(i): [json_numbers(dense.pos[::step, i, 0]),
                           json_numbers(dense.pos[::step, i, 1])] for i in moving},
        "working_point": int(iwp),
    }
    disp = dense.pos[:, iwp] - dense.pos[0, iwp]
    motion = {"phi": json_numbers(phi[::step]),
              "theta": json_numbers(np.rad2deg(run.theta[::step])),
              "dx": json_numbers(disp[::step, 0]), "dy": json_numbers(disp[::step, 1]),
              "working_point": str(study.output.working_point),
              "rocker": "-".join(str(p) for p in study.output.rocker),
              "reversed": bool(mech.crank.rot < 0), "dwell": None}
    n = phi.shape[0]
    if run.dwell_start >= 0 and np.isfinite(run.theta).all() and n > 1:
        motion["dwell"] = {"deg": json_number(study.output.dwell_deg),
                           "spans": dwell_spans(phi, run.dwell_start, run.dwell_w)}
    out = {"label": run.label, "status": kc.STATUS_NAMES.get(run.status, str(run.status)),
           "why": STATUS_HELP.get(run.status, ""), "mechanism": mechanism, "motion": motion,
           "reactions": None}
    fr = getattr(dense, "forces", None)
    if fr is not None:
        mag = fr.magnitude
        peak = [json_number(np.nanmax(mag[:, j])) if np.isfinite(mag[:, j]).any() else None
                for j in range(mag.shape[1])]
        out["reactions"] = {"phi": motion["phi"], "joints": list(fr.joint_names),
                            "where": joint_descriptions(plan),
                            "R": [json_numbers(mag[::step, j]) for j in range(mag.shape[1])],
                            "peak": peak}
    return out


def _steps(items, desc):
    """``items`` with progress: a bar on a terminal, else nothing here (the
    caller logs a plain line when done)."""
    if on_terminal() and shown() and len(items) > 1:
        from tqdm import tqdm
        return tqdm(items, desc=desc, unit="design", leave=False, dynamic_ncols=True)
    return items


def design_key(data, row) -> str:
    """A design's name as the commands (``--candidate``) and the page take it:
    its candidate number as text, or 'reference'."""
    return "reference" if row == "reference" else str(data.id(row))


def design_cycles(path, rows, data, reference=True) -> dict:
    """{candidate number (text) or 'reference': its cycle} of the stored ``rows``
    (and the reference design): each re-run with its reactions.  A design the
    scene path cannot re-run is left out with a warning."""
    t0 = time.perf_counter()
    out = {}
    todo = [int(r) for r in rows] + (["reference"] if reference else [])
    if todo:
        log.info("report: re-running %d designs for the explorer (drawing, motion, "
                 "reactions)", len(todo))
    for r in _steps(todo, "explorer designs"):
        key = design_key(data, r)
        try:
            out[key] = design_cycle(rerun_candidate(path, r, forces=True))
        except Exception as e:   # a design the scene path cannot redo: say so, go on
            log.warning("report: candidate %s not re-run for the explorer (%s)", key, e)
    if todo:
        log.info("report: %d designs re-run in %.1f s", len(out), time.perf_counter() - t0)
    return out
