"""Pictures a designer wants to see.  Every function takes computed results and
returns a matplotlib Figure: saving it (``files.save_figure``) or showing it
is the caller's choice.  The backend is the caller's too: the command line
chooses Agg, a notebook keeps its own.

The drawings share one colour code: the k-th overlaid position of the
mechanism, its marks on the point paths and the colour key beside the drawing
all have the same colour, so the crank angle of every drawn position can be
read off the key."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np

from .cyclogram_plots import cyclogram_figure  # noqa: F401 (a picture of plots, drawn there)
from .dynamics_plots import eps1_figure  # noqa: F401 (a picture of plots, drawn there)
from .labels import POINT_OFFSETS, around, is_constant, link_name, mark_peak, placer
from ..solve.scene import real_motion

POSITION_CMAP = "viridis"
MAX_KEY_TICKS = 12          # labelled crank angles on the colour key
ARROWS_PER_PATH = 3         # arrows showing the direction of travel on each path
LABEL_SPACING = 0.045       # crank-angle labels on a path: at least this share of the drawing apart


def _links_to_draw(plan, study):
    """Segments to draw: the crank, and each group's (its type's ``segments``)."""
    m = study.mechanism
    segs = [(m.crank.pivot, m.crank.tip)] + [s for g in m.groups for s in g.segments()]
    return [(plan.point(a), plan.point(b)) for a, b in segs]


def joint_labels(plan) -> dict:
    """{point index: its joint names} of the joints whose reactions are
    reported (R1 at P1, ...); empty without mass data."""
    out = {}
    for name, ip in zip(plan.joint_names, plan.joint_point):
        out.setdefault(int(ip), []).append(name)
    return out


def joint_descriptions(plan) -> list[str]:
    """One line per reported joint: 'R2: crank 1-2 / lead 2-3 at P2'."""
    from ..solve.reactions import joint_where
    return [f"{name}: {where}" for name, where in zip(plan.joint_names, joint_where(plan))]


def point_label(plan, i, joints=None) -> str:
    """A point's name with the joint reported there: 'P2 (R2)'."""
    joints = joint_labels(plan) if joints is None else joints
    name = plan.point_names[i]
    return f"{name} ({', '.join(joints[i])})" if i in joints else name


def position_colours(n):
    cmap = plt.get_cmap(POSITION_CMAP)
    return [cmap(k / max(n - 1, 1)) for k in range(n)]


def _deg_text(phi_rad):
    return f"{round(math.degrees(phi_rad), 6):g}"


def crank_angle_key(ax, phis, orientation="vertical"):
    """The colour key of the overlaid positions: one colour band per drawn
    position, labelled with its crank angle phi1.  Returns the colorbar."""
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import BoundaryNorm, ListedColormap
    n = len(phis)
    sm = ScalarMappable(norm=BoundaryNorm(np.arange(n + 1) - 0.5, n),
                        cmap=ListedColormap(position_colours(n)))
    kw = dict(fraction=0.035, pad=0.02) if orientation == "vertical" else \
        dict(fraction=0.05, pad=0.08, aspect=30)
    cb = ax.figure.colorbar(sm, ax=ax, orientation=orientation, **kw)
    every = max(1, math.ceil(n / (MAX_KEY_TICKS if orientation == "vertical" else 7)))
    ticks = list(range(0, n, every))
    cb.set_ticks(ticks, labels=[_deg_text(phis[k]) for k in ticks])
    cb.minorticks_off()
    cb.set_label("crank angle phi1 [deg] of each drawn position", fontsize=8)
    cb.ax.tick_params(labelsize=7)
    cb.ax.set_label("crank angle key")
    return cb


