"""The report's pictures that are rendered here, each a PNG data URI: the Pareto
plot (where the page has no explorer) and the hypervolume of an adaptive search.
The page draws its other charts itself (``views.charts``)."""

from __future__ import annotations

import base64
import io
import math

import numpy as np

from ..base.files import laid_out_once, literal_text
from ..base.units import unit_text

MAX_GREY = 60_000       # infeasible points drawn in the Pareto plot (seeded subsample)
MAX_FRONT_POINTS = 200_000


def _png(fig, dpi=100) -> str:
    import matplotlib.pyplot as plt
    buf = io.BytesIO()
    with literal_text(fig), laid_out_once(fig, dpi):
        fig.savefig(buf, format="png", dpi=dpi)
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def _letters(k):
    return [chr(ord("A") + i) if i < 26 else f"R{i}" for i in range(k)]


# ----------------------------------------------------------------- figures
def _plain_fmt(v, _pos=None):
    return f"{v:g}"


def _plain_2_5_fmt(v, _pos=None):
    """Minor log ticks: label only 2 and 5 times a power of ten."""
    if not v > 0:
        return ""
    lead = v / 10 ** math.floor(math.log10(v) + 1e-12)
    return f"{v:g}" if round(lead) in (2, 5) and abs(lead - round(lead)) < 1e-6 else ""


def _formatters():
    from matplotlib.ticker import FuncFormatter
    return FuncFormatter(_plain_fmt), FuncFormatter(_plain_2_5_fmt)


def pareto_figure(data, ana) -> str:
    import matplotlib.colors
    import matplotlib.pyplot as plt
    F, rank = data.F, ana.rank
    o = data.objectives
    _plain, _plain_2_5 = _formatters()
    fig, ax = plt.subplots(figsize=(10.5, 6.2), layout="constrained")
    finite = np.isfinite(F[:, :2]).all(axis=1) if F.shape[1] >= 2 else np.zeros(len(F), bool)
    if F.shape[1] < 2:
        ax.text(0.5, 0.5, "one objective: no Pareto plot", ha="center", transform=ax.transAxes)
        return _png(fig)
    x, y = F[:, 0], F[:, 1]
    logx = bool((x[finite] > 0).all()) and finite.any()
    logy = bool((y[finite] > 0).all()) and finite.any()
    rng = np.random.default_rng(data.seed)
    grey = np.flatnonzero(finite & (rank == 0))
    if grey.size > MAX_GREY:
        grey = np.sort(rng.choice(grey, MAX_GREY, replace=False))
    if grey.size:
        ax.scatter(x[grey], y[grey], s=3, c="0.75", lw=0, rasterized=True,
                   label=f"infeasible ({int((finite & (rank == 0)).sum())} with both "
                         "objectives)")
    feas = np.flatnonzero(rank > 1)
    if feas.size > MAX_FRONT_POINTS:
        feas = np.sort(rng.choice(feas, MAX_FRONT_POINTS, replace=False))
    nf = int(rank.max(initial=0))
    if feas.size:
        sc = ax.scatter(x[feas], y[feas], s=4, c=rank[feas], cmap="viridis_r", lw=0,
                        norm=matplotlib.colors.LogNorm(vmin=2, vmax=max(nf, 3)),
                        rasterized=True, alpha=0.8, label="feasible, fronts 2 ...")
        cb = fig.colorbar(sc, ax=ax, pad=0.01)
        cb.set_label("Pareto front (rank)")
        ticks = [t for t in (2, 3, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000)
                 if t <= max(nf, 3)]
        cb.set_ticks(ticks, labels=[str(t) for t in ticks])
        cb.ax.minorticks_off()
    f1 = ana.front1
    if f1.size:
        ax.plot(x[f1], y[f1], "-", color="C3", lw=1.2, zorder=4)
        ax.scatter(x[f1], y[f1], s=28, color="C3", ec="k", lw=0.5, zorder=5,
                   label=f"front 1 ({f1.size} designs)")
    reps = ana.representatives
    for lab, i in zip(_letters(len(reps)), reps):
        ax.annotate(lab, (x[i], y[i]), textcoords="offset points", xytext=(6, 6), fontsize=10,
                    weight="bold", color="C3", zorder=7)
    if ana.knee >= 0:
        ax.scatter([x[ana.knee]], [y[ana.knee]], s=140, marker="D", facecolor="none",
                   ec="k", lw=1.6, zorder=6, label=f"knee (#{data.id(ana.knee)})")
    ro = np.asarray(ana.reference.get("objectives", [np.nan, np.nan]), float)
    if ro.size >= 2 and np.isfinite(ro[:2]).all():
        ax.scatter([ro[0]], [ro[1]], s=260, marker="*", color="gold", ec="k", lw=1.0, zorder=6,
                   label="reference design (" + (
                       f"front {int(ana.reference['rank'])})"
                       if bool(ana.reference.get("feasible", True)) else "infeasible)"))
    for on, axis, setter in ((logx, ax.xaxis, ax.set_xscale), (logy, ax.yaxis, ax.set_yscale)):
        if on:
            setter("log")
            axis.set_major_formatter(_plain)
            axis.set_minor_formatter(_plain_2_5)
    ax.set_xlabel(f"{o[0]} [{unit_text(data.objective_units[0])}] (minimised)")
    ax.set_ylabel(f"{o[1]} [{unit_text(data.objective_units[1])}] (minimised)")
    ax.grid(alpha=0.3, which="both")
    if ax.get_legend_handles_labels()[0]:     # nothing to label when nothing is feasible
        ax.legend(fontsize=8, loc="upper right", markerscale=0.7, framealpha=0.9)
    ax.set_title(f"{int(data.feasible.sum())} feasible of {data.n} candidates in {nf} fronts",
                 fontsize=10)
    return _png(fig)


def search_figure(h) -> str:
    """Hypervolume of the feasible front against the evaluations of an
    adaptive search (``/search`` of the file)."""
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 3.6), layout="constrained")
    ax.plot(h["evaluations"], h["hypervolume"], "-", color="C0", lw=1.5)
    ax.set_xlabel("evaluations")
    ax.set_ylabel("hypervolume of the feasible front")
    ax.grid(alpha=0.3)
    ax.set_title(f"{h['method']}: {len(h['evaluations'])} generations", fontsize=10)
    return _png(fig)
