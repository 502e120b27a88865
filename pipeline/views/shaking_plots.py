"""The picture of the shaking force and moment on the frame (``shaking_figure``):
against the crank angle, and the shaking force's polar diagram drawn as the
reactions' is (``plots.forces_figure``), with the crank's counterweight
(``solve.shaking``) beside it.  The numbers come from
``solve.reactions.scene_forces`` (``kernels.forces.shaking``)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from .labels import is_constant, mark_peak
from ..base.units import unit_text
from .plots import _travel_arrows, outside_legend, polar_marks


def shaking_figure(res):
    """Shaking force (x, y, magnitude) and moment against phi1, and the polar
    diagram of the shaking force, with the counterweight's where the scene has
    one.  Returns the Figure."""
    fr = res.dense.forces
    crank = res.study.mechanism.crank
    cw = res.counterweight
    phi = np.rad2deg(res.dense.phi)
    F, M = fr.shaking[:, :2], fr.shaking[:, 2]
    mag = fr.shaking_magnitude
    fig = plt.figure(figsize=(13, 5.5), layout="constrained")
    gs = fig.add_gridspec(2, 2, width_ratios=[1.45, 1])
    ax = fig.add_subplot(gs[0, 0])
    ax.plot(phi, F[:, 0], lw=0.9, label="Fx")
    ax.plot(phi, F[:, 1], lw=0.9, label="Fy")
    ax.plot(phi, mag, "k", label="|F|")
    if np.isfinite(mag).any() and not is_constant(mag):
        k = int(np.nanargmax(mag))
        mark_peak(ax, phi[k], mag[k], colour="k", ms=3, what="|F|")
    if cw is not None:
        ax.plot(phi, np.hypot(cw.force_after[:, 0], cw.force_after[:, 1]), "--", color="C3",
                label="|F| with the counterweight")
    ax.set_ylabel("shaking force [N]")
    outside_legend(ax)
    ax.grid(alpha=0.3)
    ax.set_title(f"Shaking force on the frame: sum of -m a_S (gravity and loads apart), "
                 f"omega1 = {crank.omega1:g} rad/s", fontsize=10)
    ax2 = fig.add_subplot(gs[1, 0], sharex=ax)
    ax2.plot(phi, M, "k")
    ax2.set_ylabel(f"M about {fr.shaking_about} [N·m]")
    ax2.set_xlabel("crank angle phi1 [deg]")
    ax2.grid(alpha=0.3)
    ax2.set_title(f"Shaking moment on the frame about the crank's pivot {fr.shaking_about}",
                  fontsize=9)
    if crank.rot < 0:
        ax.invert_xaxis()
    axp = fig.add_subplot(gs[:, 1])
    _polar(axp, phi, F, "C0", "without a counterweight")
    if cw is not None:
        _polar(axp, phi, cw.force_after, "C3",
               f"with {cw.mass_radius:.4g} {unit_text('kg*mm')} at {cw.angle:.1f} deg from the "
               "crank")
    axp.plot([0], [0], "k+")
    axp.set_aspect("equal", adjustable="datalim")
    axp.set_xlabel("Fx [N]")
    axp.set_ylabel("Fy [N]")
    axp.grid(alpha=0.3)
    axp.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.12), borderaxespad=0.0)
    step = max(1, len(phi) // 12)
    axp.set_title("Polar diagram of the shaking force\narrows: direction as the crank turns;\n"
                  f"dots every {360 * step / len(phi):.0f} deg of phi1, labels in deg",
                  fontsize=9)
    return fig


def _polar(ax, phi, F, color, label):
    """One closed hodograph of the force F (n, 2), its peak marked."""
    fx, fy = F[:, 0], F[:, 1]
    ax.plot(np.append(fx, fx[0]), np.append(fy, fy[0]), "-", color=color, label=label)
    _travel_arrows(ax, F, color=color)
    polar_marks(ax, phi, fx, fy, color)