def _travel_arrows(ax, path, count=ARROWS_PER_PATH, color="0.25"):
    """Arrows along a closed path, pointing the way the point travels."""
    ok = np.isfinite(path).all(axis=1)
    n = len(path)
    drawn = 0
    for j in range(count):
        k = int(n * (j + 0.3) / count)
        a, b = path[(k - 1) % n], path[(k + 1) % n]
        if not (ok[(k - 1) % n] and ok[(k + 1) % n]) or np.allclose(a, b):
            continue
        ax.annotate("", xy=b, xytext=a, annotation_clip=False,
                    arrowprops=dict(arrowstyle="-|>", color=color, lw=0.9, mutation_scale=11,
                                    shrinkA=0, shrinkB=0))
        drawn += 1
    return drawn


def _angle_labels(ax, pts, phis, cols, spacing, centre):
    """Crank-angle labels at the marks of one path, those too close to an
    already labelled one left out; each pushed outward from the path's centre
    (where it covers no other label once the layout is known: else turned,
    else left out).  Returns the annotations."""
    kept, out = [], []
    for k, (p, phi) in enumerate(zip(pts, phis)):
        if not np.isfinite(p).all() or any(np.hypot(*(p - q)) < spacing for q in kept):
            continue
        kept.append(p)
        d = p - centre
        d = d / np.hypot(*d) if np.hypot(*d) > 0 else np.array([1.0, 0.0])
        out.append((ax.annotate(_deg_text(phi), p, textcoords="offset points",
                                xytext=tuple(9 * d), fontsize=6.5, color=cols[k], ha="center",
                                va="center", weight="bold"), around(*d)))
    return out


def draw_positions(ax, res, curves, highlight=None, key="vertical", marks=True, joint_key=True):
    """The mechanism at every position of ``curves`` and its points' paths.

    The positions are coloured by their crank angle (``key``: the colour key,
    "vertical", "horizontal" or None); every moving point's path (dotted, from
    the dense curves) carries coloured marks at the drawn positions and arrows
    for the direction of travel, and the crank tip's and the working point's
    marks are labelled with phi1; points where a reported joint sits are
    named with it (P2 (R2)), and ``joint_key`` lists what each joint joins."""
    plan, study = res.plan, res.study
    segs = _links_to_draw(plan, study)
    nv = plan.n_visible
    fixed = [plan.point(p) for p in study.mechanism.fixed]
    n = curves.pos.shape[0]
    cols = position_colours(n)
    for k in range(n):
        lw, alpha = (2.4, 1.0) if k == highlight else (1.0, 0.55)
        for a, b in segs:
            ax.plot(curves.pos[k, [a, b], 0], curves.pos[k, [a, b], 1], "-", color=cols[k], lw=lw,
                    alpha=alpha)
    dense = res.dense.pos
    every = np.concatenate([dense[:, :nv].reshape(-1, 2), curves.pos[:, :nv].reshape(-1, 2)])
    every = every[np.isfinite(every).all(axis=1)]
    span = float(np.ptp(every, axis=0).max()) if len(every) else 1.0
    labelled = {plan.point(study.mechanism.crank.tip), plan.point(study.output.working_point)}
    angle_labels = []
    for i in range(nv):
        if i in fixed:
            continue
        path = dense[:, i]
        ax.plot(path[:, 0], path[:, 1], ":", color="0.35", lw=0.8)
        if not marks:
            continue
        good = np.isfinite(path).all(axis=1)
        if not good.any():
            continue
        moved = float(np.ptp(path[good], axis=0).max())
        if moved > 0.004 * span:
            _travel_arrows(ax, path)
        ax.scatter(curves.pos[:, i, 0], curves.pos[:, i, 1], c=cols, s=9, zorder=3, lw=0)
        if i in labelled and moved > 0.004 * span:
            angle_labels += _angle_labels(ax, curves.pos[:, i], curves.phi, cols,
                                          LABEL_SPACING * span, path[good].mean(axis=0))
    joints = joint_labels(plan)
    for i in range(nv):
        x, y = curves.pos[0, i]
        if not np.isfinite(x):
            continue
        ax.plot(x, y, "s" if i in fixed else "o", color="k", ms=5 if i in fixed else 3)
        placer(ax).add(ax.annotate(point_label(plan, i, joints), (x, y),
                                   textcoords="offset points", xytext=(4, 4), fontsize=8),
                       POINT_OFFSETS)
    for ann, offsets in angle_labels:       # the points' names first, the angles where they fit
        placer(ax).add(ann, offsets, optional=True)
    if joints and joint_key:
        ax.text(0.98, 0.02, "\n".join(joint_descriptions(plan)), transform=ax.transAxes,
                fontsize=6.5, ha="right", va="bottom", family="monospace", multialignment="left",
                bbox=dict(boxstyle="round", fc="white", ec="0.7", alpha=0.85))
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.grid(alpha=0.3)
    if key:
        crank_angle_key(ax, curves.phi, key)


