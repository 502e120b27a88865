"""Charts of the report that the page draws itself (plotly.js, templates/charts.js)
from the numbers written here: a figure is a dict {"data", "layout"} in
plotly.js's own terms, rendered by the browser, so that building the page
renders no picture (a matplotlib picture costs 0.3-1.8 s; these cost
milliseconds).  The same quantities as the pictures of ``pipeline tolerance``
and ``pipeline compare`` (tolerance_plots.histograms_figure,
compare.comparison_figure), which stay the command line's pictures.

A user's text (a design's label, a metric's name) goes into a chart through
``plain``: plotly.js reads a few HTML tags in its labels, and a name is never
markup."""

from __future__ import annotations

import html
import math

import numpy as np

from ..kernels import config as kc
from ..base.units import unit_text
from .page import json_number, json_numbers, script_json

COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b")
LIMIT = "#c22222"
CONFIG = {"displaylogo": False, "responsive": True}
BINS = 50


def plain(text) -> str:
    """A user's text for a plotly.js label: never markup."""
    return html.escape(str(text), quote=False)


def chart_html(chart: tuple[dict, int], title: str) -> str:
    """The element the page's script draws a chart into, with its data:
    ``chart`` = (figure, height in pixels), as the functions below return it."""
    figure, height = chart
    return (f'<div class="chart" role="img" aria-label="{html.escape(title)}" '
            f'style="height:{int(height)}px"><script type="application/json" '
            f'class="chart-data">{script_json(figure)}</script></div>')


def _grid(n, cols, gap_x=0.07, gap_y=0.16):
    """Axis domains of ``n`` panels in rows of ``cols``: [(x0, x1, y0, y1)]."""
    rows = math.ceil(n / cols)
    w = (1 - gap_x * (cols - 1)) / cols
    h = (1 - gap_y * (rows - 1)) / rows
    out = []
    for k in range(n):
        r, c = divmod(k, cols)
        x0 = c * (w + gap_x)
        y1 = 1 - r * (h + gap_y)
        out.append((x0, x0 + w, y1 - h, y1))
    return out


def _axes(k):
    """plotly.js's names of panel k's axes: ('x', 'y') then ('x2', 'y2'), ..."""
    s = "" if k == 0 else str(k + 1)
    return "x" + s, "y" + s, "xaxis" + s, "yaxis" + s


def _g(v):
    return "-" if v is None or not math.isfinite(v) else f"{v:.4g}"


