"""The pictures of the crank's motion: a dynamics case over time
(``dynamics_figure``), eps1 against phi1 (``eps1_figure``, shown as
``pipeline.views.plots.eps1_figure``) and the reduced dynamics
(``reduced_figure``).  The motion itself is computed by
``pipeline.solve.crank_motion``."""

from __future__ import annotations

import math
import warnings

import matplotlib.pyplot as plt
import numpy as np

from ..kernels import config as kc
from ..solve.crank_motion import STATUS_NAMES, TAIL_SECONDS
from ..base.units import unit_text

BAND_WINDOW_S = 0.1     # s: the time window of a drawn band (a long series' min and max in it)


def eps1_figure(case):
    """The crank's angular acceleration eps1 against its angle phi1 for one
    dynamics case (pipeline.solve.crank_motion.CaseResult): the samples coloured by time
    (colour key), the fine record of the last seconds (every step) on top.
    A rotating crank is shown over one revolution (phi1 mod 360 deg).
    Returns the Figure."""
    c = case.case
    s = case.steady()
    rotating = s is not None or np.ptp(case.phi1) >= 2.0 * math.pi
    fig, ax = plt.subplots(figsize=(9.5, 5.6), layout="constrained")
    ax.set_label("eps1 against phi1")

    def x_of(phi):
        deg = np.rad2deg(phi)
        return np.mod(deg, 360.0) if rotating else deg

    sc = ax.scatter(x_of(case.phi1), case.eps1, c=case.t, s=4, cmap="plasma", lw=0,
                    label=f"every {c.sample_dt:g} s")
    cb = fig.colorbar(sc, ax=ax, pad=0.01)
    cb.set_label("time t [s]")
    cb.ax.set_label("time key")
    if case.tail_t.size:
        xt = x_of(case.tail_phi1)
        yt = np.array(case.tail_eps1, float)
        if rotating:       # no line across the wrap from 360 to 0 deg
            cut = np.flatnonzero(np.abs(np.diff(xt)) > 180.0) + 1
            xt, yt = np.insert(xt, cut, np.nan), np.insert(yt, cut, np.nan)
        ax.plot(xt, yt, "-", color="k", lw=0.7,
                label=f"last {min(TAIL_SECONDS, c.t_end):g} s (every step)")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xlabel("crank angle phi1 [deg]" + (" (mod 360)" if rotating else ""))
    ax.set_ylabel("eps1 [rad/s²]")
    if rotating:
        ax.set_xlim(0, 360)
        ax.set_xticks(np.arange(0, 361, 45))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    head = f"{case.name}: eps1 against phi1, M1 = {c.M1.text} N·m, b = {c.damping:g} N·m·s"
    if s is not None:
        tail = case.tail_eps1
        head += (f"\nsteady rotation at {s['omega_mean']:.4g} rad/s: eps1 from "
                 f"{np.min(tail):.4g} to {np.max(tail):.4g} rad/s² over the last "
                 f"{TAIL_SECONDS:g} s")
    else:
        o = case.oscillation()
        if o is not None:
            head += f"\noscillation about {o['phi_mid_deg']:.2f} deg"
    ax.set_title(head, fontsize=10)
    return fig


