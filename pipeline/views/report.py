"""One self-contained HTML page about a sweep (`pipeline report`): the Pareto
plot, the explorer of every feasible design (views/explorer.py), the parameter
importances, the representative designs drawn, front 1, the counts by status
and the run's provenance.

The page is laid out by Jinja2 templates (views/templates/: the page's
skeleton, the explorer's section, the style sheet and the scripts; page.py).
Everything is inline: the pictures are PNG data URIs, the style sheet and the
scripts (plotly.js among them) are in the page, and a few lines of script
record (in ``data-*`` attributes of <body>) whether every picture decoded and
whether a script failed, so that a headless browser can check the page.
Nothing is fetched from anywhere.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import logging
import math
import shlex
import time
from pathlib import Path

import numpy as np

from ..base.version import __version__
from ..analysis.fronts import analyze, has_analysis, read_analysis, read_sweep
from ..analysis.candidate import rerun_candidate
from ..base.files import check_output, write_text
from ..analysis.ranking import design_table, ranking
from .explorer import EXPLORER_DRAWINGS, explorer_section
from .explorer_designs import design_key
from .page import markup, plotly_js, render
from .charts import chart_html, comparison_chart, importance_chart, tolerance_chart
from .report_figures import _letters, _png, pareto_figure, search_figure
from ..results.storage import attr_text, open_results
from ..results.sweep_file import status_counts
from ..study.reader import stored_study

log = logging.getLogger("pipeline")


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


def _search_history(f):
    """The per-generation history of a search file (None for a sweep)."""
    if "search" not in f:
        return None
    g = f["search"]
    return {"method": str(attr_text(g.attrs.get("method", "?"))),
            "normalisation": str(attr_text(g.attrs.get("normalisation", ""))),
            "evaluations": g["evaluations"][()], "hypervolume": g["hypervolume"][()]}


ANIMATION_FRAMES = 60       # the animated design: one revolution in 3 s (about 0.5 MB)
ANIMATION_DPI = 60


def motion_html(path, ana, data, drawn=()) -> str:
    """The knee design (else the first representative, else the reference
    design) in motion, and its circular cyclogram against the cycle the study
    states ([output.motion_law]), else the OV-7 cycle of DOMAIN.md section 9
    that the synthesis is for.  The motion: drawn by the page's script from the
    explorer's cycle of the design when ``drawn`` (the keys of the designs the
    explorer embeds) has it, else an animated GIF embedded like the pictures."""
    from .animate import gif_bytes, motion_of
    from .show import OV7_PHASES
    from .cyclogram_plots import cyclogram_figure
    from ..solve.cyclogram import stated_cycle
    if ana.knee >= 0:
        cid, why = int(ana.knee), "the knee of front 1"
    elif len(ana.representatives):
        cid, why = int(ana.representatives[0]), "representative A"
    else:
        cid, why = "reference", "no feasible design: the study's reference design"
    key = design_key(data, cid)
    try:
        run = rerun_candidate(path, cid, forces=False)
        gif = None if key in drawn else gif_bytes(
            motion_of(run.scene, f"{run.label} ({why})"), frames=ANIMATION_FRAMES,
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
    if gif is None:
        motion = (f'<div class="design-animation" data-design="{html.escape(key)}" '
                  f'data-frames-asked="{ANIMATION_FRAMES}"></div>')
        how = f"about {ANIMATION_FRAMES} frames, drawn by the page (play and pause above it)"
    else:
        uri = "data:image/gif;base64," + base64.b64encode(gif).decode("ascii")
        motion = (f'<img class="animation" src="{uri}" alt="animation of '
                  f'{html.escape(run.label)}">')
        how = (f"{ANIMATION_FRAMES} frames, {len(gif) / 1024:.0f} KiB; the working point's path "
               "magnified when it is small")
    return (f'<p class="note">{html.escape(run.label)}, {html.escape(why)}, over one revolution '
            f"({how}), and its cyclogram: the phases of its own output "
            f"motion (inner ring) against {against} (outer ring), turned so that both dwells "
            "start together, as the crank's mounting phase would (unless the law is held "
            "fixed). <code>pipeline show FILE "
            f"--candidate {html.escape(str(run.index))} --animate</code> writes the full "
            'animation.</p><div class="cards motion">'
            f'{motion}{_img(cyc, "cyclogram of " + run.label)}</div>')


# ----------------------------------------------------------------- page parts
TOLERANCE_METRICS = ("dwell_error", "stroke", "peak_reaction")


class _StoredTolerance:
    """A tolerance file's contents (``results.tolerance_file.read_tolerance``)
    as ``charts.tolerance_chart`` reads a runs.tolerance.ToleranceAnalysis: the
    spreads and percentiles are the file's own."""

    def __init__(self, t):
        self._t = t
        self.metrics, self.units, self.nominal = t["metrics"], t["units"], t["nominal"]
        self.status, self.values, self.constraints = t["status"], t["values"], t["constraints"]
        self.label, self.yield_ = t["design"], t["yield"]

    def sigma_linear(self):
        return self._t["std_linear"]

    def sigma_sampled(self):
        return self._t["std"]

    def quantiles(self, q):
        return self._t[{0.05: "p05", 0.5: "p50", 0.95: "p95"}[q]]


