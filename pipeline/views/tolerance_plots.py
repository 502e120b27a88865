"""Pictures of a tolerance analysis: the distribution of every metric over the
builds with the constraint limits, and the tornado chart of the dimensions
that move each metric most."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np

from ..kernels import config as kc
from ..base.units import unit_text

TORNADO_ROWS = 8        # dimensions per metric in the tornado chart
BINS = 50


def _label(metric, unit):
    return f"{metric} [{unit_text(unit)}]" if unit not in ("1", "") else metric


def histograms_figure(a):
    """One panel per metric: the histogram of the builds that assemble, the
    design's value, the 5th and 95th percentiles, the normal of the linear
    prediction (mean at the design, sigma_lin) and the constraint limits
    (outside shaded).  Returns the Figure."""
    m = len(a.metrics)
    cols = min(3, m)
    rows = math.ceil(m / cols)
    fig, axs = plt.subplots(rows, cols, figsize=(4.6 * cols, 3.3 * rows + 0.8),
                            layout="constrained", squeeze=False)
    ok = a.status == kc.OK
    lin = a.sigma_linear()
    p05, p95 = a.quantiles(0.05), a.quantiles(0.95)
    limits = {}
    for name, lo, hi in a.constraints:
        limits.setdefault(name, []).append((lo, hi))
    for k, (metric, unit) in enumerate(zip(a.metrics, a.units)):
        ax = axs[k // cols, k % cols]
        v = a.values[ok, k]
        v = v[np.isfinite(v)]
        if not len(v):
            ax.text(0.5, 0.5, "no build assembles", ha="center", va="center",
                    transform=ax.transAxes)
            ax.set_axis_off()
            continue
        spread = float(v.max() - v.min())
        if spread > 0:
            ax.hist(v, bins=BINS, density=True, color="#7aa6d6", edgecolor="none")
        else:
            ax.axvline(v[0], color="#7aa6d6", lw=3)
        if lin[k] > 0 and math.isfinite(lin[k]):
            x = np.linspace(v.min(), v.max(), 200)
            ax.plot(x, np.exp(-0.5 * ((x - a.nominal[k]) / lin[k]) ** 2)
                    / (lin[k] * math.sqrt(2 * math.pi)), color="C3", lw=1,
                    label="linear prediction")
        ax.axvline(a.nominal[k], color="k", lw=1, label="design")
        for q in (p05[k], p95[k]):
            ax.axvline(q, color="0.4", lw=0.8, ls="--")
        for lo, hi in limits.get(metric, ()):
            if math.isfinite(lo):
                ax.axvspan(min(lo, v.min()), lo, color="C3", alpha=0.12, lw=0)
                ax.axvline(lo, color="C3", lw=1)
            if math.isfinite(hi):
                ax.axvspan(hi, max(hi, v.max()), color="C3", alpha=0.12, lw=0)
                ax.axvline(hi, color="C3", lw=1)
        ax.set_xlabel(_label(metric, unit))
        ax.set_yticks([])
        ax.set_title(f"sigma {_g(a.sigma_sampled()[k])} (linear {_g(lin[k])})\n"
                     f"5-95 %: {_g(p05[k])} to {_g(p95[k])}", fontsize=9)
    for k in range(m, rows * cols):
        axs[k // cols, k % cols].set_axis_off()
    fig.legend(*axs[0, 0].get_legend_handles_labels(), loc="outside lower center", ncol=2,
               fontsize=8, frameon=False)
    failed = int((~ok).sum())
    fig.suptitle(f"{a.label}: {len(a.status):,} builds within the tolerances, yield "
                 f"{100 * a.yield_:.1f} %" + (f", {failed:,} do not assemble" if failed else "")
                 + "\n(dashed: 5th and 95th percentiles; red: the constraint limits)",
                 fontsize=10)
    return fig


def tornado_figure(a, metrics=None):
    """Per metric, the dimensions that move it most: the metric with one
    dimension at -tolerance and at +tolerance (exact, bars), the linear
    prediction (ticks).  Returns the Figure."""
    metrics = list(metrics or a.metrics)
    idx = [a.metrics.index(m) for m in metrics]
    cols = min(2, len(idx))
    rows = math.ceil(len(idx) / cols)
    fig, axs = plt.subplots(rows, cols, figsize=(6.6 * cols, 0.32 * TORNADO_ROWS * rows + 1.2
                                                 * rows + 0.6),
                            layout="constrained", squeeze=False)
    tol = np.array([d.tolerance for d in a.dimensions])
    for n, k in enumerate(idx):
        ax = axs[n // cols, n % cols]
        lo, hi = a.one_at_a_time[k, :, 0], a.one_at_a_time[k, :, 1]
        swing = np.nan_to_num(np.abs(hi - lo), nan=-1.0)
        order = [j for j in np.argsort(-swing) if tol[j] > 0][:TORNADO_ROWS][::-1]
        y = np.arange(len(order))
        base = a.nominal[k]
        ax.barh(y, lo[order] - base, left=base, color="#7aa6d6", label="-tolerance")
        ax.barh(y, hi[order] - base, left=base, color="#f0a35e", label="+tolerance")
        lin = a.sensitivity[k, order] * tol[order]
        ax.plot(base + lin, y, "k|", ms=10, label="linear")
        ax.plot(base - lin, y, "k|", ms=10)
        ax.axvline(base, color="k", lw=0.8)
        ax.set_yticks(y, [f"{a.dimensions[j].param} ±{tol[j]:g} {a.dimensions[j].units}"
                          for j in order], fontsize=8)
        ax.set_xlabel(_label(a.metrics[k], a.units[k]))
        ax.grid(axis="x", alpha=0.3)
    for n in range(len(idx), rows * cols):
        axs[n // cols, n % cols].set_axis_off()
    fig.legend(*axs[0, 0].get_legend_handles_labels(), loc="outside lower center", ncol=3,
               fontsize=8, frameon=False)
    fig.suptitle(f"{a.label}: each dimension alone at its tolerance limits", fontsize=10)
    return fig


def _g(x):
    return "-" if not np.isfinite(x) else f"{x:.4g}"