def scene_figure(res):
    """Mechanism at its table positions with trajectories, and the working
    point's displacement, velocity and acceleration against crank angle.
    Returns the Figure (saving it is the caller's choice)."""
    study = res.study
    crank = study.mechanism.crank
    wp = study.output.working_point
    iwp = res.plan.point(wp)
    fig = plt.figure(figsize=(13, 8), layout="constrained")
    gs = fig.add_gridspec(3, 2, width_ratios=[1.25, 1])
    ax = fig.add_subplot(gs[:, 0])
    table = res.table
    draw_positions(ax, res, _without_closing_row(table), highlight=0)
    ax.set_title(f"{study.title}\n{table.pos.shape[0] - 1} positions (thick: phi1 = "
                 f"{_deg_text(table.phi[0])} deg), dotted: point paths, arrows: direction of "
                 f"travel (working point {wp})", fontsize=10)
    d = res.dense
    phi = np.rad2deg(d.phi)
    v, a, _, _ = real_motion(d, crank.omega1, crank.eps1)
    disp = d.pos[:, iwp] - d.pos[0, iwp]
    rows = [(disp, "displacement [mm]"), (v[:, iwp], "velocity [m/s]"),
            (a[:, iwp], "acceleration [m/s²]")]
    for r, (data, label) in enumerate(rows):
        axr = fig.add_subplot(gs[r, 1])
        axr.plot(phi, data[:, 0], label="x")
        axr.plot(phi, data[:, 1], label="y")
        if np.isfinite(data).any():
            axr.plot(phi, np.hypot(data[:, 0], data[:, 1]), "k--", lw=0.8, label="|.|")
        axr.set_ylabel(f"{wp} {label}")
        axr.grid(alpha=0.3)
        if crank.rot < 0:
            axr.invert_xaxis()
        if r == 0:
            axr.legend(fontsize=8, ncol=3)
            axr.set_title(f"omega1 = {crank.omega1:g} rad/s", fontsize=10)
    axr.set_xlabel("crank angle phi1 [deg]")
    return fig


def _without_closing_row(curves):
    """The table without its closing row (same position as the first)."""
    from dataclasses import replace
    n = curves.pos.shape[0] - 1
    return replace(curves, phi=curves.phi[:n], pos=curves.pos[:n], d1=curves.d1[:n],
                   d2=curves.d2[:n])