def tolerance_html(path, ana, data) -> str:
    """The knee, each representative design and the reference design as their
    tolerance files beside the results file hold them (``pipeline tolerance FILE
    --candidate ID`` writes one): the yield, the 5-95 % range of the main
    metrics and the dimension that moves each most; the knee's distributions
    drawn.  Nothing is computed here: a design without its file gets the
    command that writes it."""
    from ..base.errors import ResultsError
    from ..results.tolerance_file import read_tolerance, tolerance_output
    rows, missing, knee_chart = [], [], None
    designs = list(dict.fromkeys([i for i in [ana.knee] + list(ana.representatives) if i >= 0]))
    for i in designs + ["reference"]:
        cid = design_key(data, i)
        label = "reference design" if i == "reference" else f"candidate #{cid}"
        label += " (knee)" if i == ana.knee else ""
        file = tolerance_output(path, {"candidate": cid})
        if not file.exists():
            missing.append(cid)
            continue
        try:
            t = read_tolerance(file)
        except (ResultsError, OSError, KeyError) as e:
            log.warning("report: %s not read (%s)", file, e)
            missing.append(cid)
            continue
        if t["candidate"] != cid:       # a file renamed from another design's
            log.warning("report: %s is the tolerance file of candidate %s, not %s", file,
                        t["candidate"], cid)
            missing.append(cid)
            continue
        if i == ana.knee:
            knee_chart = chart_html(tolerance_chart(_StoredTolerance(t)), "the knee's builds")
        share = np.abs(t["sensitivity"]) * t["sigma"][None, :]
        cells = [html.escape(label), f"{100 * t['yield']:.1f} % of {t['samples']:,}"]
        for m in TOLERANCE_METRICS:
            if m not in t["metrics"]:
                cells.append("&ndash;")
                continue
            k = t["metrics"].index(m)
            j = int(np.nanargmax(share[k])) if np.isfinite(share[k]).any() else 0
            cells.append(f"{_fmt(t['nominal'][k])} [{_fmt(t['p05'][k])}, "
                         f"{_fmt(t['p95'][k])}]<br>"
                         f"<small>most: {html.escape(t['dimensions'][j])}</small>")
        rows.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    command = html.escape(f"pipeline tolerance {shlex.quote(str(path))} --candidate ")
    if not rows:
        return (f'<p class="note">No tolerance analysis of these designs yet: <code>{command}'
                f"{html.escape(missing[0])}</code> writes one (any design: its number, knee "
                "or reference) beside the results file, which this page then shows.</p>")
    head = "".join(f"<th>{h}</th>" for h in ["design", "yield (builds)"] + [
        f"{m} (5-95 %)" for m in TOLERANCE_METRICS])
    out = ['<p class="note">Each design built with its dimensions drawn within the '
           "study's tolerances ([tolerance]; ISO 2768-f by default), every build through "
           "the exact kernels, as its tolerance file holds it; the yield is the share that "
           "assembles and meets the constraints.</p>",
           f'<div class="wide"><table><tr>{head}</tr>{"".join(rows)}</table></div>']
    if missing:
        out.append('<p class="note">Not analysed yet: ' + ", ".join(
            f"<code>{command}{html.escape(c)}</code>" for c in missing) + "</p>")
    if knee_chart is not None:
        out.append(knee_chart)
    return "".join(out)