def tolerance_chart(a) -> tuple[dict, int]:
    """The builds of a tolerance analysis (runs.tolerance.ToleranceAnalysis): one
    panel per metric with the histogram of the builds that assemble, the
    design's value, the 5th and 95th percentiles, the normal of the linear
    prediction and the constraint limits (outside shaded).  Returns (figure,
    height in pixels)."""
    m = len(a.metrics)
    cols = min(3, m)
    rows = math.ceil(m / cols)
    ok = a.status == kc.OK
    lin, sig = a.sigma_linear(), a.sigma_sampled()
    p05, p95 = a.quantiles(0.05), a.quantiles(0.95)
    limits = {}
    for name, lo, hi in a.constraints:
        limits.setdefault(name, []).append((lo, hi))
    data, layout, shapes, notes = [], {}, [], []
    legend = set()
    for k, ((x0, x1, y0, y1), metric, unit) in enumerate(zip(_grid(m, cols), a.metrics,
                                                              a.units)):
        xa, ya, xkey, ykey = _axes(k)
        v = a.values[ok, k]
        v = v[np.isfinite(v)]
        label = plain(metric) + (f" [{plain(unit_text(unit))}]" if unit not in ("1", "") else "")
        layout[xkey] = {"domain": [x0, x1], "anchor": ya, "title": {"text": label}}
        layout[ykey] = {"domain": [y0, y1], "anchor": xa, "showticklabels": False}
        if not len(v):
            notes.append({"text": "no build assembles", "xref": f"{xa} domain",
                          "yref": f"{ya} domain", "x": 0.5, "y": 0.5, "showarrow": False})
            continue
        data.append({"type": "histogram", "x": json_numbers(v), "xaxis": xa, "yaxis": ya,
                     "histnorm": "probability density", "nbinsx": BINS,
                     "marker": {"color": "#7aa6d6"}, "name": "builds",
                     "showlegend": "builds" not in legend, "legendgroup": "builds"})
        legend.add("builds")
        if lin[k] > 0 and math.isfinite(lin[k]):
            x = np.linspace(v.min(), v.max(), 120)
            y = np.exp(-0.5 * ((x - a.nominal[k]) / lin[k]) ** 2) / (lin[k] * math.sqrt(2 * math.pi))
            data.append({"type": "scatter", "mode": "lines", "x": json_numbers(x),
                         "y": json_numbers(y), "xaxis": xa, "yaxis": ya,
                         "line": {"color": LIMIT, "width": 1}, "name": "linear prediction",
                         "showlegend": "linear" not in legend, "legendgroup": "linear"})
            legend.add("linear")
        lines = [(a.nominal[k], "#000", "solid")] + [(q, "#666", "dash") for q in (p05[k], p95[k])]
        # the axis spans the builds; a limit far outside them is named at the edge
        # instead of squeezing the histogram into a corner
        span = float(v.max() - v.min()) or abs(float(v[0])) * 1e-3 or 1.0
        lo_x, hi_x = v.min() - 0.3 * span, v.max() + 0.3 * span
        for lo, hi in limits.get(metric, ()):
            for edge, side in ((lo, -1), (hi, 1)):
                if not math.isfinite(edge):
                    continue
                if v.min() - 2 * span <= edge <= v.max() + 2 * span:
                    lo_x, hi_x = min(lo_x, edge - 0.1 * span), max(hi_x, edge + 0.1 * span)
                    lines.append((edge, LIMIT, "solid"))
                    shapes.append({"type": "rect", "xref": xa, "yref": f"{ya} domain",
                                   "x0": json_number(edge),
                                   "x1": json_number(edge + side * 10 * span),
                                   "y0": 0, "y1": 1, "fillcolor": LIMIT, "opacity": 0.12,
                                   "line": {"width": 0}})
                else:
                    notes.append({"text": ("limit " + _g(edge) + " &#8594;" if side > 0
                                           else "&#8592; limit " + _g(edge)),
                                  "xref": f"{xa} domain", "yref": f"{ya} domain",
                                  "x": 1.0 if side > 0 else 0.0, "y": 0.9,
                                  "xanchor": "right" if side > 0 else "left",
                                  "showarrow": False, "font": {"color": LIMIT, "size": 11}})
        layout[xkey]["range"] = [json_number(lo_x), json_number(hi_x)]
        for x, colour, dash in lines:
            if math.isfinite(x):
                shapes.append({"type": "line", "xref": xa, "yref": f"{ya} domain",
                               "x0": json_number(x), "x1": json_number(x), "y0": 0, "y1": 1,
                               "line": {"color": colour, "width": 1, "dash": dash}})
        notes.append({"text": f"sigma {_g(sig[k])} (linear {_g(lin[k])})<br>"
                              f"5-95 %: {_g(p05[k])} to {_g(p95[k])}",
                      "xref": f"{xa} domain", "yref": f"{ya} domain", "x": 0.5, "y": 1.0,
                      "yanchor": "bottom", "showarrow": False, "font": {"size": 11}})
    failed = int((~ok).sum())
    title = (f"{plain(a.label)}: {len(a.status):,} builds within the tolerances, yield "
             f"{100 * a.yield_:.1f} %" + (f", {failed:,} do not assemble" if failed else "")
             + "<br><sub>dashed: 5th and 95th percentiles; black: the design; red: the "
               "constraint limits, outside shaded</sub>")
    height = 150 + 290 * rows
    layout.update(title={"text": title, "font": {"size": 13}}, shapes=shapes, annotations=notes,
                  bargap=0, margin={"l": 30, "r": 20, "t": 110, "b": 60},
                  legend={"orientation": "h", "x": 0.5, "xanchor": "center", "y": -0.08,
                          "yanchor": "top"})
    return {"data": data, "layout": layout, "config": CONFIG}, height