def forces_figure(res):
    """Joint reactions and balancing moment against crank angle, and the polar
    diagram of the reaction in the most loaded joint.  Returns the Figure."""
    fr = res.dense.forces
    mech = res.study.mechanism
    crank = mech.crank
    phi = np.rad2deg(res.dense.phi)
    rows = 3 if mech.loads else 2
    fig = plt.figure(figsize=(13, 5.5 if rows == 2 else 8.0), layout="constrained")
    gs = fig.add_gridspec(rows, 2, width_ratios=[1.45, 1])
    ax = fig.add_subplot(gs[0, 0])
    mag = np.hypot(fr.R[:, :, 0], fr.R[:, :, 1])
    where = dict(zip(res.plan.joint_names, joint_descriptions(res.plan)))
    ax.set_label("joint reactions")
    for j, name in enumerate(fr.joint_names):
        line, = ax.plot(phi, mag[:, j], label=where.get(name, name))
        if np.isfinite(mag[:, j]).any() and not is_constant(mag[:, j]):
            k = int(np.nanargmax(mag[:, j]))
            mark_peak(ax, phi[k], mag[k, j], colour=line.get_color(), ms=3, what=f"|{name}|")
    ax.set_ylabel("|R| [N]")
    # beside the curves, never over their peaks
    outside_legend(ax, ncol=2 if len(fr.joint_names) > 8 else 1)
    ax.grid(alpha=0.3)
    ax.set_title(f"Joint reactions at omega1 = {crank.omega1:g} rad/s", fontsize=10)
    ax2 = fig.add_subplot(gs[1, 0], sharex=ax)
    ax2.plot(phi, fr.M_bal, "k", label="M_bal: the main shaft's moment")
    for k, name in enumerate(fr.input_names):      # inputs driven from the main shaft
        ax2.plot(phi, fr.drive[:, k, 1], "--", label=f"share of input {name!r} (drive x dq/dphi1)")
    if fr.input_names:
        outside_legend(ax2)
    ax2.set_ylabel("M_bal [N·m]")
    ax2.set_xlabel("crank angle phi1 [deg]")
    ax2.grid(alpha=0.3)
    if mech.loads:
        # the loads as the study gives them (formulas of phi and t), against phi1
        ax3 = fig.add_subplot(gs[2, 0], sharex=ax)
        from ..solve.reactions import sample_loads
        loads = sample_loads(mech, res.dense.phi)
        for k, ld in enumerate(mech.loads):
            for c, (e, what, unit) in enumerate(((ld.fx, "fx", "N"), (ld.fy, "fy", "N"),
                                                 (ld.moment, "M", "N·m"))):
                y = loads[:, k, c]
                if np.any(y != 0.0):
                    ax3.plot(phi, y, label=f"{what} on {ld.body}"
                             + (f" at {ld.point}" if ld.point and c < 2 else "")
                             + f" = {getattr(e, 'text', e)} [{unit}]")
        ax3.set_ylabel("load [N, N·m]")
        ax3.set_xlabel("crank angle phi1 [deg]")
        ax3.legend(fontsize=7, loc="best")     # no peaks marked here
        ax3.grid(alpha=0.3)
        ax3.set_title("External loads, as the study gives them", fontsize=9)
    if crank.rot < 0:
        ax.invert_xaxis()
    j = int(np.nanargmax(np.nanmax(mag, axis=0)))
    axp = fig.add_subplot(gs[:, 1])
    rx, ry = fr.R[:, j, 0], fr.R[:, j, 1]
    axp.plot(np.append(rx, rx[0]), np.append(ry, ry[0]), "-", color="C3")
    axp.plot([0], [0], "k+")
    _travel_arrows(axp, np.stack([rx, ry], axis=1), color="C3")
    # crank-angle marks every 30 deg of the revolution (the first one labelled)
    step = polar_marks(axp, phi, rx, ry, "C3")
    axp.set_aspect("equal", adjustable="datalim")
    axp.set_xlabel("Rx [N]")
    axp.set_ylabel("Ry [N]")
    axp.grid(alpha=0.3)
    # short lines: a tall diagram is narrow, and its title must not pass the edge
    axp.set_title(f"Polar diagram of {where.get(fr.joint_names[j], fr.joint_names[j])}\n"
                  "(the most loaded joint)\narrows: direction as the crank turns;\n"
                  f"dots every {360 * step / len(phi):.0f} deg of phi1, labels in deg", fontsize=9)
    return fig


def outside_legend(ax, **kw):
    """The axes' legend beside it, right of its frame: it covers no curve, peak
    or label (the layout makes room for it)."""
    return ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                     borderaxespad=0.0, **kw)


