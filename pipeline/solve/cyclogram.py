"""The machine's cyclogram of one design (DOMAIN.md section 9): the design's
own phases from its output motion (dwell, forward, back), the required cycle
of the organ its output drives and of the machine's other organs (the study's
[cycle] and [output.motion_law]), and the phase error at each boundary of the
output's phases, actual minus required.

Crank travel tau (deg) = rot * (phi1 - phi0), which grows as the crank turns,
is the design's clock: the first dense position is tau = 0.  The machine's
cycle angle psi is placed on it as psi = tau - turn: with ``align = "best"``
(the default) ``turn`` puts the required dwell's start where the design's
dwell starts, as the crank's mounting phase would align them (so the error at
the dwell's start is 0 by construction); with ``align = "fixed"`` turn =
-phase, psi = rot * (phi1 - phi0) + phase.

The views draw what this module computes (``pipeline.views.plots``) and the
scene's results file stores its phase errors (``/cyclogram``)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..model.cycle import output_shaped

DWELL_RESIDUAL = 0.10       # a window whose output moves more (share of its range) is no dwell
BOUNDARIES = ("dwell start", "forward start", "back start")   # where each output phase begins


def output_motion(res) -> dict | None:
    """The output's motion over the dense revolution as one number per
    position, and its best dwell window (DOMAIN.md section 9, computed as
    ``peaks.scene_motion`` does): the rocker angle theta [deg] from its first
    position when the study names ``[output] rocker``, else the working point's
    displacement [mm] along the main direction of its path.  None when the
    revolution does not assemble everywhere or the output does not move.

    Returns {y, what, unit, start (index of the window's first position),
    w (intervals in the window), error, dwell_deg}."""
    from ..kernels.metrics import dwell_error, relative_angle
    plan, d, out = res.plan, res.dense, res.study.output
    if d.overall != 0 or not np.isfinite(d.pos[:, :plan.n_visible]).all():
        return None
    if out.rocker is not None:
        ip, iq = (plan.point(p) for p in out.rocker)
        r = d.pos[:, iq] - d.pos[:, ip]
        y = np.degrees([relative_angle(r[0, 0], r[0, 1], x, z) for x, z in r])
        what, unit = f"rocker angle theta of {out.rocker[0]}->{out.rocker[1]}", "deg"
    else:
        iw = plan.point(out.working_point)
        p = d.pos[:, iw] - d.pos[:, iw].mean(axis=0)
        u = np.linalg.svd(p, full_matrices=False)[2][0]
        y = p @ u
        y = y - y[0]
        what, unit = f"{out.working_point} along its path's main direction", "mm"
    n = len(y)
    if not np.ptp(y) > 0:
        return None
    w = int(round(out.dwell_deg * n / 360))
    q = np.empty(n + w + 1, np.int64)
    err, start, _ = dwell_error(np.ascontiguousarray(y, dtype=np.float64), w, q, q.copy())
    if start < 0:
        return None
    return {"y": np.asarray(y, float), "what": what, "unit": unit, "start": int(start), "w": w,
            "error": float(err), "dwell_deg": out.dwell_deg}


def design_phases(motion) -> list[tuple]:
    """The design's own cycle as (name, start, length) in degrees of crank
    travel from the first dense position: its dwell (the best window), forward
    (to the position farthest from the dwell) and back (to the dwell again).
    The lengths sum to 360 deg."""
    y, s, w = motion["y"], motion["start"], motion["w"]
    n = len(y)
    step = 360.0 / n
    rest = (s + np.arange(w + 1, n)) % n
    mean = y[(s + np.arange(w + 1)) % n].mean()
    far = w + 1 + int(np.argmax(np.abs(y[rest] - mean))) if rest.size else n
    return [("dwell", s * step, w * step), ("forward", (s + w) * step, (far - w) * step),
            ("back", (s + far) * step, (n - far) * step)]


def stated_cycle(study):
    """The cycle a study requires, from the phases of its ``[output.motion_law]``:
    ([(name, start, end)] in degrees of the cycle angle psi, turn), where
    ``turn`` is None when the law is aligned at its best (the cyclogram turns
    it so that the dwells start together) and -phase when it is held fixed
    (psi = rot * (phi1 - phi0) + phase).  (None, None) when the study states
    no phases."""
    law = getattr(study.output, "motion_law", None)
    phases = getattr(law, "phases", None) or ()
    if not phases:
        return None, None
    out = []
    for p in phases:
        name = "dwell" if p.law == "dwell" else (
            f"{'forward' if p.level1 > p.level0 else 'back'} ({p.law})")
        out.append((name, float(p.start), float(p.start) + float(p.length)))
    fixed = getattr(law, "align", "best") == "fixed"
    return out, (-float(getattr(law, "phase", 0.0)) if fixed else None)


@dataclass
class Ring:
    """One organ's required phases: (kind, start, end) in deg of the cycle angle."""
    organ: str
    phases: list
    output: bool = False        # the organ the mechanism's output drives


@dataclass
class Cyclogram:
    """The machine's cyclogram of one design (see the module's docstring)."""
    rings: list                 # Ring: the output organ's first, then the others as declared
    turn: float | None          # deg of crank travel: tau = psi + turn (None: no placement)
    align: str                  # "best" or "fixed"
    motion: dict | None = None  # output_motion
    design: list = field(default_factory=list)   # design_phases (tau)
    dwells: bool = False        # the design's best window is a dwell (DWELL_RESIDUAL)
    actual: np.ndarray | None = None      # deg of crank travel, per BOUNDARIES
    required: np.ndarray | None = None    # deg of crank travel (psi + turn), per BOUNDARIES
    error: np.ndarray | None = None       # deg, actual - required in (-180, 180]
    why: str = ""               # why there are no phase errors

    @property
    def output_ring(self):
        return next((r for r in self.rings if r.output), None)

    def summary(self) -> dict:
        """The phase errors as run-summary lines."""
        if self.error is None:
            return {"phase_error": self.why} if self.why else {}
        how = ("the cycle turned so that both dwells start together" if self.align == "best"
               else "the cycle held at psi = rot (phi1 - phi0) + phase")
        ring = self.output_ring
        out = {}
        for b, a, r, e in zip(BOUNDARIES, self.actual, self.required, self.error):
            out[f"phase_error {ring.organ} {b}"] = (
                f"{e:+.1f} deg (design at psi = {(a - self.turn) % 360:.1f}, required "
                f"{(r - self.turn) % 360:g})")
        out["phase_error"] = f"actual - required, deg of the cycle angle psi; {how}"
        return out


def required_rings(study):
    """(rings, turn, align) of a study: the output organ's required phases (the
    [cycle] organ named by ``output``, else [output.motion_law]'s phases) and
    the other organs of [cycle]; turn None for align = "best"."""
    cyc = getattr(study, "cycle", None)
    law_phases, law_turn = stated_cycle(study)
    rings = []
    out_name = cyc.output if cyc is not None else ""
    organ = cyc.organ(out_name) if cyc is not None and out_name else None
    if organ is not None:
        rings.append(Ring(organ.name, [(p.kind, p.start, p.start + p.length)
                                       for p in organ.phases], True))
        turn = None if cyc.align == "best" else -cyc.phase
        align = cyc.align
    elif law_phases is not None:
        rings.append(Ring(out_name or "output", law_phases, True))
        turn, align = law_turn, ("best" if law_turn is None else "fixed")
    else:
        align = cyc.align if cyc is not None else "best"
        turn = -cyc.phase if cyc is not None else None
    for o in (cyc.organs if cyc is not None else ()):     # the other organs, as declared
        if o.name != out_name:
            rings.append(Ring(o.name, [(p.kind, p.start, p.start + p.length)
                                       for p in o.phases]))
    return rings, turn, align


def phase_key(name):
    """dwell, forward or back: the kind of a required output phase's name
    ("dwell", "forward (cycloidal)", "swing back", ...), else the name."""
    return next((k for k in ("dwell", "forward", "back") if k in name), name)


def wrap(d):
    """Angles (deg) into (-180, 180]."""
    d = np.asarray(d, float)
    return 180.0 - np.mod(180.0 - d, 360.0)


def scene_cyclogram(res, cycle=None, name="required cycle", turn=None) -> Cyclogram:
    """The cyclogram of a scene: its design's phases, the required rings and,
    where the output organ's required phases are one dwell, forward and back
    and the design dwells, the phase error at each boundary.  ``cycle``: the
    output organ's required phases as (name, start, end[, colour]) in deg of the
    cycle angle, instead of the study's (named ``name``, placed by ``turn``:
    None aligns the dwells)."""
    rings, turn_, align = required_rings(res.study)
    if cycle is None:
        turn = turn_
    else:
        rings = [Ring(name, [tuple(c) for c in cycle], True)] + [r for r in rings if not r.output]
        align = "best" if turn is None else "fixed"
    cg = Cyclogram(rings=rings, turn=turn, align=align)
    cg.motion = output_motion(res)
    if cg.motion is None:
        cg.why = "no phases: the output does not move or the mechanism does not assemble"
        if turn is None:
            cg.turn = 0.0
        return cg
    cg.design = design_phases(cg.motion)
    cg.dwells = cg.motion["error"] <= DWELL_RESIDUAL
    ring = cg.output_ring
    if cg.turn is None:
        dwell0 = next((a for k, a, *_ in ring.phases if phase_key(k) == "dwell"),
                      ring.phases[0][1]) if ring is not None else 0.0
        cg.turn = cg.design[0][1] - dwell0 if ring is not None else 0.0
    if ring is None:
        return cg
    if not output_shaped(phase_key(k) for k, *_ in ring.phases):
        cg.why = (f"not computed: the required phases of {ring.organ} are not one dwell, "
                  "forward and back")
        return cg
    if not cg.dwells:
        cg.why = (f"not computed: the design does not dwell (its best {cg.motion['dwell_deg']:g} "
                  f"deg window moves {100 * cg.motion['error']:.0f} % of its range)")
        return cg
    start = {phase_key(k): a for k, a, *_ in ring.phases}
    cg.actual = np.array([a for _, a, _ in cg.design], float)
    cg.required = np.array([start[k] + cg.turn for k in ("dwell", "forward", "back")], float)
    cg.error = wrap(cg.actual - cg.required)
    return cg
