"""Peaks a designer asks for, exact, with the crank angle where they happen.

For a scene: the peak speed |v| and acceleration |a| of every named point, the
peak |omega| and |eps| of every link, the smallest transmission angle of every
dyad and class III lead, and, with forces, the peak reaction of every joint,
the peak normal force |N| and couple |C| of every slide, the peak
|balancing moment| and the peak |shaking force| and |shaking moment| on the
frame (``kernels.forces.shaking``), and with [mechanism.friction] the
reactions and M_bal with friction and each plain bearing's pressure p,
sliding speed v and p*v (``solve.friction``).  Each peak is bracketed by the
largest sample of the dense revolution and its two neighbours, then found by
a bounded 1-D maximiser (SciPy's Brent) on the exact kinematics: the
continuation is walked from the first position to the trial angle, so the
peak lies on the revolution's own assembly branch.

An input law (``pipeline.model.groups.law``) may swing within a few dense
positions (a short rise, a geared crank's turn) and its derivatives jump at
its breaks (a rise's ends, a table's knots): the brackets are then found on
the dense positions divided until each of the law's pieces holds
PIECE_POSITIONS, with the breaks as positions of their own, each side of a
break searched apart, and every hump whose sample may lie below its top
refined too (``bracket_positions``, ``_rivals``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.mechanism import transmission_items
from .scene import Continuation, real_motion, solve_curves

XATOL = 1e-9          # rad: where a peak is, to about 6e-8 deg


@dataclass
class Peak:
    quantity: str       # velocity, acceleration, omega, eps, reaction, slide_normal,
                        # slide_couple, M_bal, shaking_force, shaking_moment,
                        # min_transmission_angle; with friction bearing_pressure,
                        # sliding_speed, bearing_pv (BEARING_PEAKS)
    item: str           # the point, link, joint, slide or dyad
    value: float        # the peak magnitude
    unit: str
    phi1: float         # crank angle of the peak, deg
    grid_value: float   # the largest sample of the dense revolution


# the plain bearings' peaks (with [mechanism.friction]): the scene keeps them with its
# friction (``solve.friction.FrictionForces.peaks``, the results file's /friction), not
# among the peaks of /peaks
BEARING_PEAKS = ("bearing_pressure", "sliding_speed", "bearing_pv")
# the quantities of the kinematics alone, and those of the forces
MOTION_PEAKS = ("velocity", "acceleration", "omega", "eps")
FORCE_PEAKS = ("reaction", "slide_normal", "slide_couple", "M_bal", "shaking_force",
               "shaking_moment") + BEARING_PEAKS


def _magnitudes(study, plan, curves, forces=None, quantity=None):
    """{(quantity, item, unit): array over the rows of ``curves``}: of every
    quantity, or those of ``quantity`` (a refined peak's trial angle asks for its
    own): the motion's and the transmission angles' only where asked, the forces'
    all from the ``forces`` given.  The same arrays either way."""
    out = {}
    if quantity is None or quantity in MOTION_PEAKS:
        crank = study.mechanism.crank
        v, a, om, ep = real_motion(curves, crank.omega1, crank.eps1)
        nv = plan.n_visible
        for i, name in enumerate(plan.point_names[:nv]):
            out[("velocity", name, "m/s")] = np.hypot(v[:, i, 0], v[:, i, 1])
            out[("acceleration", name, "m/s²")] = np.hypot(a[:, i, 0], a[:, i, 1])
        for j, lab in enumerate(study.output.link_labels):
            out[("omega", lab, "1/s")] = np.abs(om[:, j])
            out[("eps", lab, "1/s²")] = np.abs(ep[:, j])
    for label, kind, names in (transmission_items(study.mechanism) if quantity in (
            None, "transmission_deviation") else ()):
        # transmission angle, as its deviation from 90 deg
        if kind == "lines":     # a group with a sliding pair: two lines (see below)
            u, w = (_line(curves.pos, plan, *line) for line in names)
        else:
            P = [curves.pos[:, plan.point_names.index(p)] for p in names]
            if kind == "dyad":  # at the middle joint B, between B->A and B->C
                a, b, c = P
                u, w = a - b, c - b
            else:               # class III lead J-P: the lead against J->Q (see below)
                j, piv, a, b, c, d = P
                u, w = piv - j, _meet(a - j, b - j, c - j, d - j)
        mu = np.degrees(np.arctan2(np.abs(u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0]),
                                   np.abs(u[:, 0] * w[:, 0] + u[:, 1] * w[:, 1])))
        out[("transmission_deviation", label, "deg")] = 90.0 - mu
    if forces is not None:
        mag = forces.magnitude
        for j, name in enumerate(forces.joint_names):
            out[("reaction", name, "N")] = mag[:, j]
        for k, name in enumerate(forces.slide_names):   # each prismatic pair's |N|, |C|
            out[("slide_normal", name, "N")] = np.abs(forces.slide[:, k, 0])
            out[("slide_couple", name, "N·m")] = np.abs(forces.slide[:, k, 1])
        out[("M_bal", "crank", "N·m")] = np.abs(forces.M_bal)
        if forces.shaking is not None:      # on the frame (kernels.forces.shaking)
            out[("shaking_force", "frame", "N")] = forces.shaking_magnitude
            out[("shaking_moment", "frame", "N·m")] = np.abs(forces.shaking[:, 2])
        fr = forces.friction
        if fr is not None:      # [mechanism.friction]: each plain bearing's p, v and p*v
            pv = fr.pv
            for j, (name, _, _) in enumerate(fr.spec.pins):
                out[("bearing_pressure", name, "MPa")] = fr.pressure[:, j]
                out[("sliding_speed", name, "m/s")] = fr.sliding_speed[:, j]
                out[("bearing_pv", name, "MPa·m/s")] = pv[:, j]
    return out


def split_bearing_peaks(peaks):
    """(the peaks but the bearings', {(quantity, joint): Peak} of the bearings')."""
    return ([p for p in peaks if p.quantity not in BEARING_PEAKS],
            {(p.quantity, p.item): p for p in peaks if p.quantity in BEARING_PEAKS})


def _line(pos, plan, a, b, alpha):
    """Direction (n, 2) of the link a->b turned by alpha, or of the absolute
    alpha where a is None (``kernels.metrics._line``)."""
    c, s = math.cos(alpha), math.sin(alpha)
    if a is None:
        return np.broadcast_to(np.array([c, s]), (pos.shape[0], 2))
    d = pos[:, plan.point_names.index(b)] - pos[:, plan.point_names.index(a)]
    return np.stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]], axis=1)


def _meet(a, b, c, d):
    """Direction (n, 2) from the origin to the meet of the lines a-b and c-d
    (homogeneous coordinates: (X, Y), W's sign aside; parallel lines give
    their common direction)."""
    l1 = np.stack([a[:, 1] - b[:, 1], b[:, 0] - a[:, 0], a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]],
                  axis=1)
    l2 = np.stack([c[:, 1] - d[:, 1], d[:, 0] - c[:, 0], c[:, 0] * d[:, 1] - c[:, 1] * d[:, 0]],
                  axis=1)
    q = np.cross(l1, l2)
    return q[:, :2]


def scene_peaks(res, keep=None) -> list[Peak]:
    """Every peak of the scene ``res`` (pipeline.solve.scene.SceneResult), refined;
    with ``keep(quantity, item)`` only those it keeps (each peak is refined on
    its own: the same numbers to the bit as among all of them)."""
    from scipy.optimize import minimize_scalar

    from .friction import scene_forces_with_friction
    study, plan, dense = res.study, res.plan, res.dense

    def forces_of(c):        # (with the mechanism's friction, where it has some)
        return scene_forces_with_friction(study.mechanism, plan, c, lambda phis: solve_curves(
            plan, phis, 2, res.tolerances))
    if dense.overall != 0 or not np.isfinite(dense.pos).all():
        return []      # a scene that does not assemble everywhere has no peaks to refine
    crank = study.mechanism.crank
    phis = dense.phi
    order = 2
    with_forces = dense.forces is not None
    grid = _magnitudes(study, plan, dense, dense.forces)
    if keep is not None:
        grid = {k: v for k, v in grid.items() if keep(k[0], k[1])}
    nodes, walked, breaks = bracket_positions(study.mechanism, phis)
    if len(nodes) == len(phis):
        samples = grid            # no input law steeper than the dense revolution resolves
    else:
        c = solve_curves(plan, nodes, order, res.tolerances)
        samples = {k: v for k, v in _magnitudes(study, plan, c, forces_of(c) if with_forces
                                                 else None).items() if k in grid}
        bad = c.status != 0       # (a position the walk between dense ones failed: unsampled)
        samples = {k: np.where(bad, np.nan, v) for k, v in samples.items()}
    n = len(nodes)
    phi_end = crank.phi0 + crank.rot * 2.0 * math.pi
    walks, forced = {}, {}
    # each trial angle's walk goes on from the dense position before it (the same bits as
    # the walk from the first position, for one step): the states kept at the first trial
    resume = []

    def at(m, phi, quantity):
        """The magnitudes of ``quantity`` at ``phi``, walked from phis[0] through
        phis[:m] (the walk, and the forces where the quantity is one, kept for the
        other peaks that try the same angle)."""
        key = (m, float(phi))
        if key not in walks:
            if not resume:
                resume.append(Continuation.of(plan, phis, order, res.tolerances))
            if resume[0] is not None and m >= 1:
                c = resume[0].row(m, phi)
            else:
                c = solve_curves(plan, np.concatenate([phis[:m], [phi]]), order,
                                 res.tolerances)
            walks[key] = (c.status[-1], _row(c, -1))
        status, row = walks[key]
        f = None
        if with_forces and quantity in FORCE_PEAKS:
            if key not in forced:
                forced[key] = forces_of(row)
            f = forced[key]
        return status, _magnitudes(study, plan, row, f, quantity)

    out = []
    for key, values in samples.items():
        if not np.isfinite(values).any():
            continue     # not computed at the study's analysis level (velocities, ...)
        kmax = int(np.nanargmax(values))
        best_phi, best = nodes[kmax], float(values[kmax])
        for lo, hi, m in _brackets(_rivals(values), n, breaks, walked):
            lo, hi = nodes[lo], nodes[hi] if hi < n else phi_end

            def neg(phi, key=key, m=m):
                st, mags = at(m, phi, key[0])
                v = mags[key][0]
                return -v if st == 0 and math.isfinite(v) else math.inf

            # (an angle whose walk fails scores inf; the bounded search's parabola
            # through it is NaN, which sends it to a golden-section step: no warning)
            with np.errstate(invalid="ignore", over="ignore"):
                r = minimize_scalar(neg, bounds=(min(lo, hi), max(lo, hi)),
                                    method="bounded", options={"xatol": XATOL})
            if r.success and -r.fun > best:
                best_phi, best = float(r.x), float(-r.fun)
        top = float(np.nanmax(grid[key]))     # the largest sample of the dense revolution
        if key[0] == "transmission_deviation":     # stored as what designers read
            out.append(Peak("min_transmission_angle", key[1], 90.0 - best, key[2],
                            math.degrees(best_phi), 90.0 - top))
        else:
            out.append(Peak(key[0], key[1], best, key[2], math.degrees(best_phi), top))
    return out


# positions within each piece of an input law (a rise, a return, a spline piece, a geared
# crank's turn) at which the peaks are bracketed: the dense revolution's steps that a
# shorter piece overlaps are divided until it has as many (at the reader's steepest laws,
# limits.LAW_MIN_POSITIONS and TABLE_LAW_MIN_POSITIONS, into 8 or 32)
PIECE_POSITIONS = 64
BREAK_FUZZ = 1e-12      # rad: a law's break this close to a position is at that position


def bracket_positions(mech, phis):
    """(nodes, walked, breaks) where the peaks are bracketed: the dense
    revolution ``phis`` (its step 2 pi / n), each step that a piece of an
    input law shorter than PIECE_POSITIONS steps overlaps divided in equal
    parts until the piece holds that many (``Law.pieces``), and the crank
    angles where a law's derivatives jump added as positions of their own.
    ``walked[j]``: how many dense positions lie before node j (the walk to a
    trial angle between nodes goes through those); ``breaks``: the nodes at
    a law's break, each side of which is refined apart (a peak on a jump is a
    one-sided limit).  The dense revolution itself (and no breaks) without
    input laws."""
    crank = mech.crank
    n = len(phis)
    step = 2.0 * math.pi / n
    parts = np.ones(n, np.int64)         # per dense step
    cuts = []
    for g in mech.groups:
        law = getattr(g, "law", None)
        if law is None:
            continue
        where, pieces = law.pieces()
        # along the revolution: the distance from phis[0] (rad, [0, 2 pi))
        cuts += [crank.rot * (c - crank.phi0) % (2.0 * math.pi) for c in where]
        for start, length in pieces:
            need = math.ceil(PIECE_POSITIONS * step / length * (1.0 - 1e-9))
            if need <= 1:
                continue
            # the piece, in the revolution's direction (a backward crank meets it end first)
            first = (crank.rot * (start - crank.phi0) if crank.rot > 0 else
                     -(start + length - crank.phi0)) % (2.0 * math.pi)
            k = np.arange(math.floor(first / step), math.ceil((first + length) / step)) % n
            parts[k] = np.maximum(parts[k], need)
    dense_at = np.arange(n) * step
    within = np.concatenate([np.arange(p) / p for p in parts]) if parts.max() > 1 else \
        np.zeros(n)
    owner = np.repeat(np.arange(n), parts)
    sub = dense_at[owner] + within * step
    nodes = phis[owner] + crank.rot * within * step
    first_of = np.concatenate([[0], np.cumsum(parts)[:-1]])
    sub[first_of], nodes[first_of] = dense_at, phis      # the dense positions themselves, exactly
    is_break = np.zeros(len(sub), bool)
    extra = []
    for s in sorted(set(cuts)):
        j = int(np.searchsorted(sub, s))
        j = j if j < len(sub) and (j == 0 or sub[j] - s < s - sub[j - 1]) else j - 1
        if abs(sub[j] - s) <= BREAK_FUZZ:
            is_break[j] = True
        elif 2.0 * math.pi - s <= BREAK_FUZZ:
            is_break[0] = True
        else:
            extra.append(s)
    if extra:
        extra = np.array(extra)
        order = np.argsort(np.concatenate([sub, extra]), kind="stable")
        sub = np.concatenate([sub, extra])[order]
        nodes = np.concatenate([nodes, crank.phi0 + crank.rot * extra])[order]
        is_break = np.concatenate([is_break, np.ones(len(extra), bool)])[order]
    walked = np.searchsorted(dense_at, sub, side="left")
    return nodes, walked, frozenset(np.flatnonzero(is_break).tolist())


def scene_motion(res) -> dict:
    """Dwell error and stroke of a scene with an output rocker (DOMAIN.md
    section 9, as the sweep computes them), and with [output.motion_law] the
    law error (``pipeline.model.motion_law``): {} without a rocker."""
    from ..kernels.metrics import dwell_error, relative_angle
    out_spec = res.study.output
    if out_spec.rocker is None or res.dense.overall != 0:
        return {}
    plan, pos = res.plan, res.dense.pos
    ip, iq = (plan.point_names.index(p) for p in out_spec.rocker)
    rx, ry = pos[:, iq, 0] - pos[:, ip, 0], pos[:, iq, 1] - pos[:, ip, 1]
    theta = np.array([relative_angle(rx[0], ry[0], x, y) for x, y in zip(rx, ry)])
    n = len(theta)
    w = int(round(out_spec.dwell_deg * n / 360))
    q = np.empty(n + w + 1, np.int64)
    err, start, full = dwell_error(theta, w, q, q.copy())
    iw = plan.point_names.index(out_spec.working_point)
    radius = math.hypot(pos[0, iw, 0] - pos[0, ip, 0], pos[0, iw, 1] - pos[0, ip, 1])
    out = {"dwell_error": float(err), "dwell_start": float(np.degrees(res.dense.phi[start]))
           if start >= 0 else math.nan, "stroke": radius * float(full), "dwell_deg":
           out_spec.dwell_deg}
    law = out_spec.motion_law
    if law is not None:
        out.update(law.error(theta, res.study.mechanism.crank, res.dense.phi))
    return out


RIVALS = 4            # local maxima refined per quantity (two humps of nearly one height)
RIVAL_SHARE = 0.999   # ... those within 0.1 % of the largest sample
RISERS = 8            # and at most this many more whose top may rise above the largest sample


def _rivals(values):
    """Indices of the grid's local maxima (cyclic) within RIVAL_SHARE of the
    largest sample, the largest first, then those whose top may lie above the
    largest sample, the most promising first: the true peak lies next to one
    of them.  A sharp hump (a geared crank's turn, a short rise) may be
    sampled well below its top: a parabola through a sample and its two
    neighbours rises above the sample by at most an eighth of their second
    difference; a hump counts as a riser if twice that lifts it to the
    largest sample."""
    v = np.nan_to_num(np.asarray(values, float), nan=-np.inf)
    if not np.isfinite(v).any() or np.nanmax(v) <= 0.0:
        return [int(np.argmax(v))]
    before, after = np.roll(v, 1), np.roll(v, -1)
    local = (v >= before) & (v >= after)
    near = local & (v >= RIVAL_SHARE * v.max())
    idx = np.nonzero(near)[0]
    out = [int(i) for i in idx[np.argsort(-v[idx])][:RIVALS]] or [int(np.argmax(v))]
    with np.errstate(invalid="ignore"):
        reach = v + (2.0 * v - before - after) / 4.0
        rise = local & ~near & np.isfinite(reach) & (reach >= v.max())
    idx = np.nonzero(rise)[0]
    return out + [int(i) for i in idx[np.argsort(-reach[idx])][:RISERS]]


def _brackets(rivals, n, breaks, walked):
    """(lo, hi, m) per search: the nodes (of ``n``; hi = n is the revolution's
    end) that bracket each rival node k, k - 1 to k + 1, or each side apart
    where k is a law's break; the first node also from the last (the
    revolution is closed).  m: the dense positions walked before the search."""
    out = []
    for k in rivals:
        if k in breaks:
            sides = [(k - 1, k), (k, k + 1)] if k > 0 else [(n - 1, n), (0, 1)]
        else:
            sides = [(max(k - 1, 0), k + 1)] + ([(n - 1, n)] if k == 0 else [])
        out += [(lo, hi, int(walked[lo])) for lo, hi in sides]
    return out


def _row(curves, k):
    """Row ``k`` of ``curves`` as a one-position Curves."""
    from dataclasses import replace
    sl = slice(k, None) if k == -1 else slice(k, k + 1)
    return replace(curves, phi=curves.phi[sl], pos=curves.pos[sl], d1=curves.d1[sl],
                   d2=curves.d2[sl], status=curves.status[sl], margin=curves.margin[sl],
                   iterations=curves.iterations[sl], links=curves.links[sl], forces=None)


def peaks_frame(peaks):
    """The peaks as a DataFrame (units in ``df.attrs``)."""
    import pandas as pd
    df = pd.DataFrame([(p.quantity, p.item, p.value, p.unit, p.phi1, p.grid_value)
                       for p in peaks],
                      columns=["quantity", "item", "value", "unit", "phi1", "grid_value"])
    df.attrs["units"] = {"phi1": "deg"}
    return df