def comparison_section_html(path, ana, data) -> str:
    """The knee (else representative A) against the study's reference design,
    both re-run as scenes (``analysis.compare.compare_candidate``): the table
    of ``pipeline compare FILE --candidate ID`` and its chart."""
    from ..analysis.compare import compare_candidate
    from .compare import comparison_html
    if ana.knee >= 0:
        i, why = int(ana.knee), "the knee of front 1"
    elif len(ana.representatives):
        i, why = int(ana.representatives[0]), "representative A"
    else:
        return '<p class="note">No feasible design to compare with the reference design.</p>'
    cid = design_key(data, i)
    try:
        cmp = compare_candidate(path, cid)
    except Exception as e:   # a design the scene path cannot redo: say so, go on
        log.warning("report: no comparison of candidate %s (%s)", cid, e)
        return f'<p class="note">No comparison: {html.escape(str(e))}</p>'
    return (f'<p class="note">Candidate #{html.escape(cid)} ({html.escape(why)}) against the '
            "study's reference design, both re-run as scenes at the operating speed: each "
            "peak with the crank angle where it happens, the change against the reference "
            f"design. <code>pipeline compare FILE --candidate {html.escape(cid)}</code> prints "
            "the same table.</p>" + comparison_html(cmp)
            + chart_html(comparison_chart(cmp), "the design against the reference design"))


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


def _card(title, values, variables, data, key, drawn) -> str:
    """A design's card: its drawing (by the page's script, from the explorer's
    cycle of the design, where ``drawn`` has ``key``), its metrics and its
    design variables."""
    rows = [(k, v) for k, v in values]
    rows += [(f"{n} [{u}]", _fmt(x, 5)) for n, x, u in zip(data.names, variables, data.units)]
    pic = (f'<div class="design-drawing" data-design="{html.escape(key)}"></div>'
           if key in drawn else "")
    return f'<div class="card"><h3>{html.escape(title)}</h3>{pic}{_kv(rows)}</div>'


def _metric_row(f, i, names):
    out = []
    for m in names:
        if m in f["metrics"]:
            d = f["metrics"][m]
            v = float(d[i]) if i != "reference" else float(f["reference"][m][0])
            out.append((f"{m} [{attr_text(d.attrs.get('units', '1'))}]", _fmt(v)))
    return out


class _Progress:
    """A plain line per part of the report as it is built (logging: the CLI's
    -q silences it), with the seconds the part took."""

    def __init__(self):
        self.t = time.perf_counter()

    def __call__(self, what):
        now = time.perf_counter()
        log.info("report: %s (%.1f s)", what, now - self.t)
        self.t = now