def polar_marks(ax, phi, fx, fy, colour):
    """A hodograph's marks: dots every 30 deg of phi1 (every 90 deg labelled,
    where the label fits), its peak marked and labelled.  Returns the step
    between dots (samples)."""
    step = max(1, len(phi) // 12)
    ax.plot(fx[::step], fy[::step], "o", ms=3, color=colour)
    mag = np.hypot(fx, fy)
    k = int(np.nanargmax(mag))
    mark_peak(ax, fx[k], fy[k], colour=colour, ms=4, what="polar")
    c = np.array([np.nanmean(fx), np.nanmean(fy)])
    p = placer(ax)
    p.add(ax.annotate(f"max {mag[k]:.1f} N\nat {phi[k]:.0f} deg", (fx[k], fy[k]), fontsize=8,
                      color=colour, textcoords="offset points",
                      xytext=(4, 4)), POINT_OFFSETS)
    for q in range(0, len(phi), step * 3):
        p.add(ax.annotate(f"{phi[q]:.0f}", (fx[q], fy[q]), fontsize=7, color="0.3",
                          xytext=(3, 3), textcoords="offset points"),
              around(fx[q] - c[0], fy[q] - c[1], 8.0), optional=True)
    return step


# ----------------------------------------------------------------- small multiples
def _angle_deg(x):
    """Link angle in degrees, unwrapped over its finite samples."""
    out = np.full(x.shape, np.nan)
    ok = np.isfinite(x)
    if ok.any():
        out[ok] = np.rad2deg(np.unwrap(x[ok]))
    return out


def not_computed(ax, y, study):
    """Say so on a panel whose quantity the study's analysis level leaves out."""
    if not np.isfinite(y).any():
        ax.text(0.5, 0.5, f"not computed (analysis = {study.output.analysis})",
                ha="center", va="center", transform=ax.transAxes, fontsize=7)


def trim_rows(axes, used):
    """Remove the rows of a panel grid past the first ``used`` and label the
    crank-angle axis of the last one kept."""
    for r in range(used, axes.shape[0]):
        for c in range(axes.shape[1]):
            axes[r, c].remove()
    for c in range(axes.shape[1]):
        axes[used - 1, c].set_xlabel("crank angle phi1 [deg]", fontsize=8)
        axes[used - 1, c].xaxis.set_tick_params(labelbottom=True)


def moving_points(res) -> list[int]:
    """Indices of the named points that move (the fixed pivots left out)."""
    fixed = {res.plan.point(p) for p in res.study.mechanism.fixed}
    return [i for i in range(res.plan.n_visible) if i not in fixed]


def kinematics_figure(res):
    """Small multiples against the crank angle: every link's angle, omega and
    eps (one row per link of the study's ``[output] links``) and every moving
    point's speed |v| and acceleration |a| with their x and y components (one
    row per point); the refined peaks marked.  Panels: links x 3 + points x 2.
    Returns the Figure."""
    study, plan, d = res.study, res.plan, res.dense
    crank = study.mechanism.crank
    phi = np.rad2deg(d.phi)
    v, a, om, ep = real_motion(d, crank.omega1, crank.eps1)
    labels = list(study.output.link_labels)
    pts = moving_points(res)
    nrows = max(len(labels), len(pts), 1)
    fig = plt.figure(figsize=(16, 1.25 * nrows + 1.3), layout="constrained")
    left, right = fig.subfigures(1, 2, width_ratios=[3, 2]) if labels else (None, fig)
    peaks = {(p.quantity, p.item): p for p in res.peaks or ()}
    ticks = np.arange(-720, 721, 90)
    ticks = ticks[(ticks >= min(phi.min(), phi.max())) & (ticks <= max(phi.min(), phi.max()))]

    def peak_mark(ax, peak, sign, unit):
        """The refined peak: a red dot and its value on a white ground (no curve
        strikes it through), placed where it covers no other text."""
        frac = (peak.phi1 - phi[0]) / (phi[-1] - phi[0]) if phi[-1] != phi[0] else 0.0
        right = frac > 0.7
        mark_peak(ax, peak.phi1, sign * peak.value, what=ax.get_label())
        ann = ax.annotate(f"peak {peak.value:.4g} {unit}\nat {peak.phi1:.2f} deg",
                          (peak.phi1, sign * peak.value), textcoords="offset points",
                          xytext=(0, 0), fontsize=6.5, color="C3",
                          bbox=dict(boxstyle="square,pad=0.1", fc="white", ec="none", alpha=0.85))
        inward = -1 if right else 1
        down = -1 if sign > 0 else 1
        placer(ax).add(ann, ((5 * inward, 4 * down, "right" if right else "left",
                              "top" if sign > 0 else "bottom"),
                             (-5 * inward, 4 * down, "left" if right else "right",
                              "top" if sign > 0 else "bottom"),
                             (5 * inward, -4 * down, "right" if right else "left",
                              "bottom" if sign > 0 else "top")))

    def panel(ax, label, title, peak=None, unit="", signed=True):
        ax.set_label(label)
        ax.set_title(title, fontsize=8, loc="left", pad=2)
        ax.grid(alpha=0.3)
        ax.tick_params(labelsize=7)
        ax.set_xticks(ticks)
        if crank.rot < 0 and not ax.xaxis_inverted():
            ax.invert_xaxis()
        y = ax.get_lines()[0].get_ydata()
        # what the peak is of: the curve, or the magnitude of an x, y pair; a constant
        # one (the uniform crank's omega and eps) has no peak to show
        shown = y if signed else np.hypot(*[ln.get_ydata() for ln in ax.get_lines()[:2]])
        if peak is not None and not is_constant(shown):
            k = int(np.argmin(np.abs(phi - peak.phi1)))
            sign = -1.0 if signed and np.isfinite(y[k]) and y[k] < 0 else 1.0
            peak_mark(ax, peak, sign, unit)

    if labels:
        axes = left.subplots(nrows, 3, sharex=True, squeeze=False)
        for j, lab in enumerate(labels):
            series = [(_angle_deg(d.links[:, j, 0]), "angle", "[deg]", None),
                      (om[:, j], "omega", "[1/s]", peaks.get(("omega", lab))),
                      (ep[:, j], "eps", "[1/s²]", peaks.get(("eps", lab)))]
            for c, (y, what, unit, pk) in enumerate(series):
                ax = axes[j, c]
                ax.plot(phi, y, "k-", lw=1.0)
                not_computed(ax, y, study)
                panel(ax, f"link {lab} {what}", f"{link_name(study, lab)}: {what} {unit}", pk,
                      unit.strip("[]"))
        trim_rows(axes, len(labels))
        left.suptitle(f"Links: angle, omega, eps (omega1 = {crank.omega1:g} rad/s, "
                      f"eps1 = {crank.eps1:g} rad/s²)", fontsize=10)
    if pts:
        axes = right.subplots(nrows, 2, sharex=True, squeeze=False)
        for r, i in enumerate(pts):
            name = plan.point_names[i]
            for c, (arr, what, unit) in enumerate(((v, "velocity", "m/s"),
                                                    (a, "acceleration", "m/s²"))):
                ax = axes[r, c]
                ax.plot(phi, arr[:, i, 0], "-", color="C0", lw=0.7, label="x")
                ax.plot(phi, arr[:, i, 1], "-", color="C1", lw=0.7, label="y")
                mag = np.hypot(arr[:, i, 0], arr[:, i, 1])
                ax.plot(phi, mag, "k-", lw=1.1, label="|.|")
                not_computed(ax, mag, study)
                panel(ax, f"point {name} {what}", f"{name}: {what} [{unit}]",
                      peaks.get((what, name)), unit, signed=False)
                if r == 0 and c == 0:
                    ax.legend(fontsize=6.5, ncol=3, loc="lower left", handlelength=1.2)
        trim_rows(axes, len(pts))
        right.suptitle("Moving points: velocity and acceleration (x, y and magnitude)",
                       fontsize=10)
    fig.suptitle(f"{study.title}: kinematics against the crank angle (red: refined peaks)",
                 fontsize=11)
    return fig
