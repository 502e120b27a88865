"""One self-contained HTML page about a sweep (`pipeline report`): the Pareto
plot, the parameter importances, the representative designs drawn, front 1,
the counts by status and the run's provenance.

Everything is inline: the pictures are PNG data URIs, the style sheet is in the
page, and a few lines of script only record (in ``data-*`` attributes of
<body>) whether every picture decoded, so that a headless browser can check
the page.  Nothing is fetched from anywhere.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import io
import logging
import math
from pathlib import Path

import numpy as np

from .version import __version__
from .analysis import analyze, has_analysis, read_analysis, read_sweep
from .browse import design_table, ranking, rerun_candidate
from .files import write_text
from .storage import attr_text, open_results
from .sweep_file import status_counts

log = logging.getLogger("pipeline")

MAX_GREY = 60_000       # infeasible points drawn in the Pareto plot (seeded subsample)
MAX_FRONT_POINTS = 200_000

CSS = """
body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; margin: 0 auto;
       max-width: 1180px; padding: 1.2em 2em 3em; color: #222; line-height: 1.4; }
h1 { font-size: 1.55em; margin-bottom: 0.1em; }
h2 { font-size: 1.2em; border-bottom: 1px solid #ccc; padding-bottom: 0.2em; margin-top: 1.8em; }
.sub { color: #555; margin-top: 0; }
table { border-collapse: collapse; font-size: 0.85em; margin: 0.5em 0; }
th, td { padding: 0.2em 0.6em; text-align: right; border-bottom: 1px solid #e4e4e4; }
th { background: #f3f3f3; }
td.l, th.l { text-align: left; white-space: nowrap; }
.wide { overflow-x: auto; max-width: 100%; }
img { max-width: 100%; height: auto; }
.cards { display: flex; flex-wrap: wrap; gap: 14px; }
.motion img { max-width: 48%; align-self: flex-start; }
.card { border: 1px solid #ddd; border-radius: 6px; padding: 8px; width: 350px; }
.card h3 { font-size: 0.95em; margin: 0.1em 0 0.3em; }
.card table { font-size: 0.78em; width: 100%; }
.kv td:first-child { text-align: left; color: #555; }
pre { background: #f7f7f7; border: 1px solid #ddd; padding: 0.8em; font-size: 0.8em;
      overflow-x: auto; }
.note { color: #555; font-size: 0.9em; }
tr.knee td { background: #fff4d6; }
table.sortable th { cursor: pointer; }
table.sortable th:hover { background: #e6eef8; }
#explorer { display: flex; flex-wrap: wrap; gap: 16px; align-items: flex-start; }
#explorer svg { border: 1px solid #ddd; background: #fff; }
#explorer circle.pt { fill: #9ab; fill-opacity: 0.55; cursor: pointer; }
#explorer circle.f1 { fill: #c22; fill-opacity: 0.9; }
#explorer circle.sel { stroke: #000; stroke-width: 2; }
#tip { position: absolute; pointer-events: none; background: #fffbe8; border: 1px solid #cc9;
       padding: 3px 6px; font-size: 0.8em; display: none; }
#design-panel { min-width: 320px; max-width: 520px; font-size: 0.9em; }
"""

SCRIPT = """
(function () {
  // sortable tables: a click on a header sorts by that column (again: reversed)
  function cellValue(td) {
    var t = td.textContent.trim(), v = parseFloat(t);
    return isNaN(v) ? t : v;
  }
  Array.prototype.forEach.call(document.querySelectorAll('table.sortable'), function (table) {
    Array.prototype.forEach.call(table.tHead.rows[0].cells, function (th, col) {
      th.addEventListener('click', function () {
        var body = table.tBodies[0], rows = Array.prototype.slice.call(body.rows);
        var asc = th.dataset.order !== 'asc';
        rows.sort(function (a, b) {
          var x = cellValue(a.cells[col]), y = cellValue(b.cells[col]);
          return (x < y ? -1 : x > y ? 1 : 0) * (asc ? 1 : -1);
        });
        rows.forEach(function (r) { body.appendChild(r); });
        th.dataset.order = asc ? 'asc' : 'desc';
      });
    });
  });
  // the front explorer: hover a point for its numbers, click it for the design
  var data = document.getElementById('explorer-data');
  if (data) {
    var d = JSON.parse(data.textContent), tip = document.getElementById('tip');
    var panel = document.getElementById('design-panel');
    function label(k) {
      var p = d.points[k];
      return '#' + p.i + ' (front ' + (p.f || '-') + '): ' + d.objectives.map(function (o, j) {
        return o + ' ' + p.m[j].toPrecision(4) + (d.objective_units[j] && d.objective_units[j] !== '1' ? ' ' + d.objective_units[j] : '');
      }).join(', ');
    }
    function el(tag, text, cls) {   // text only: names and units never become markup
      var e = document.createElement(tag);
      if (text !== undefined) { e.textContent = text; }
      if (cls) { e.className = cls; }
      return e;
    }
    function show(k, circle) {
      var p = d.points[k], table = el('table', undefined, 'kv');
      function row(label, value) {
        var tr = el('tr'); tr.appendChild(el('td', label)); tr.appendChild(el('td', value));
        table.appendChild(tr);
      }
      d.objectives.forEach(function (o, j) {
        row(o + ' [' + d.objective_units[j] + ']', p.m[j].toPrecision(5));
      });
      d.names.forEach(function (n, j) { row(n + ' [' + d.units[j] + ']', p.v[j].toPrecision(5)); });
      var pic = d.drawings[String(p.i)];
      panel.textContent = '';
      panel.appendChild(el('h3', 'Candidate ' + p.i + (p.f ? ', front ' + p.f : '')));
      if (pic) {   // the embedded drawing and curves of a front-1 design
        var img = el('img');
        img.alt = 'design ' + p.i;
        img.setAttribute('src', pic);
        panel.appendChild(img);
      } else {
        panel.appendChild(el('p', 'Its drawing and curves: pipeline show ' + d.file +
                                  ' --candidate ' + p.i, 'note'));
      }
      panel.appendChild(table);
      panel.dataset.candidate = String(p.i);
      Array.prototype.forEach.call(document.querySelectorAll('#explorer circle.sel'), function (c) { c.classList.remove('sel'); });
      circle.classList.add('sel');
    }
    Array.prototype.forEach.call(document.querySelectorAll('#explorer circle.pt'), function (c) {
      var k = Number(c.dataset.k);
      c.addEventListener('mouseenter', function (e) {
        tip.textContent = label(k); tip.style.display = 'block';
        tip.style.left = (e.pageX + 12) + 'px'; tip.style.top = (e.pageY + 12) + 'px';
      });
      c.addEventListener('mouseleave', function () { tip.style.display = 'none'; });
      c.addEventListener('click', function () { show(k, c); });
    });
  }
  window.addEventListener('error', function () {
    document.body.dataset.jsErrors = String(Number(document.body.dataset.jsErrors || 0) + 1);
  });
  window.addEventListener('load', function () {
    var imgs = Array.prototype.slice.call(document.images);
    var ok = imgs.filter(function (i) { return i.complete && i.naturalWidth > 0; }).length;
    document.body.dataset.imagesTotal = String(imgs.length);
    document.body.dataset.imagesOk = String(ok);
    document.body.dataset.imagesLoaded = (imgs.length > 0 && ok === imgs.length) ? 'true' : 'false';
  });
})();
"""


def _png(fig, dpi=100) -> str:
    import matplotlib.pyplot as plt
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def _img(uri, alt):
    return f'<img src="{uri}" alt="{html.escape(alt)}">'


def _fmt(v, digits=4):
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    try:
        v = float(v)
    except (TypeError, ValueError):
        return html.escape(str(v))
    if math.isnan(v):
        return "&ndash;"
    if math.isinf(v):
        return "&infin;"
    return f"{v:.{digits}g}"


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
                   label=f"reference design (front {int(ana.reference['rank'])})")
    for on, axis, setter in ((logx, ax.xaxis, ax.set_xscale), (logy, ax.yaxis, ax.set_yscale)):
        if on:
            setter("log")
            axis.set_major_formatter(_plain)
            axis.set_minor_formatter(_plain_2_5)
    ax.set_xlabel(f"{o[0]} [{data.objective_units[0]}] (minimised)")
    ax.set_ylabel(f"{o[1]} [{data.objective_units[1]}] (minimised)")
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


def _search_history(f):
    """The per-generation history of a search file (None for a sweep)."""
    if "search" not in f:
        return None
    g = f["search"]
    return {"method": str(attr_text(g.attrs.get("method", "?"))),
            "normalisation": str(attr_text(g.attrs.get("normalisation", ""))),
            "evaluations": g["evaluations"][()], "hypervolume": g["hypervolume"][()]}


def importance_figure(data, ana) -> str:
    import matplotlib.pyplot as plt
    objs = list(data.objectives)
    fig, axes = plt.subplots(1, len(objs), figsize=(5.2 * len(objs), 3.8), layout="constrained",
                             squeeze=False)
    names = data.names
    ypos = np.arange(len(names))
    for ax, o in zip(axes[0], objs):
        m = ana.models.get(o, {})
        if not m.get("fitted"):
            ax.text(0.5, 0.5, f"no model:\n{attr_text(m.get('reason', 'not fitted'))}", ha="center",
                    va="center", transform=ax.transAxes, wrap=True, fontsize=9)
            ax.set_axis_off()
            ax.set_title(o, fontsize=10)
            continue
        mean, std = np.asarray(m["mean"]), np.asarray(m["std"])
        ax.barh(ypos, mean, xerr=std, color="C0", alpha=0.85, capsize=2)
        ax.set_yticks(ypos, names)
        ax.invert_yaxis()
        ax.axvline(0, color="k", lw=0.6)
        ax.set_xlabel("drop of held-out R$^2$ when shuffled")
        ax.grid(alpha=0.3, axis="x")
        ax.set_title(f"{o}: held-out R$^2$ = {float(m['r2_test']):.3f}\n"
                     f"({attr_text(m.get('target', ''))} target, {int(m.get('n_train', 0))} train / "
                     f"{int(m.get('n_test', 0))} test)", fontsize=10)
    return _png(fig)


def design_figure(run) -> str:
    import matplotlib.pyplot as plt
    from .plots import draw_positions
    fig, ax = plt.subplots(figsize=(3.6, 4.4), layout="constrained")
    draw_positions(ax, run.scene, run.table, highlight=0, key="horizontal", joint_key=False)
    ax.set_xlabel("x [mm]", fontsize=8)
    ax.set_ylabel("y [mm]", fontsize=8)
    ax.tick_params(labelsize=7)
    return _png(fig, dpi=90)


ANIMATION_FRAMES = 60       # the animated design: one revolution in 3 s (about 0.5 MB)
ANIMATION_DPI = 60


def motion_html(path, ana) -> str:
    """The knee design (else the first representative, else the reference
    design) in motion: an animated GIF of one revolution, embedded like the
    pictures, and its circular cyclogram against the cycle the study states
    ([output.motion_law]), else the OV-7 cycle of DOMAIN.md section 9 that the
    synthesis is for."""
    from .animate import gif_bytes, motion_of
    from .browse import OV7_PHASES
    from .plots import cyclogram_figure, stated_cycle
    if ana.knee >= 0:
        cid, why = int(ana.knee), "the knee of front 1"
    elif len(ana.representatives):
        cid, why = int(ana.representatives[0]), "representative A"
    else:
        cid, why = "reference", "no feasible design: the study's reference design"
    try:
        run = rerun_candidate(path, cid, forces=False)
        gif = gif_bytes(motion_of(run.scene, f"{run.label} ({why})"), frames=ANIMATION_FRAMES,
                        dpi=ANIMATION_DPI)
        cycle, turn = stated_cycle(run.study)
        if cycle is not None:
            against, name = "the study's motion law", "required ([output.motion_law])"
        else:
            against, name, cycle = "the OV-7 cycle", "OV-7 cycle", OV7_PHASES
        cyc = _png(cyclogram_figure(run.scene, cycle, name, turn), dpi=70)
    except Exception as e:   # a design the scene path cannot redraw: say so, go on
        log.warning("report: no animation of candidate %s (%s)", cid, e)
        return f'<p class="note">No animation: {html.escape(str(e))}</p>'
    uri = "data:image/gif;base64," + base64.b64encode(gif).decode("ascii")
    return (f'<p class="note">{html.escape(run.label)}, {html.escape(why)}, over one revolution '
            f"({ANIMATION_FRAMES} frames, {len(gif) / 1024:.0f} KiB; the working point's path "
            "magnified when it is small), and its cyclogram: the phases of its own output "
            f"motion (inner ring) against {against} (outer ring), turned so that both dwells "
            "start together, as the crank's mounting phase would (unless the law is held "
            "fixed). <code>pipeline show FILE "
            f"--candidate {html.escape(str(run.index))} --animate</code> writes the full "
            'animation.</p><div class="cards motion">'
            f'<img class="animation" src="{uri}" alt="animation of {html.escape(run.label)}">'
            f'{_img(cyc, "cyclogram of " + run.label)}</div>')


EXPLORER_POINTS = 3000      # feasible designs in the interactive plot (front 1 always)
EXPLORER_DRAWINGS = 12      # front-1 designs whose drawing and curves are embedded


def explorer_html(path, data, ana) -> str:
    """The interactive front: an SVG of the feasible designs (front 1 in red)
    over the first two objectives; hover shows a design's numbers, a click its
    variables, metrics and (for the first front-1 designs) its drawing and
    curves.  Plain SVG and a few lines of script: one offline file."""
    import json

    from .browse import candidate_figure
    feas = np.nonzero(data.feasible & np.isfinite(data.F).all(axis=1))[0]
    if data.F.shape[1] < 2:
        return '<p class="note">The explorer plots two objectives; this study has one.</p>'
    if feas.size == 0:
        return '<p class="note">No feasible design to explore.</p>'
    front1 = set(int(i) for i in ana.front1)
    rest = np.array([i for i in feas if int(i) not in front1], np.int64)
    rng = np.random.default_rng(data.seed)
    if rest.size > EXPLORER_POINTS:
        rest = np.sort(rng.choice(rest, EXPLORER_POINTS, replace=False))
    idx = np.concatenate([rest, np.array(sorted(front1), np.int64)])
    F = data.F[idx, :2]
    lo, hi = F.min(axis=0), F.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    W, H, M = 620, 420, 56
    X = M + (F[:, 0] - lo[0]) / span[0] * (W - 1.5 * M)
    Y = H - M + (F[:, 1] - lo[1]) / span[1] * -(H - 1.5 * M)
    points, circles = [], []
    for k, (i, x, y) in enumerate(zip(idx, X, Y)):
        f1 = int(i) in front1
        points.append({"i": int(i), "f": int(ana.rank[i]), "m": [float(v) for v in data.F[i]],
                       "v": [float(v) for v in data.params[i]]})
        circles.append(f'<circle class="pt{" f1" if f1 else ""}" data-k="{k}" '
                       f'cx="{x:.1f}" cy="{y:.1f}" r="{4.5 if f1 else 2.6}"/>')
    ticks = []
    for t in np.linspace(0.0, 1.0, 5):
        x = M + t * (W - 1.5 * M)
        y = H - M - t * (H - 1.5 * M)
        ticks.append(f'<text x="{x:.0f}" y="{H - M + 16}" font-size="10" text-anchor="middle">'
                     f"{lo[0] + t * span[0]:.4g}</text>")
        ticks.append(f'<text x="{M - 6}" y="{y + 3:.0f}" font-size="10" text-anchor="end">'
                     f"{lo[1] + t * span[1]:.4g}</text>")
    o, u = data.objectives, data.objective_units
    svg = (f'<svg width="{W}" height="{H}" viewBox="0 0 {W} {H}" role="img">'
           f'<line x1="{M}" y1="{H - M}" x2="{W - M / 2}" y2="{H - M}" stroke="#444"/>'
           f'<line x1="{M}" y1="{H - M}" x2="{M}" y2="{M / 2}" stroke="#444"/>'
           + "".join(ticks) +
           f'<text x="{W / 2:.0f}" y="{H - 14}" font-size="12" text-anchor="middle">'
           f"{html.escape(o[0])} [{html.escape(u[0])}]</text>"
           f'<text x="14" y="{H / 2:.0f}" font-size="12" text-anchor="middle" '
           f'transform="rotate(-90 14 {H / 2:.0f})">{html.escape(o[1])} '
           f"[{html.escape(u[1])}]</text>" + "".join(circles) + "</svg>")
    drawings = {}
    for i in list(ana.front1[np.argsort(data.F[ana.front1, 0])])[:EXPLORER_DRAWINGS]:
        try:
            fig = candidate_figure(rerun_candidate(path, int(i)))
        except Exception as e:   # a design the scene path cannot redraw: say so, go on
            log.warning("report: candidate %d not drawn (%s)", int(i), e)
            continue
        drawings[str(int(i))] = _png(fig, dpi=60)
    payload = {"points": points, "objectives": list(o), "objective_units": list(u),
               "names": list(data.names), "units": list(data.units),
               "file": Path(path).name, "drawings": drawings}
    # inside <script>: no character that the HTML parser reads as markup
    text = (json.dumps(payload).replace("&", "\\u0026").replace("<", "\\u003c")
            .replace(">", "\\u003e"))
    return (f'<div id="explorer">{svg}<div id="design-panel"><p class="note">Hover a point '
            "for its objectives; click it for the design (front-1 designs with their drawing "
            "and curves).</p></div></div><div id=\"tip\"></div>"
            f'<script type="application/json" id="explorer-data">{text}</script>')


# ----------------------------------------------------------------- page parts
def _table_html(df, knee=None) -> str:
    cols = list(df.columns)
    out = ['<table class="sortable"><thead><tr>']
    out += [f'<th class="{"l" if c in ("selection", "mark") else ""}">{html.escape(str(c))}</th>'
            for c in cols]
    out.append("</tr></thead><tbody>")
    for _, row in df.iterrows():
        cls = ' class="knee"' if knee is not None and row.get("candidate") == knee else ""
        out.append(f"<tr{cls}>" + "".join(
            f'<td class="l">{html.escape(str(row[c]))}</td>' if c in ("selection", "mark")
            else f"<td>{_fmt(row[c])}</td>" for c in cols) + "</tr>")
    out.append("</tbody></table>")
    return "".join(out)


def _kv(pairs) -> str:
    return '<table class="kv">' + "".join(
        f"<tr><td>{html.escape(str(k))}</td><td>{v}</td></tr>" for k, v in pairs) + "</table>"


def _card(title, run, values, data) -> str:
    rows = [(k, v) for k, v in values]
    rows += [(f"{n} [{u}]", _fmt(x, 5)) for n, x, u in zip(data.names, run.x, data.units)]
    pic = design_figure(run)
    return (f'<div class="card"><h3>{html.escape(title)}</h3>{_img(pic, title)}'
            f"{_kv(rows)}</div>")


def _metric_row(f, i, names):
    out = []
    for m in names:
        if m in f["metrics"]:
            d = f["metrics"][m]
            v = float(d[i]) if i != "reference" else float(f["reference"][m][0])
            out.append((f"{m} [{attr_text(d.attrs.get('units', '1'))}]", _fmt(v)))
    return out


def build_html(path, top=20) -> str:
    """The report page of an analyzed sweep file."""
    data = read_sweep(path)
    with open_results(path, "sweep") as f:
        ana = read_analysis(f)
        a = {k: attr_text(f.attrs[k]) for k in f.attrs}
        counts = status_counts(f)
        rk = ranking(f)
        front = ana.front1[:top]
        ftab = design_table(f, front, "", rk).drop(columns=["selection", "front"])
        mark = []
        reps = list(ana.representatives)
        letters = dict(zip(reps, _letters(len(reps))))
        for i in front:
            tags = (["knee"] if i == ana.knee else []) + \
                ([f"representative {letters[i]}"] if i in letters else [])
            mark.append(", ".join(tags))
        ftab.insert(1, "mark", mark)
        show_metrics = [m for m in ("dwell_error", "peak_reaction", "stroke",
                                    "singularity_margin", "dwell_start", "peak_M_bal")]
        rep_values = {i: _metric_row(f, i, show_metrics) for i in reps}
        ref_values = _metric_row(f, "reference", show_metrics) if "reference" in f else None
        ga = {k: attr_text(f["analysis"].attrs[k]) for k in f["analysis"].attrs}
        history = _search_history(f)

    title = a.get("study_title", a.get("study_name", "sweep"))
    parts = [f"<h1>{html.escape(str(title))}</h1>",
             f'<p class="sub">Sweep report of <code>{html.escape(Path(path).name)}</code>: '
             f"{data.n} candidates, study <code>{html.escape(str(a.get('study_name', '')))}"
             "</code></p>"]

    # summary
    ref = ana.reference
    knee = ana.knee
    summary = [("candidates", data.n),
               ("feasible", f"{int(data.feasible.sum())} "
                            f"({100 * data.feasible.mean():.1f}%)" if data.n else "0"),
               ("objectives (minimised)", ", ".join(data.objectives)),
               ("Pareto fronts", int(ana.rank.max(initial=0))),
               ("front 1", f"{ana.front1.size} designs")]
    if knee >= 0:
        summary.append(("knee", f"#{data.id(knee)}: " + ", ".join(
            f"{o} {_fmt(data.F[knee, j])} {data.objective_units[j]}"
            for j, o in enumerate(data.objectives))))
    if int(ref["rank"]) > 0:
        summary.append(("reference design", f"front {int(ref['rank'])}, dominated by "
                        f"{int(ref['dominated_by_count'])} feasible candidates "
                        f"({len(ref['dominators_front1'])} of them on front 1); "
                        f"{html.escape(str(ref.get('note', '')))}"))
    parts += ["<h2>Summary</h2>", _kv(summary)]
    if not a.get("complete", True):
        parts.append('<p class="note"><b>The sweep is unfinished</b>: only the evaluated '
                     "candidates are ranked.</p>")

    parts += ["<h2>Pareto fronts</h2>",
              '<p class="note">Every feasible candidate coloured by its front (front 1 in red, '
              "joined by a line); grey: candidates that violate a constraint but have both "
              "objectives; diamond: the knee of front 1; star: the study's reference design; "
              "letters: the representative designs below.</p>",
              _img(pareto_figure(data, ana), "Pareto plot"),
              "<h3>Explore the designs</h3>", explorer_html(path, data, ana)]

    parts += ["<h2>What drives each objective</h2>",
              '<p class="note">A gradient-boosted tree model of each objective on the design '
              "variables, fitted on the feasible candidates (seeded subsample and split); "
              "permutation importance = how much the held-out R<sup>2</sup> drops when one "
              "variable is shuffled (mean &plusmn; std over the repeats).</p>",
              _img(importance_figure(data, ana), "parameter importances")]

    parts.append("<h2>Representative designs</h2>")
    parts.append('<p class="note">Front-1 members nearest the centroids of a k-means '
                 "clustering of the normalised front-1 objectives, each drawn at 12 crank "
                 "positions (thick: phi1 = 0), with the study's reference design for "
                 "comparison. <code>pipeline show FILE --candidate ID</code> draws one with "
                 "its motion and reactions.</p>")
    cards = []
    for i in reps:
        run = rerun_candidate(path, int(i), forces=False)
        cards.append(_card(f"{letters[i]}: candidate #{data.id(i)}"
                           + (" (knee)" if i == knee else ""),
                           run, rep_values[i], data))
    if ref_values is not None:
        run = rerun_candidate(path, "reference", forces=False)
        cards.append(_card("reference design", run, ref_values, data))
    parts.append('<div class="cards">' + "".join(cards) + "</div>" if cards else
                 '<p class="note">No feasible design: nothing to draw.</p>')

    parts += ["<h2>A design in motion</h2>", motion_html(path, ana)]

    parts.append("<h2>Front 1</h2>")
    more = f" (first {len(front)} of {ana.front1.size})" if ana.front1.size > len(front) else ""
    parts.append(f'<p class="note">Non-dominated feasible designs sorted by '
                 f"{html.escape(data.objectives[0])}{more}.</p>")
    parts.append(f'<div class="wide">{_table_html(ftab, knee)}</div>' if len(front)
                 else '<p class="note">empty</p>')

    if history is not None and len(history["evaluations"]):
        parts.append("<h2>Adaptive search</h2>")
        seeded = a.get("seeded_from", "")
        parts.append(_kv([("method", html.escape(f"{history['method']} (pymoo)")),
                          ("generations", len(history["evaluations"])),
                          ("evaluations", f"{int(history['evaluations'][-1]):,}"),
                          ("seeded from", html.escape(f"{a.get('n_seeded', 0)} designs of "
                                                      f"{seeded}") if seeded else "no"),
                          ("hypervolume", _fmt(history["hypervolume"][-1]))]))
        parts.append('<p class="note">Hypervolume of the feasible front of every candidate '
                     f"evaluated so far: {html.escape(history['normalisation'])}.</p>")
        parts.append(_img(search_figure(history), "hypervolume against evaluations"))

    parts.append("<h2>Candidates by status</h2>")
    parts.append(_kv([(k, f"{v['count']} ({v['percent']:.1f}%)") for k, v in counts.items()]))

    parts.append("<h2>Provenance</h2>")
    prov = [("results file", html.escape(str(Path(path).resolve()))),
            ("study file", html.escape(str(a.get("study_file", "")))),
            ("run with", f"pipeline {html.escape(str(a.get('software_version', '?')))}, "
                         f"{html.escape(str(a.get('created', '?')))}"),
            ("analysis", f"pipeline {html.escape(str(ga.get('software_version', '?')))}, "
                         f"{html.escape(str(ga.get('created', '?')))}"),
            ("report", f"pipeline {__version__}, "
                       f"{_dt.datetime.now(_dt.timezone.utc).isoformat(timespec='seconds')}"),
            ("seed", html.escape(str(a.get("seed", "?")))),
            ("sampler", html.escape(str(a.get("sampler", "?")))),
            ("positions per revolution", html.escape(str(a.get("positions_per_revolution", "?")))),
            ("format", html.escape(f"{a.get('format', '?')} {a.get('format_version', '')}"))]
    if "wall_time_s" in a:
        prov.append(("sweep wall time", f"{float(a['wall_time_s']):.1f} s "
                                        f"({html.escape(str(a.get('engine', '')))})"))
    study_n = _study_candidates(a.get("study_toml", ""))
    run_n = int(a.get("n_candidates", data.n))
    prov.insert(1, ("candidates in this run", f"{run_n:,}" + (
        f" (the study below says {study_n:,}; the run's --candidates replaced it)"
        if study_n is not None and study_n != run_n else "")))
    parts.append(_kv(prov))
    parts.append("<p>The study, as stored verbatim in the results file:</p>")
    parts.append(f"<pre>{html.escape(str(a.get('study_toml', '')))}</pre>")

    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
            f"<title>{html.escape(str(title))}: sweep report</title>\n"
            f"<style>{CSS}</style>\n</head>\n<body>\n" + "\n".join(parts)
            + f"\n<script>{SCRIPT}</script>\n</body>\n</html>\n")


def _study_candidates(text):
    """The candidate count the stored study asks for (None if it says none)."""
    import tomllib
    try:
        return int(tomllib.loads(str(text)).get("sweep", {}).get("candidates"))
    except (tomllib.TOMLDecodeError, TypeError, ValueError):
        return None


def default_report_output(path) -> Path:
    path = Path(path)
    return path.with_name(f"{path.stem}_report.html")


def write_report(path, out=None, top=20) -> dict:
    """Write the HTML report of a sweep file (running ``analyze`` first if the
    file has no analysis); returns a summary."""
    if top < 1:
        raise ValueError(f"--top must be at least 1, got {top}")
    with open_results(path, "sweep") as f:
        analyzed = has_analysis(f)
    info = {}
    if not analyzed:
        log.info("%s has no analysis: running `pipeline analyze` first", path)
        info["analysis"] = "run now (stored in the results file)"
        analyze(path)
    page = build_html(path, top=top)
    out = Path(out) if out else default_report_output(path)
    write_text(out, page)
    info.update(report=str(out), size=f"{out.stat().st_size / 1024:.0f} KiB")
    return info
