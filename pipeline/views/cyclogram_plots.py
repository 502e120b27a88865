"""The machine's cyclogram (``cyclogram_figure``, shown as
``pipeline.views.plots.cyclogram_figure``): the design's phases inside, one
ring per organ of the study's ``[cycle]`` (or the required cycle given), each
phase error of the output organ marked.  What it draws is computed by
``pipeline.solve.cyclogram``."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np

from ..solve.cyclogram import BOUNDARIES, phase_key, scene_cyclogram


PHASE_COLOURS = {"dwell": "#9cc3e6", "forward": "#f6b26b", "back": "#93c47d",
                 "rise": "#f9cb9c", "fall": "#b6d7a8", "move": "#d5a6bd"}
RING = 0.14                 # radial thickness of a ring of phases (the rim is at r = 1)
RING_GAP = 0.035
ERROR_COLOUR = "C3"


def _tangent(theta_deg, direction):
    """Text rotation (deg) along a ring at the dial angle ``theta_deg`` (zero at
    the top, ``direction`` +1 counter-clockwise), kept upright."""
    rot = (direction * theta_deg) % 360.0
    return rot - 180.0 if 90.0 < rot <= 270.0 else rot


def _ring(ax, r0, phases, gid, label, direction, inch_per_r, name=None, strong=False,
          alpha=1.0):
    """One ring of phases between r0 and r0 + RING: a wedge per phase, (kind,
    start, end[, colour]) in deg of the dial, each with ``gid(kind)`` and
    ``label(kind, a, b)``, and its text along the ring where it fits (the
    ring's ``name`` in its longest phase)."""
    longest = max(range(len(phases)), key=lambda k: (phases[k][2] - phases[k][1]) % 360.0 or 360)
    for k, ph in enumerate(phases):
        kind, a, b = ph[0], float(ph[1]), float(ph[2])
        length = (b - a) % 360.0 or 360.0
        colour = (ph[3] if len(ph) > 3 and ph[3] else None) or PHASE_COLOURS.get(
            phase_key(kind), "0.85")
        bar = ax.bar(np.deg2rad(a), RING, width=np.deg2rad(length), bottom=r0, align="edge",
                     color=colour, ec="k", lw=1.4 if strong else 0.7, alpha=alpha)[0]
        bar.set_gid(gid(kind))
        bar.set_label(label(kind, a, b))
        # the text along the ring: as much as fits in the arc (about 0.5 em per character)
        mid = a + length / 2
        arc = np.deg2rad(length) * (r0 + RING / 2) * inch_per_r
        fs = 6.5
        for text in ([f"{name}: {_words(ph, a, b)}"] if k == longest and name else []) + [
                _words(ph, a, b), kind]:
            if len(text) * fs * 0.52 / 72 < 0.92 * arc:
                ax.text(np.deg2rad(mid), r0 + RING / 2, text, ha="center", va="center",
                        fontsize=fs, rotation=_tangent(mid, direction), rotation_mode="anchor")
                break


def _words(ph, a, b):
    """A phase's text on its wedge: 'dwell 240-30' (a design phase: its length)."""
    if len(ph) > 4:
        return ph[4]
    return f"{ph[0]} {_span(a, b)}"


def _span(a, b):
    """'240-30', '290-360': a phase's cycle angles (deg) as the thesis writes them."""
    a, b = a % 360.0, b % 360.0
    return f"{round(a, 6):g}-{round(b, 6) or 360:g}"


def cyclogram_figure(res, cycle=None, cycle_name="required cycle", turn=None):
    """The machine's circular cyclogram of one revolution (the dial turns the
    way the crank turns, phi1 on the rim), rings inside out:

    * the design's dwell, forward and back phases from its output motion (the
      dwell is the best window of the study's ``dwell`` length, where the design
      actually dwells; a window that moves more than DWELL_RESIDUAL of the range
      is "slowest", no dwell, and no dwell window is drawn);
    * the required cycle of the organ the output drives: ``cycle`` as (name,
      start, end[, colour]) in degrees of the cycle angle (e.g. the OV-7 cycle of
      DOMAIN.md section 9), else the study's [cycle] organ named by ``output``,
      else the phases of ``[output.motion_law]``, if any;
    * the machine's other organs of the study's [cycle] (needle, sinker,
      presser of the OV-7), on the same cycle angle.

    The cycle is turned so that the required dwell starts where the design's
    does (as the crank's mounting phase would align it), or by ``turn``
    degrees of crank travel (held fixed); each boundary of the output's phases
    is marked with its phase error, actual - required (``solve.cyclogram``).
    The output motion itself is the radial trace inside.  Wedges carry the gid
    'phase design NAME', 'phase cycle NAME' (the output organ's) or 'phase
    organ' (the other organs'), and the label 'ORGAN: KIND FROM-TO deg'; the
    error marks 'phase error BOUNDARY'.  Returns the Figure."""
    study = res.study
    if cycle is None and getattr(res, "cyclogram", None) is not None:
        cg = res.cyclogram
    else:
        cg = scene_cyclogram(res, cycle, cycle_name, turn)
    crank = study.mechanism.crank
    out_ring = cg.output_ring
    others = [r for r in cg.rings if not r.output]
    figw = 8.6 if not others else 10.0
    fig = plt.figure(figsize=(figw, figw * 1.17), layout="constrained")
    gs = fig.add_gridspec(2, 1, height_ratios=[1.0, 0.17])
    ax = fig.add_subplot(gs[0], projection="polar")
    ax.set_label("cyclogram")
    ax.set_theta_zero_location("N")
    direction = 1 if crank.rot > 0 else -1
    ax.set_theta_direction(direction)
    motion = cg.motion
    if motion is None:
        why = "the mechanism does not assemble over the whole revolution" \
            if res.dense.overall != 0 else "its output does not move"
        ax.text(0.5, 0.5, f"no cyclogram: {why}", transform=ax.transAxes, ha="center")
        ax.set_axis_off()
        return fig
    y, n = motion["y"], len(motion["y"])
    step = 360.0 / n
    tau = np.arange(n) * step
    phases, dwells = cg.design, cg.dwells
    r_design = 1.0 - RING
    rings_r = [1.0 + RING_GAP + k * (RING + RING_GAP) for k in range(len(cg.rings))]
    r_lim = (rings_r[-1] + RING if cg.rings else 1.0) + 0.04
    inch_per_r = 0.42 * figw / r_lim
    # the design's own phases
    design = []
    for name, a, length in phases:
        shown = name if name != "dwell" or dwells else "slowest"
        design.append((shown, a, a + length,
                       PHASE_COLOURS[name] if shown != "slowest" else "0.85",
                       f"{shown} {length:.0f} deg"))
    labels = {d[0]: d[4] for d in design}
    _ring(ax, r_design, design, lambda k: f"phase design {'dwell' if k == 'slowest' else k}",
          lambda k, a, b: f"design: {labels[k]}" + (
              "" if k != "slowest" else f" (moves {100 * motion['error']:.0f} % of its range: "
                                        "no dwell)"), direction, inch_per_r, strong=True)
    # the required rings, on the cycle angle psi = tau - turn
    t = cg.turn
    for r0, ring in zip(rings_r, cg.rings):
        ph = [(p[0], float(p[1]) + t, float(p[2]) + t, p[3] if len(p) > 3 else None,
               f"{p[0]} {_span(float(p[1]), float(p[2]))}") for p in ring.phases]
        _ring(ax, r0, ph, (lambda k: f"phase cycle {k}") if ring.output else
              (lambda k: "phase organ"),
              lambda k, a, b, o=ring.organ: f"{o}: {k} {_span(a - t, b - t)} deg",
              direction, inch_per_r, name=ring.organ, alpha=0.8 if ring.output else 0.7)
    # the output motion: inside the rings, low values at the centre
    lo, hi = float(y.min()), float(y.max())
    r_lo, r_hi = 0.30, r_design - 0.16
    r = r_lo + (r_hi - r_lo) * (y - lo) / (hi - lo)
    ax.plot(np.deg2rad(np.append(tau, 360.0)), np.append(r, r[0]), "k-", lw=1.3,
            label=f"output: {motion['what']}")
    handles = [ax.get_lines()[-1]]
    if dwells:      # (a design that does not dwell has no dwell window to show)
        s, w = motion["start"], motion["w"]
        win = (s + np.arange(w + 1)) % n
        handles += ax.plot(np.deg2rad(s * step + np.arange(w + 1) * step), r[win], "-",
                           color="C3", lw=2.6, label="best dwell window")
    # each boundary's phase error: an arc from the required to the actual boundary
    table = []
    if cg.error is not None:
        r_mark = 1.0 + RING_GAP / 2
        for b, act, req, err in zip(BOUNDARIES, cg.actual, cg.required, cg.error):
            arc = np.deg2rad(np.linspace(act - err, act, 30))
            line, = ax.plot(arc, np.full(arc.shape, r_mark), "-", color=ERROR_COLOUR, lw=2.2,
                            solid_capstyle="butt", gid=f"phase error {b}")
            for edge in (act - err, act):
                ax.plot(np.deg2rad([edge, edge]), [r_design, rings_r[0] + RING], "-",
                        color=ERROR_COLOUR, lw=0.9)
            ax.text(np.deg2rad(act - err / 2), r_design - 0.07, f"{err:+.1f}", ha="center",
                    va="center", fontsize=7.5, color=ERROR_COLOUR, weight="bold",
                    rotation=_tangent(act - err / 2, direction), rotation_mode="anchor",
                    gid=f"phase error {b} text")
            table.append(f"{b:<14} {(act - t) % 360:6.1f} {(req - t) % 360:6.1f} {err:+7.1f}")
        handles.append(line)
        line.set_label(f"phase error of the design against {out_ring.organ} [deg]")
    # crank angles on the rim (phi1 of the study's revolution) and the turning direction
    marks = np.arange(0, 360, 30)
    ax.set_xticks(np.deg2rad(marks),
                  labels=[f"{round(math.degrees(crank.phi0) + crank.rot * m, 6):g}" for m in marks],
                  fontsize=8)
    ax.set_yticks([])
    ax.set_ylim(0, r_lim)
    ax.grid(alpha=0.35)
    ax.set_axisbelow(True)
    arc = np.deg2rad(np.linspace(-60, 60, 40))
    ax.plot(arc, np.full(arc.shape, 0.2), "-", color="C3", lw=1.2)
    ax.annotate("", xy=(arc[-1], 0.2), xytext=(arc[-4], 0.2),
                arrowprops=dict(arrowstyle="-|>", color="C3", lw=1.2, mutation_scale=12))
    ax.text(0, 0.06, "crank\nturns", color="C3", fontsize=7.5, ha="center", va="center")
    # the key: colours of the phases, the rings inside out, the errors
    from matplotlib.patches import Patch
    kinds = (["dwell"] if dwells else []) + ["forward", "back"]
    kinds += sorted({phase_key(p[0]) for ring in cg.rings for p in ring.phases} - set(kinds))
    handles += [Patch(fc=PHASE_COLOURS.get(k, "0.85"), ec="k", lw=0.6, label=k) for k in kinds]
    if not dwells:
        handles.append(Patch(fc="0.85", ec="k", lw=0.6, label="slowest (the design: no dwell)"))
    unit = motion["unit"]
    stroke = (getattr(res, "motion", None) or {}).get("stroke")
    rings = ", ".join(["design (its output's phases)"] + [
        f"{ring.organ}" + (" (required)" if ring.output else "") for ring in cg.rings])
    info = [f"output: {motion['what']}",
            f"range {hi - lo:.3g} {unit}; " + (
                f"in the best {motion['dwell_deg']:g} deg window it moves "
                if dwells else f"its slowest {motion['dwell_deg']:g} deg move ")
            + f"{100 * motion['error']:.2g} % of that" + (
                f"; stroke {stroke:.3g} mm" if stroke else ""),
            f"rings, inside out: {rings}"]
    if cg.rings:
        info.append(f"required phases in deg of the cycle angle psi = crank travel "
                    f"{-t:+g} deg" + (" (dwells aligned)" if cg.align == "best" else ""))
    if table:
        info += ["", f"{'boundary':<14} {'design':>6} {'req.':>6} {'error':>7}   (psi, deg)"] \
            + table
    elif cg.why and cg.rings:
        info.append(f"phase errors {cg.why}")
    # the key's two parts side by side, each as wide as its text (estimated at
    # 0.6 em per character of the 7 pt font), so neither covers the other
    labels = [h.get_label() for h in handles]
    ncol = 2 if 2 * max(map(len, labels)) + 2 * 8 + max(map(len, info)) < figw * 72 / 4.4 else 1
    wide_key = ncol * (max(map(len, labels)) * 0.55 + 6) * 7 / 72
    wide_info = max(map(len, info)) * 0.62 * 7 / 72
    parts = gs[1].subgridspec(1, 2, width_ratios=[wide_key, max(wide_info, 0.1)], wspace=0.0)
    key = fig.add_subplot(parts[0])
    key.set_label("cyclogram key")
    key.set_axis_off()
    key.legend(handles=handles, loc="upper left", fontsize=7, ncol=ncol, framealpha=0.9,
               borderaxespad=0.0)
    about = fig.add_subplot(parts[1])
    about.set_label("cyclogram notes")
    about.set_axis_off()
    about.text(1.0, 1.0, "\n".join(info), ha="right", va="top", fontsize=7,
               family="monospace", transform=about.transAxes, multialignment="left",
               bbox=dict(boxstyle="round", fc="white", ec="0.7", alpha=0.9))
    dwell_phi = round(math.degrees(crank.phi0) + crank.rot * phases[0][1], 6)
    where = (f"the design dwells from phi1 = {dwell_phi:g} deg for {phases[0][2]:g} deg"
             if dwells else f"no dwell: its slowest {phases[0][2]:g} deg start at phi1 = "
                            f"{dwell_phi:g} deg")
    ax.set_title(f"{study.title}\ncyclogram over one revolution (rim: crank angle phi1 [deg]); "
                 f"{where}", fontsize=10)
    return fig
