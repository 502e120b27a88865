"""Pictures a designer wants to see.  Every function takes computed results and
returns a matplotlib Figure: saving it (``files.save_figure``) or showing it
is the caller's choice.  The backend is the caller's too: the command line
chooses Agg, a notebook keeps its own."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from .scene import real_motion


def _links_to_draw(plan, study):
    """Segments to draw: every group's links, from the mechanism declaration."""
    m = study.mechanism
    segs = [(m.crank.pivot, m.crank.tip)]
    from .model import RRR, RRP, RPR, ClassIII, Attach
    for g in m.groups:
        if isinstance(g, RRR):
            segs += [(g.A, g.B), (g.C, g.B)]
        elif isinstance(g, RRP):
            segs += [(g.A, g.B)]
        elif isinstance(g, RPR):
            segs += [(g.pivot, g.guide_end)]
        elif isinstance(g, ClassIII):
            p3, p4, p5 = g.joints
            segs += [(g.input, p3), (p3, p4), (p4, p5), (p5, p3), (g.pivot_4, p4), (g.pivot_5, p5)]
        elif isinstance(g, Attach):
            if g.along:
                segs += [(g.base, g.point)]
                if g.base not in g.along:
                    segs += [(g.along[0], g.point)]
    return [(plan.point(a), plan.point(b)) for a, b in segs]


def draw_positions(ax, res, curves, highlight=None):
    """The mechanism at every position of ``curves`` and its points' paths."""
    plan, study = res.plan, res.study
    segs = _links_to_draw(plan, study)
    nv = plan.n_visible
    fixed = [plan.point(p) for p in study.mechanism.fixed]
    n = curves.pos.shape[0]
    cmap = plt.get_cmap("viridis")
    for k in range(n):
        col = cmap(k / max(n - 1, 1))
        lw, alpha = (2.4, 1.0) if k == highlight else (1.0, 0.55)
        for a, b in segs:
            ax.plot(curves.pos[k, [a, b], 0], curves.pos[k, [a, b], 1], "-", color=col, lw=lw,
                    alpha=alpha)
    dense = res.dense.pos
    for i in range(nv):
        if i in fixed:
            continue
        ax.plot(dense[:, i, 0], dense[:, i, 1], ":", color="0.35", lw=0.8)
    for i in range(nv):
        x, y = curves.pos[0, i]
        if not np.isfinite(x):
            continue
        ax.plot(x, y, "s" if i in fixed else "o", color="k", ms=5 if i in fixed else 3)
        ax.annotate(plan.point_names[i], (x, y), textcoords="offset points", xytext=(4, 4),
                    fontsize=8)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.grid(alpha=0.3)


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
    ax.set_title(f"{study.title}\n{table.pos.shape[0] - 1} positions, dotted: point paths "
                 f"(working point {wp})", fontsize=10)
    d = res.dense
    phi = np.rad2deg(d.phi)
    v, a, _, _ = real_motion(d, crank.omega1, crank.eps1)
    disp = d.pos[:, iwp] - d.pos[0, iwp]
    rows = [(disp, "displacement [mm]"), (v[:, iwp], "velocity [m/s]"),
            (a[:, iwp], "acceleration [m/s$^2$]")]
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
    crank = res.study.mechanism.crank
    phi = np.rad2deg(res.dense.phi)
    fig = plt.figure(figsize=(13, 5.5), layout="constrained")
    gs = fig.add_gridspec(2, 2, width_ratios=[1.6, 1])
    ax = fig.add_subplot(gs[0, 0])
    mag = np.hypot(fr.R[:, :, 0], fr.R[:, :, 1])
    for j, name in enumerate(fr.joint_names):
        ax.plot(phi, mag[:, j], label=name)
    ax.set_ylabel("|R| [N]")
    ax.legend(fontsize=8, ncol=4)
    ax.grid(alpha=0.3)
    ax.set_title(f"Joint reactions at omega1 = {crank.omega1:g} rad/s", fontsize=10)
    ax2 = fig.add_subplot(gs[1, 0], sharex=ax)
    ax2.plot(phi, fr.M_bal, "k")
    ax2.set_ylabel("M_bal [N m]")
    ax2.set_xlabel("crank angle phi1 [deg]")
    ax2.grid(alpha=0.3)
    if crank.rot < 0:
        ax.invert_xaxis()
    j = int(np.nanargmax(np.nanmax(mag, axis=0)))
    axp = fig.add_subplot(gs[:, 1])
    rx, ry = fr.R[:, j, 0], fr.R[:, j, 1]
    axp.plot(np.append(rx, rx[0]), np.append(ry, ry[0]), "-", color="C3")
    axp.plot([0], [0], "k+")
    k = int(np.nanargmax(mag[:, j]))
    axp.annotate(f"max {mag[k, j]:.1f} N\nat {phi[k]:.0f} deg", (rx[k], ry[k]), fontsize=8)
    axp.set_aspect("equal", adjustable="datalim")
    axp.set_xlabel("Rx [N]")
    axp.set_ylabel("Ry [N]")
    axp.grid(alpha=0.3)
    axp.set_title(f"Polar diagram of {fr.joint_names[j]} (most loaded joint)", fontsize=10)
    return fig

