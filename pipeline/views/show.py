"""One candidate re-run as a scene and drawn (`pipeline show`): the design at
12 positions, its output motion over the OV-7 cyclogram and against the crank
angle, and its joint reactions."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..analysis.candidate import STATUS_HELP, CandidateRun, rerun_candidate
from ..base.files import check_output, save_figure
from ..kernels import config as kc
from ..results.storage import open_results

# OV-7 cyclogram of the eyelets, main-shaft angle in deg (DOMAIN.md section 9)
OV7_DWELL_START = 240.0
OV7_PHASES = (("dwell", 240.0, 390.0, "#cfe3f7"),
              ("swing forward", 30.0, 130.0, "#fbe3c8"),
              ("swing back", 130.0, 240.0, "#d9efd2"))


def _spans(a, b, period=360.0):
    """The interval [a, b] (0 < b - a <= period) as pieces inside [0, period]."""
    lo = a % period
    hi = lo + (b - a)
    if hi <= period:
        return [(lo, hi)]
    return [(lo, period), (0.0, hi - period)]


def _headroom(ax, values, frac=0.45):
    """Room above the curves for the legend."""
    lo, hi = float(np.nanmin(values)), float(np.nanmax(values))
    span = hi - lo if hi > lo else 1.0
    ax.set_ylim(lo - 0.05 * span, hi + frac * span)


def candidate_figure(run: CandidateRun, caption_extra=""):
    """The design at 12 positions, its output motion over the OV-7 cyclogram and
    against the crank angle, and its joint reactions against the crank angle.
    Returns the Figure."""
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    from .plots import draw_positions

    study, crank = run.study, run.study.mechanism.crank
    n = run.dense.phi.shape[0]
    phi = np.rad2deg(run.dense.phi)
    fig = plt.figure(figsize=(15, 9.5), layout="constrained")
    gs = fig.add_gridspec(3, 2, width_ratios=[1.0, 1.25])
    ax = fig.add_subplot(gs[:, 0])
    draw_positions(ax, run.scene, run.table, highlight=0)
    ax.set_title(f"{run.label}: {run.table.pos.shape[0]} positions (thick: phi1 = "
                 f"{np.rad2deg(run.table.phi[0]):g} deg), dotted: point paths", fontsize=10)
    if run.status != kc.OK:
        ax.text(0.5, 0.97, f"{kc.STATUS_NAMES.get(run.status, run.status)}: "
                f"{STATUS_HELP.get(run.status, '')}\nno position drawn past the failure",
                transform=ax.transAxes, ha="center", va="top", fontsize=9, color="C3",
                bbox=dict(boxstyle="round", fc="white", ec="C3", alpha=0.9))
    # the design's variables under the drawing, in columns (inside it they covered the
    # crank's circle)
    cells = [f"{nm} = {v:.2f} {u}" for nm, v, u in zip(run.names, run.x, run.units)]
    per_column = max(1, math.ceil(len(cells) / 3))          # three columns
    width = max(map(len, cells), default=0)
    rows = [cells[r::per_column] for r in range(per_column)]
    params = "\n".join("   ".join(c.ljust(width) for c in row).rstrip() for row in rows)
    ax.annotate(params, (0.5, 0.0), xycoords=ax.xaxis.label, xytext=(0, -6),
                textcoords="offset points", fontsize=8, family="monospace", ha="center",
                va="top", bbox=dict(boxstyle="round", fc="white", ec="0.7", alpha=0.9))

    ax1 = fig.add_subplot(gs[0, 1])
    ax2 = fig.add_subplot(gs[1, 1])
    ax3 = fig.add_subplot(gs[2, 1])
    delta = study.output.dwell_deg
    radius = study.sweep.stroke_radius
    caption = ""
    if np.isfinite(run.theta).all() and run.dwell_start >= 0:
        s, w = run.dwell_start, run.dwell_w
        step = 360.0 / n
        win = (s + np.arange(w + 1)) % n
        th = np.rad2deg(run.theta - run.theta[win].mean())
        lo, hi = th[win].min(), th[win].max()
        # cycle angle: the best window moved to start at 240 deg of the main shaft
        psi = (np.arange(n) * step - s * step + OV7_DWELL_START) % 360.0
        order = np.argsort(psi)
        xs = np.append(psi[order], 360.0)
        ys = np.append(th[order], th[order][0])
        for name, a, b, col in OV7_PHASES:
            for k, (x0, x1) in enumerate(_spans(a, b)):
                ax1.axvspan(x0, x1, color=col, alpha=0.8, lw=0, label=name if k == 0 else None)
        for k, (x0, x1) in enumerate(_spans(OV7_DWELL_START, OV7_DWELL_START + w * step)):
            ax1.add_patch(Rectangle((x0, lo), x1 - x0, hi - lo, fill=False, hatch="///",
                                    ec="C3", lw=1.0,
                                    label=f"best {delta:g} deg window: residual {hi - lo:.3g} deg"
                                    if k == 0 else None))
        ax1.plot(xs, ys, "k-", lw=1.4, label="theta")
        _headroom(ax1, th)
        ax1.set_xlim(0, 360)
        ax1.set_xticks(np.arange(0, 361, 30))
        ax1.set_xlabel("main-shaft cycle angle [deg] (motion shifted: best window at 240)")
        ax1.set_ylabel("theta - dwell position [deg]")
        sec = ax1.secondary_yaxis("right", functions=(lambda d: np.deg2rad(d) * radius,
                                                      lambda mm: np.rad2deg(mm / radius)))
        sec.set_ylabel("eyelet arc [mm]")
        ax1.legend(fontsize=7, ncol=2, loc="upper right")
        ax1.grid(alpha=0.3)
        ax1.set_title(f"Output motion over the OV-7 cyclogram: dwell error "
                      f"{run.dwell_error:.4g}, stroke {radius * np.ptp(run.theta):.2f} mm",
                      fontsize=10)
        shift = (OV7_DWELL_START - s * step) % 360.0
        start_phi = phi[s]
        caption = (f"Motion shown shifted by {shift:g} deg: the best {delta:g} deg dwell window, "
                   f"found at phi1 = {start_phi:g} deg, is aligned with the OV-7 dwell "
                   f"(240 -> {(OV7_DWELL_START + delta) % 360:g} deg of the main shaft), as the "
                   "crank mounting phase would align it.")
        ax2.plot(phi, th, "k-", lw=1.2)
        _headroom(ax2, th)
        for k in range(w):        # the best window, sample by sample (wraps at 360)
            a_, b_ = phi[win[k]], phi[win[k]] + crank.rot * step
            ax2.axvspan(min(a_, b_), max(a_, b_), color="C3", alpha=0.18, lw=0,
                        label="best dwell window" if k == 0 else None)
        ax2.set_xlabel("crank angle phi1 [deg]")
        ax2.set_ylabel("theta - dwell position [deg]")
        ax2.grid(alpha=0.3)
        ax2.legend(fontsize=7, loc="upper right")
        ax2.set_title("Output motion against the crank angle (as computed)", fontsize=10)
        if crank.rot < 0:
            ax2.invert_xaxis()
    else:
        what = kc.STATUS_NAMES.get(run.status, run.status)
        where = f" at phi1 = {run.fail_phi:g} deg" if math.isfinite(run.fail_phi) else ""
        ax1.text(0.5, 0.5, f"no dwell window: the design fails ({what}{where})",
                 ha="center", va="center", transform=ax1.transAxes)
        ax1.set_axis_off()
        if np.isfinite(run.theta).any():
            ax2.plot(phi, np.rad2deg(run.theta), "k-", lw=1.2)
            ax2.set_ylabel("theta - theta(phi1 = 0) [deg]")
            ax2.grid(alpha=0.3)
            if crank.rot < 0:
                ax2.invert_xaxis()
        if math.isfinite(run.fail_phi):
            ax2.axvline(run.fail_phi, color="C3", lw=1.5, label=f"{what}{where}")
            ax2.legend(fontsize=7, loc="upper right")
            if not np.isfinite(run.theta).any():
                ax2.set_xlim(0, crank.rot * 360.0)
        ax2.set_xlabel("crank angle phi1 [deg]")
        ax2.set_title("Output motion against the crank angle, up to the failure", fontsize=10)
    fr = run.dense.forces
    if fr is not None:
        mag = fr.magnitude
        for j, name in enumerate(fr.joint_names):
            ax3.plot(phi, mag[:, j], label=name, lw=1.1)
        j, k = np.unravel_index(int(np.nanargmax(mag)), mag.shape)[::-1]
        ax3.annotate(f"peak {mag[k, j]:.0f} N ({fr.joint_names[j]}, {phi[k]:g} deg)",
                     (phi[k], mag[k, j]), textcoords="offset points", xytext=(6, -4),
                     fontsize=8)
        ax3.set_ylabel("|R| [N]")
        _headroom(ax3, mag)
        ax3.legend(fontsize=7, ncol=len(fr.joint_names), loc="upper right")
        if crank.rot < 0:
            ax3.invert_xaxis()
        ax3.set_title(f"Joint reactions at omega1 = {crank.omega1:g} rad/s", fontsize=10)
    else:
        ax3.text(0.5, 0.5, "no force analysis (the design does not assemble over the whole "
                 "revolution)", ha="center", va="center", transform=ax3.transAxes)
        ax3.set_yticks([])
        ax3.set_xticks([])
    ax3.set_xlabel("crank angle phi1 [deg]")
    ax3.grid(alpha=0.3)
    fig.suptitle(f"{study.title}: {run.label} ({kc.STATUS_NAMES.get(run.status, run.status)})"
                 + (f" {caption_extra}" if caption_extra else ""), fontsize=11)
    if caption:
        fig.text(0.5, 0.0, caption, ha="center", va="bottom", fontsize=9, style="italic",
                 wrap=True)
        fig.get_layout_engine().set(rect=(0, 0.025, 1, 0.975))
    return fig


def default_show_output(path, index) -> Path:
    path = Path(path)
    tag = "reference" if index == "reference" else f"candidate{index}"
    return path.with_name(f"{path.stem}_{tag}.png")


def _picture_format(out: Path):
    """Refuse a picture name whose suffix matplotlib does not write (a results
    file's .h5, a page's .html), before anything is computed."""
    from matplotlib.backend_bases import FigureCanvasBase
    kinds = FigureCanvasBase.get_supported_filetypes()
    if out.suffix.lower().lstrip(".") not in kinds:
        raise ValueError(f"{out}: a picture is written as .png (or {', '.join(sorted(kinds))}); "
                         f"got {out.suffix or 'no suffix'!r}")


def show(path, cid, out=None) -> dict:
    """`pipeline show`: re-run a candidate and draw it; returns a summary."""
    from ..base.progress import ticking
    with ticking("show", after=0.2, say_done=False):     # a live line, soon
        return _show(path, cid, out)


def _show(path, cid, out):
    if out is not None:         # before the design is re-run: never over a results file
        out = check_output(out, inputs=(path,))
        _picture_format(out)
    run = rerun_candidate(path, cid)
    out = check_output(Path(out) if out else default_show_output(path, run.index),
                       inputs=(path,))
    with open_results(path, "sweep") as f:
        stored = None
        if run.index != "reference":
            stored = float(f["metrics/dwell_error"][run.index]) if "dwell_error" in f["metrics"] \
                else None
            st = int(f["candidates/status"][run.index])
        else:
            st = int(f["reference/status"][0])
    import matplotlib.pyplot as plt
    fig = candidate_figure(run)
    save_figure(fig, out, dpi=100)
    plt.close(fig)
    info = {"candidate": run.index, "status": kc.STATUS_NAMES.get(run.status, run.status),
            "stored status": kc.STATUS_NAMES.get(st, st), "picture": str(out)}
    if np.isfinite(run.dwell_error):
        info["dwell error"] = f"{run.dwell_error:.4g}" + (
            f" (stored {stored:.4g})" if stored is not None and np.isfinite(stored) else "")
    if run.dense.forces is not None:
        info["peak reaction"] = f"{np.nanmax(run.dense.forces.magnitude):.1f} N (the grid's)"
        info.update(refined_peak_reaction(path, run))
    return info


def refined_peak_reaction(path, run) -> dict:
    """The design's peak reaction refined between positions as its scene refines
    it (``analysis.refined``), beside the value `pipeline analyze` stored for it
    (fronts 1-3)."""
    from ..analysis.candidate import candidate_scene
    from ..analysis.refined import design_peaks
    scene, _, _ = candidate_scene(path, run.index)
    r = design_peaks(scene, ("peak_reaction",))
    if "peak_reaction" not in r.values:
        return {}
    joint = run.dense.forces.joint_names[int(r.values["peak_joint"])]
    text = (f"{r.values['peak_reaction']:.12g} N at {joint}, phi1 = {r.values['peak_phi']:.4f} "
            "deg (refined between positions, as the design's scene)")
    with open_results(path, "sweep") as f:
        g = f.get("analysis/refined")
        if run.index != "reference" and g is not None and "peak_reaction" in g:
            at = np.flatnonzero(g["index"][()] == run.index)
            if at.size:
                text += f"; stored by analyze {float(g['peak_reaction'][at[0]]):.12g} N"
    return {"refined peak reaction": text}