def dynamics_figure(case):
    """phi1(t), omega1(t), eps1(t) and omega1 against phi1 (mod 360 deg for a
    rotation); the title gives the coefficient of non-uniformity.  Returns the
    Figure."""
    c = case.case
    s = case.steady()
    o = None if s is not None else case.oscillation()
    head = f"{case.name}: M1 = {c.M1.text} N·m, b = {c.damping:g} N·m·s, {case.method}"
    if s is not None:
        head += (f"\nsteady rotation: omega_mean = {s['omega_mean']:.4g} rad/s "
                 f"({s['rpm']:.0f} rpm), coefficient of non-uniformity "
                 f"delta = {s['delta']:.4g} (last {s['revolutions']} revolutions)")
    elif o is not None:
        head += (f"\noscillation about {o['phi_mid_deg']:.2f} deg, amplitude "
                 f"{o['amplitude_deg']:.3g} deg, period {o['period_s']:.4g} s")
    if case.status != kc.OK:
        head += f"\nstopped: {STATUS_NAMES[case.status]}"
    fig, axs = plt.subplots(2, 2, figsize=(12, 7.5), layout="constrained")
    rows = [(np.rad2deg(case.phi1), None, "phi1 [deg]"),
            (case.omega1, case.tail_omega1, "omega1 [rad/s]"),
            (case.eps1, case.tail_eps1, "eps1 [rad/s²]")]
    for ax, (y, fine, label) in zip((axs[0, 0], axs[0, 1], axs[1, 0]), rows):
        if fine is None:
            ax.plot(case.t, y, lw=0.8, label=f"every {c.sample_dt:g} s")
        else:
            # a fast rotation over many seconds: drawn sample by sample it is a solid
            # block (and the samples alias it); the band of its min and max per column
            # keeps every extreme and shows how the swing grows
            _band(ax, case.t, y, "C0", f"every {c.sample_dt:g} s: min to max, mean dashed")
            if fine.size:
                _band(ax, case.tail_t, fine, "C3", "every step: min to max, mean dashed")
            ax.legend(fontsize=8, loc="best")
        ax.set_xlabel("t [s]")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    ax = axs[1, 1]
    rotating = s is not None
    phi_s = np.rad2deg(case.phi1)
    phi_t = np.rad2deg(case.tail_phi1)
    if rotating:
        # the steady rotation (every step of the last seconds) as a line per turn; the
        # run-up's sparse samples mod 360 deg would be a cloud (omega1(t) shows them)
        xt, yt = np.mod(phi_t, 360.0), np.asarray(case.tail_omega1, float)
        cut = np.flatnonzero(np.abs(np.diff(xt)) > 180.0) + 1
        ax.plot(np.insert(xt, cut, np.nan), np.insert(yt, cut, np.nan), "-", lw=0.6,
                color="C3", label=f"last {TAIL_SECONDS:g} s (every step)")
        ax.axhline(s["omega_mean"], color="0.3", lw=0.8, ls="--",
                   label=f"omega_mean {s['omega_mean']:.4g} rad/s")
        ax.set_xlim(0, 360)
    else:
        ax.plot(phi_s, case.omega1, lw=0.6, label="samples")
    ax.set_xlabel("phi1 [deg]" + (" (mod 360)" if rotating else ""))
    ax.set_ylabel("omega1 [rad/s]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.suptitle(head, fontsize=10)
    return fig


def _band(ax, t, y, colour, label, window=BAND_WINDOW_S):
    """A long series drawn legibly: per ``window`` seconds (a few turns of a
    fast crank) its minimum and maximum as the band's edges (every extreme
    kept) and its mean as a line; a short series as the line itself."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    columns = max(1, int(np.ceil(np.ptp(t) / window))) if t.size else 1
    if t.size <= 4 * columns:
        ax.plot(t, y, lw=0.6, color=colour, label=label.split(":")[0])
        return
    edges = np.linspace(0, t.size, columns + 1).astype(int)
    spans = list(zip(edges[:-1], edges[1:]))
    tc = np.array([t[a:b].mean() for a, b in spans])
    with warnings.catch_warnings():     # a span with no motion (a stopped or refused case)
        warnings.simplefilter("ignore", RuntimeWarning)
        lo = np.array([np.nanmin(y[a:b]) for a, b in spans])
        hi = np.array([np.nanmax(y[a:b]) for a, b in spans])
        mid = np.array([np.nanmean(y[a:b]) for a, b in spans])
    ax.fill_between(tc, lo, hi, color=colour, alpha=0.2, lw=0, label=label)
    ax.plot(tc, lo, lw=0.7, color=colour)
    ax.plot(tc, hi, lw=0.7, color=colour)
    ax.plot(tc, mid, lw=0.9, color=colour, ls="--")


def reduced_figure(red):
    """J(phi), (1/2) dJ/dphi and Q(phi) against the crank angle, the equilibria
    marked.  Returns the Figure."""
    fig, axes = plt.subplots(3, 1, figsize=(8, 7.5), sharex=True, layout="constrained")
    deg = np.degrees(red.phi)
    for ax, y, label in zip(axes, (red.J, red.half_dJ, red.Q),
                            ("J [kg·m²]", "(1/2) dJ/dphi [kg·m²]", "Q [N·m] (without M1)")):
        ax.plot(deg, y, "k-", lw=1.2)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        for p, st in red.equilibria:
            ax.axvline(p, color="C2" if st else "C3", lw=1, ls="--")
    axes[2].axhline(0.0, color="0.5", lw=0.8)
    axes[-1].set_xlabel("crank angle phi1 [deg]")
    axes[-1].set_xlim(0, 360)
    fig.suptitle("Reduced dynamics of the crank; equilibria: " + (", ".join(
        f"{p:.2f} deg ({'stable' if st else 'unstable'})" for p, st in red.equilibria)
        or "none"), fontsize=10)
    return fig


def motion_forces_figure(name, records, constant):
    """The kinetostatics along a dynamics case's motion beside the constant
    speed's (``pipeline.solve.motion_forces``): the peak |R| of every joint
    (constant speed, the whole case's samples, the steady rotation), and
    over the crank angle the largest joint's |R| and the balancing moment of
    the steady rotation (every step) against the constant-speed curves.
    ``records``: {"samples"[, "steady"]: MotionForces}; ``constant``: the
    scene's Reactions at constant speed (or None).  Returns the Figure."""
    fig, axs = plt.subplots(1, 3, figsize=(15, 5.2), layout="constrained")
    rec = records.get("steady") or records["samples"]
    joints = list(rec.forces.joint_names)
    x = np.arange(len(joints))
    bars = []
    if constant is not None:
        bars.append(("constant speed", [p[1] for p in constant.peaks()], "0.6"))
    bars.append(("whole case (samples)", [p[1] for p in records["samples"].peaks()], "C0"))
    if "steady" in records:
        bars.append(("steady rotation (every step)", [p[1] for p in records["steady"].peaks()],
                     "C3"))
    width = 0.8 / len(bars)
    ax = axs[0]
    ax.set_label("peak reactions")
    for i, (label, vals, colour) in enumerate(bars):
        ax.bar(x + (i - (len(bars) - 1) / 2) * width, vals, width, label=label, color=colour)
    ax.set_xticks(x, joints)
    ax.set_ylabel("peak |R| [N]")
    ax.set_title("peak joint reactions", fontsize=10)
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=1)
    peaks = rec.peaks()
    j = max(range(len(peaks)), key=lambda i: peaks[i][1]) if peaks else 0
    rotating = rec.record == "steady"

    def angle(phi):
        deg = np.rad2deg(phi)
        return np.mod(deg, 360.0) if rotating else deg

    for ax, y, y0, label, what in (
            (axs[1], rec.forces.magnitude[:, j],
             None if constant is None else constant.magnitude[:, j],
             f"|{joints[j]}| [N]", f"reaction {joints[j]}"),
            (axs[2], rec.forces.M_bal, None if constant is None else constant.M_bal,
             f"M_bal [{unit_text('N*m')}]", "balancing moment")):
        ax.set_label(what)
        ax.plot(angle(rec.phi1), y, ".", ms=1.5, color="C3",
                label="along the motion" + (" (steady rotation)" if rotating else ""))
        if y0 is not None:
            order = np.argsort(np.mod(np.rad2deg(constant.phi), 360.0))
            ax.plot(np.mod(np.rad2deg(constant.phi), 360.0)[order], y0[order], "-", lw=1.0,
                    color="0.3", label="constant speed")
        ax.set_xlabel("crank angle phi1 [deg]" + (" (mod 360)" if rotating else ""))
        ax.set_ylabel(label)
        if rotating:
            ax.set_xlim(0, 360)
            ax.set_xticks(np.arange(0, 361, 60))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)
        ax.set_title(what, fontsize=10)
    fig.suptitle(f"{name}: forces under the real crank motion (omega1(t), eps1(t)) against "
                 "the constant speed", fontsize=11)
    return fig
