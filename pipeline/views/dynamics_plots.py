"""The crank's own picture of a dynamics case (``eps1_figure``, shown as
``pipeline.views.plots.eps1_figure``): eps1 against phi1."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np


def eps1_figure(case):
    """The crank's angular acceleration eps1 against its angle phi1 for one
    dynamics case (pipeline.solve.crank_motion.CaseResult): the samples coloured by time
    (colour key), the fine record of the last seconds (every step) on top.
    A rotating crank is shown over one revolution (phi1 mod 360 deg).
    Returns the Figure."""
    from ..solve.crank_motion import TAIL_SECONDS
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
    ax.set_ylabel("eps1 [rad/s$^2$]")
    if rotating:
        ax.set_xlim(0, 360)
        ax.set_xticks(np.arange(0, 361, 45))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    head = f"{case.name}: eps1 against phi1, M1 = {c.M1.text} N m, b = {c.damping:g} N m s"
    if s is not None:
        tail = case.tail_eps1
        head += (f"\nsteady rotation at {s['omega_mean']:.4g} rad/s: eps1 from "
                 f"{np.min(tail):.4g} to {np.max(tail):.4g} rad/s$^2$ over the last "
                 f"{TAIL_SECONDS:g} s")
    else:
        o = case.oscillation()
        if o is not None:
            head += f"\noscillation about {o['phi_mid_deg']:.2f} deg"
    ax.set_title(head, fontsize=10)
    return fig