def comparison_chart(cmp) -> tuple[dict, int]:
    """Designs against each other (analysis.compare.Comparison): the working
    point's path centred on its mean, its displacement along the path's main
    direction and M_bal against the crank angle, and the peak |R| of every
    joint as grouped bars.  Returns (figure, height in pixels)."""
    from .compare import displacement
    data, shapes, notes = [], [], []
    grid = _grid(4, 2, gap_x=0.1, gap_y=0.2)
    titles = ("working point's path (dot: phi1 = first position)",
              "working point's displacement along its path's main direction",
              "peak |R| per joint", "balancing moment on the crank")
    layout = {}
    for k, ((x0, x1, y0, y1), t) in enumerate(zip(grid, titles)):
        xa, ya, xkey, ykey = _axes(k)
        layout[xkey] = {"domain": [x0, x1], "anchor": ya}
        layout[ykey] = {"domain": [y0, y1], "anchor": xa}
        notes.append({"text": t, "xref": f"{xa} domain", "yref": f"{ya} domain", "x": 0.5,
                      "y": 1.0, "yanchor": "bottom", "showarrow": False, "font": {"size": 12}})
    descending = False
    for k, d in enumerate(cmp.designs):
        c = COLOURS[k % len(COLOURS)]
        name = plain(d.label)
        p = d.path - np.nanmean(d.path, axis=0)
        data.append({"type": "scatter", "mode": "lines", "x": json_numbers(p[:, 0]),
                     "y": json_numbers(p[:, 1]), "xaxis": "x", "yaxis": "y",
                     "line": {"color": c}, "name": f"{name} ({plain(d.working_point)})",
                     "legendgroup": name})
        data.append({"type": "scatter", "mode": "markers", "x": [json_number(p[0, 0])],
                     "y": [json_number(p[0, 1])], "xaxis": "x", "yaxis": "y",
                     "marker": {"color": c, "size": 7}, "showlegend": False,
                     "legendgroup": name, "hoverinfo": "skip"})
        stroke = d.motion.get("stroke")
        data.append({"type": "scatter", "mode": "lines", "x": json_numbers(d.phi),
                     "y": json_numbers(displacement(d.path)), "xaxis": "x2", "yaxis": "y2",
                     "line": {"color": c}, "legendgroup": name, "showlegend": False,
                     "name": name + (f": stroke {stroke:.2f} mm" if stroke is not None else "")})
        descending |= len(d.phi) > 1 and d.phi[-1] < d.phi[0]
        if d.M_bal is not None:
            data.append({"type": "scatter", "mode": "lines", "x": json_numbers(d.phi),
                         "y": json_numbers(d.M_bal), "xaxis": "x4", "yaxis": "y4",
                         "line": {"color": c}, "legendgroup": name, "showlegend": False,
                         "name": name})
    rows = [r for r in cmp.rows if r.key.startswith("reaction[")]
    for k, d in enumerate(cmp.designs):
        v = [None if r.values[k] is None else json_number(r.values[k]) for r in rows]
        if any(x is not None for x in v):
            data.append({"type": "bar", "x": [plain(r.quantity.removeprefix("peak |R| "))
                                               for r in rows],
                         "y": v, "xaxis": "x3", "yaxis": "y3", "showlegend": False,
                         "marker": {"color": COLOURS[k % len(COLOURS)]},
                         "legendgroup": plain(d.label), "name": plain(d.label)})
    if not any(d.M_bal is not None for d in cmp.designs):
        for xa, ya in (("x3", "y3"), ("x4", "y4")):
            notes.append({"text": "no force analysis in any design", "xref": f"{xa} domain",
                          "yref": f"{ya} domain", "x": 0.5, "y": 0.5, "showarrow": False})
    layout["xaxis"]["title"] = {"text": "x - mean [mm]"}
    layout["yaxis"].update(title={"text": "y - mean [mm]"}, scaleanchor="x")
    for key in ("xaxis2", "xaxis4"):
        layout[key]["title"] = {"text": "crank angle phi1 [deg]"}
        layout[key]["autorange"] = "reversed" if descending else True
    layout["yaxis2"]["title"] = {"text": "displacement [mm]"}
    layout["yaxis3"]["title"] = {"text": "peak |R| [N]"}
    layout["yaxis4"]["title"] = {"text": f"M_bal [{unit_text('N*m')}]"}
    layout.update(title={"text": " vs ".join(plain(t) for t in cmp.labels), "font": {"size": 13}},
                  barmode="group", shapes=shapes, annotations=notes,
                  margin={"l": 60, "r": 20, "t": 70, "b": 50},
                  legend={"orientation": "h", "x": 0.5, "xanchor": "center", "y": -0.1,
                          "yanchor": "top"})
    return {"data": data, "layout": layout, "config": CONFIG}, 760


def importance_chart(data, ana) -> tuple[dict, int]:
    """The permutation importance of every design variable for each objective
    (the gradient-boosted model of the analysis): bars with their spread over
    the repeats, one panel per objective.  Returns (figure, height in pixels)."""
    objs = list(data.objectives)
    names = [plain(n) for n in data.names]
    bars, layout, notes = [], {}, []
    for k, ((x0, x1, y0, y1), o) in enumerate(zip(_grid(len(objs), len(objs), gap_x=0.12),
                                                  objs)):
        xa, ya, xkey, ykey = _axes(k)
        m = ana.models.get(o, {})
        layout[xkey] = {"domain": [x0, x1], "anchor": ya, "zeroline": True,
                        "title": {"text": "drop of held-out R² when shuffled"}}
        layout[ykey] = {"domain": [y0, y1], "anchor": xa, "autorange": "reversed",
                        "automargin": True}
        if not m.get("fitted"):
            notes.append({"text": f"{plain(o)}: no model ({plain(m.get('reason', 'not fitted'))})",
                          "xref": f"{xa} domain", "yref": f"{ya} domain", "x": 0.5, "y": 0.5,
                          "showarrow": False})
            continue
        bars.append({"type": "bar", "orientation": "h", "x": json_numbers(np.asarray(m["mean"])),
                     "y": names, "xaxis": xa, "yaxis": ya, "showlegend": False, "name": plain(o),
                     "marker": {"color": COLOURS[0]},
                     "error_x": {"type": "data", "array": json_numbers(np.asarray(m["std"])),
                                 "thickness": 1, "width": 2}})
        notes.append({"text": f"{plain(o)}: held-out R² = {float(m['r2_test']):.3f}<br>"
                              f"({plain(m.get('target', ''))} target, {int(m.get('n_train', 0))} "
                              f"train / {int(m.get('n_test', 0))} test)",
                      "xref": f"{xa} domain", "yref": f"{ya} domain", "x": 0.5, "y": 1.0,
                      "yanchor": "bottom", "showarrow": False, "font": {"size": 12}})
    layout.update(annotations=notes, margin={"l": 70, "r": 20, "t": 60, "b": 50})
    return {"data": bars, "layout": layout, "config": CONFIG}, 110 + 22 * len(names)