def build_html(path, top=20, drawings=None) -> str:
    """The report page of an analyzed sweep file.  ``drawings``: the front-1
    designs whose cycle the explorer embeds (None: all of front 1 up to
    EXPLORER_DRAWINGS; the knee and the reference design come with them)."""
    drawings = EXPLORER_DRAWINGS if drawings is None else drawings
    step = _Progress()
    data = read_sweep(path)
    with open_results(path, "sweep") as f:
        # the study stored in the file, read first: one that cannot be read stops the
        # report in one line (the designs the page re-runs would each be lost to it)
        stored_study(f.attrs, path)
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
        ref_variables = (f["reference/params"][()] if "reference/params" in f
                         else None)
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
    if int(ref["rank"]) > 0 and not bool(ref.get("feasible", True)):   # on no front
        summary.append(("reference design", "infeasible, on no front: "
                        f"{html.escape(str(ref.get('note', '')))}; dominated by "
                        f"{int(ref['dominated_by_count'])} feasible candidates"))
    elif int(ref["rank"]) > 0:
        summary.append(("reference design", f"front {int(ref['rank'])}, dominated by "
                        f"{int(ref['dominated_by_count'])} feasible candidates "
                        f"({len(ref['dominators_front1'])} of them on front 1); "
                        f"{html.escape(str(ref.get('note', '')))}"))
    parts += ["<h2>Summary</h2>", _kv(summary)]
    if not a.get("complete", True):
        parts.append('<p class="note"><b>The sweep is unfinished</b>: only the evaluated '
                     "candidates are ranked.</p>")

    step(f"read {data.n:,} candidates")
    explorer, drawn = explorer_section(path, data, ana, drawings)
    live = 'id="explorer-data"' in explorer     # else a note: no explorer on this page
    parts.append("<h2>Pareto fronts</h2>")
    if not live:                                # the fronts as a picture instead
        parts += ['<p class="note">Every feasible candidate coloured by its front (front 1 '
                  "in red, joined by a line); grey: candidates that violate a constraint but "
                  "have both objectives; diamond: the knee of front 1; star: the study's "
                  "reference design; letters: the representative designs below.</p>",
                  _img(pareto_figure(data, ana), "Pareto plot")]
    parts += ["<h3>Explore the designs</h3>", explorer]
    step("explorer")

    parts += ["<h2>What drives each objective</h2>",
              '<p class="note">A gradient-boosted tree model of each objective on the design '
              "variables, fitted on the feasible candidates (seeded subsample and split); "
              "permutation importance = how much the held-out R<sup>2</sup> drops when one "
              "variable is shuffled (mean &plusmn; std over the repeats).</p>",
              chart_html(importance_chart(data, ana), "parameter importances")]
    step("importances")

    parts.append("<h2>Representative designs</h2>")
    parts.append('<p class="note">Front-1 members nearest the centroids of a k-means '
                 "clustering of the normalised front-1 objectives, each drawn at its table's crank "
                 "positions (thick: the first) with the paths of its points (zoom by drag, "
                 "double-click to reset), with the study's reference design for "
                 "comparison. <code>pipeline show FILE --candidate ID</code> draws one with "
                 "its motion and reactions.</p>")
    cards = []
    for i in reps:
        cards.append(_card(f"{letters[i]}: candidate #{data.id(i)}"
                           + (" (knee)" if i == knee else ""),
                           rep_values[i], data.params[i], data, design_key(data, i), drawn))
    if ref_values is not None and ref_variables is not None:
        cards.append(_card("reference design", ref_values, ref_variables, data, "reference",
                           drawn))
    parts.append('<div class="cards">' + "".join(cards) + "</div>" if cards else
                 '<p class="note">No feasible design: nothing to draw.</p>')

    step(f"{len(cards)} representative designs drawn")
    parts += ["<h2>How the designs hold up when made</h2>", tolerance_html(path, ana, data)]
    step("tolerances")
    parts += ["<h2>Against the reference design</h2>",
              comparison_section_html(path, ana, data)]
    step("comparison with the reference design")
    parts += ["<h2>A design in motion</h2>", motion_html(path, ana, data, drawn)]
    step("animation")

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

    # the parts are HTML written above from escaped pieces; the explorer's section
    # comes from its own template, its script and plotly.js only when it is there
    charts = any('class="chart"' in p for p in parts)
    page = render("report.html.j2", title=str(title), parts=[markup(p) for p in parts],
                  plotly=plotly_js() if live or charts else None, explorer=live)
    step("page")
    return page


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


def write_report(path, out=None, top=20, drawings=None) -> dict:
    """Write the HTML report of a sweep file (running ``analyze`` first if the
    file has no analysis); returns a summary.  ``drawings``: front-1 designs
    whose cycle the explorer embeds (None: all of front 1 up to
    EXPLORER_DRAWINGS; 0: none, nor the knee's and the reference design's)."""
    if top < 1:
        raise ValueError(f"--top must be at least 1, got {top}")
    if drawings is not None and drawings < 0:
        raise ValueError(f"--drawings must be at least 0, got {drawings}")
    out = Path(out) if out else default_report_output(path)
    out = check_output(out, inputs=(path,))    # before the analysis: never over results
    with open_results(path, "sweep") as f:
        analyzed = has_analysis(f)
    info = {}
    if not analyzed:
        log.info("%s has no analysis: running `pipeline analyze` first", path)
        info["analysis"] = "run now (stored in the results file)"
        analyze(path)
    from ..base.progress import ticking
    with ticking("report"):         # a live line while the parts are built
        page = build_html(path, top=top, drawings=drawings)
    write_text(check_output(out, inputs=(path,)), page)
    info.update(report=str(out), size=f"{out.stat().st_size / 1024:.0f} KiB")
    return info
