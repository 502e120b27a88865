"""The picture of a scene's joint friction (``friction_figure``, `pipeline run`'s
<name>_friction.png): the power each joint and slide loses against the crank
angle, with their total and its mean over the revolution, and each pin's
bearing p*v against the study's ``pv_max``.  The numbers come from
``solve.friction`` (``FrictionForces``)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from .labels import is_constant, mark_peak
from .plots import joint_descriptions, outside_legend


def friction_figure(res):
    """Loss per joint and slide over phi1 (W), and p*v per pin over phi1
    against pv_max (MPa*m/s).  Returns the Figure."""
    fr = res.dense.forces.friction
    crank = res.study.mechanism.crank
    phi = np.rad2deg(res.dense.phi)
    nj = len(fr.spec.pins)
    where = dict(zip(res.plan.joint_names, joint_descriptions(res.plan)))
    fig = plt.figure(figsize=(11, 6.5), layout="constrained")
    ax = fig.add_subplot(2, 1, 1)
    ax.set_label("friction loss")
    for e, name in enumerate(fr.element_names):
        ax.plot(phi, fr.loss[:, e], lw=0.9, label=where.get(name, name))   # slide[...]
    total = fr.total_loss
    ax.plot(phi, total, "k", label="total")
    mean = fr.mean_loss()
    if np.isfinite(mean):
        ax.axhline(mean, color="k", ls=":", lw=0.9,
                   label=f"mean {mean:.4g} W over the revolution")
    if np.isfinite(total).any() and not is_constant(total):
        k = int(np.nanargmax(total))
        mark_peak(ax, phi[k], total[k], colour="k", ms=3, what="total loss")
    ax.set_ylabel("friction loss [W]")
    ax.grid(alpha=0.3)
    outside_legend(ax, ncol=2 if len(fr.element_names) > 8 else 1)
    ax.set_title(f"Power lost in the joints' friction at omega1 = {crank.omega1:g} rad/s "
                 f"(f = {fr.spec.revolute:g} at the pins"
                 + (f", {fr.spec.slide:g} at the slides)" if fr.force.shape[1] else ")"),
                 fontsize=10)
    ax2 = fig.add_subplot(2, 1, 2, sharex=ax)
    ax2.set_label("bearing p*v")
    pv = fr.pv
    for j, (name, d, length) in enumerate(fr.spec.pins):
        line, = ax2.plot(phi, pv[:, j], lw=0.9, label=f"{name} (d {d:g} mm, l {length:g} mm)")
        if np.isfinite(pv[:, j]).any() and not is_constant(pv[:, j]):
            k = int(np.nanargmax(pv[:, j]))
            mark_peak(ax2, phi[k], pv[k, j], colour=line.get_color(), ms=3, what=f"p*v {name}")
    if fr.spec.pv_max is not None:
        ax2.axhline(fr.spec.pv_max, color="C3", ls="--", lw=1.0,
                    label=f"pv_max {fr.spec.pv_max:g} MPa·m/s")
    ax2.set_ylabel("p*v [MPa·m/s]")
    ax2.set_xlabel("crank angle phi1 [deg]")
    ax2.grid(alpha=0.3)
    outside_legend(ax2, ncol=2 if nj > 8 else 1)
    ax2.set_title("Plain bearings: p*v = |R| / (d l) x |omega_rel| d / 2 per pin", fontsize=9)
    if crank.rot < 0:
        ax.invert_xaxis()
    return fig
