"""Analysis, browsing, show and report of a sweep (`pipeline analyze|browse|show|report`).

The session's small sweep of the main job's study (conftest.py: synthesis_sweep)
is copied once per module; tests that write into a file work on copies of it.
"""

import json
import os
import re
import subprocess
from io import StringIO

import h5py
import numpy as np
import pandas as pd
import pytest

from support.browser import (FRONT_TRACE, CLICK_PACE_S, EMPTY_SPOT, ISOLATED, PLOT_AREA, POINT,
                             WEBGL, Page, chromium, click_each_front_1_design, devtools, open_page)
from support.html_page import explorer_data, markup_only
from support.naive_pareto import brute_force_rank, dominates_ref
from pipeline.analysis.fronts import analyze
from pipeline.views.browse import rerun_candidate
from pipeline.cli import main
from pipeline.results.storage import attr_text, read_units, variables
from support.sweep_helpers import SYNTHESIS_N as N
from support.sweep_helpers import copy_of
from support.tolerances import SWEEP_VS_SCENE_REL

# the run's date and duration, and HDF5's dimension-scale bookkeeping (object references)
VOLATILE = {"created", "elapsed_s", "DIMENSION_LIST", "REFERENCE_LIST"}
COMMANDS = ("analyze", "browse", "show", "report")


# ---------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory, synthesis_sweep):
    """The README's main job (studies/ov7_synthesis.toml) with fewer candidates:
    this module's copy of the session's sweep."""
    return copy_of(synthesis_sweep, tmp_path_factory.mktemp("sweep"))


@pytest.fixture(scope="module")
def analyzed(sweep_file, tmp_path_factory):
    p = copy_of(sweep_file, tmp_path_factory.mktemp("analyzed"), "copy.h5")
    return p, analyze(p)


@pytest.fixture(scope="module")
def cli_run(sweep_file, tmp_path_factory):
    """Every new command run once through `pipeline.cli.main` on a fresh copy of the
    main job's file, capturing what they print."""
    d = tmp_path_factory.mktemp("cli")
    p = copy_of(sweep_file, d, "ov7_synthesis.h5")
    out = {"file": p, "dir": d}

    def run(*argv):
        import contextlib
        import io
        buf, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(err):
            code = main([str(a) for a in argv])
        return code, buf.getvalue(), err.getvalue()

    out["browse_before"] = run("browse", p, "--wide")
    out["analyze"] = run("analyze", p, "--format", "json")
    out["browse"] = run("browse", p, "--top", "4")
    out["browse10"] = run("browse", p, "--top", "10")
    out["json"] = run("browse", p, "--format", "json", "--top", "3")
    out["csv"] = run("browse", p, "--format", "csv", "--top", "3")
    out["candidate"] = run("browse", p, "--candidate", "knee")
    out["candidate_json"] = run("browse", p, "--candidate", "0", "--format", "json")
    out["show"] = run("show", p, "--candidate", "knee", "-o", d / "knee.png", "-q")
    # the report of a file nobody analyzed runs the analysis first
    fresh = copy_of(sweep_file, d, "fresh.h5")
    out["report"] = run("report", fresh, "-o", d / "report.html", "--format", "json")
    out["fresh"] = fresh
    return out


def h5_items(path, group):
    """{name: (attrs, data)} of every object under ``group``."""
    items = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            attrs = {k: np.asarray(v) for k, v in obj.attrs.items() if k not in VOLATILE}
            data = obj[()] if isinstance(obj, h5py.Dataset) else None
            items[name] = (attrs, data)
        f[group].visititems(visit)
        items["."] = ({k: np.asarray(v) for k, v in f[group].attrs.items()
                       if k not in VOLATILE}, None)
    return items


def objectives(path):
    """The objectives the fronts are ranked on: the stored metrics, with the
    peaks analyze refined between positions (fronts 1-3) in their place."""
    with h5py.File(path, "r") as f:
        obj = [str(o) for o in f.attrs["objectives"]]
        F = np.stack([f[f"metrics/{o}"][()] for o in obj], axis=1)
        g = f.get("analysis/refined")
        for j, o in enumerate(obj):
            if g is not None and o in g.attrs["ranked_on"]:   # (a failed scene: the grid's)
                v = g[o][()]
                F[g["index"][()][np.isfinite(v)], j] = v[np.isfinite(v)]
        return F, f["candidates/feasible"][()]


def reference_objectives(f):
    """The reference design's objectives as ranked (its peaks refined likewise)."""
    obj = [str(o) for o in f.attrs["objectives"]]
    r = np.array([f["reference"][o][0] for o in obj])
    g = f.get("analysis/refined")
    if g is not None and "reference" in g:
        cols = [str(c) for c in g["column"][()].astype(str)]
        for j, o in enumerate(obj):
            if o in g.attrs["ranked_on"]:
                r[j] = g["reference"][cols.index(o)]
    return r


# ---------------------------------------------------------------- fronts
def test_ranks_equal_brute_force_on_the_sweep(analyzed):
    p, _ = analyzed
    F, feas = objectives(p)
    ref = brute_force_rank(F, feas)
    with h5py.File(p, "r") as f:
        g = f["analysis"]
        rank = g["pareto_rank"][()]
        np.testing.assert_array_equal(rank, ref)
        assert rank.dtype == np.int32 and (rank[~feas] == 0).all() and (rank[feas] >= 1).all()
        front = g["front1/index"][()]
        assert set(front) == set(np.flatnonzero(ref == 1))
        np.testing.assert_array_equal(g["front1/objectives"][()], F[front])
        np.testing.assert_array_equal(g["front1/params"][()], f["candidates/params"][()][front])
        assert np.all(np.diff(F[front, 0]) >= 0), "front 1 is sorted by the first objective"
        assert g["knee"][()] in front


@pytest.mark.parametrize("seed,n_obj", [(1, 2), (2, 2), (3, 3)])
def test_ranks_equal_brute_force_on_random_sets(sweep_file, tmp_path, seed, n_obj):
    """Random objectives on a grid (many ties and duplicates) written into a copy
    of the sweep file; 3 objectives exercise the general ranking path."""
    p = copy_of(sweep_file, tmp_path)
    rng = np.random.default_rng(seed)
    obj = ["dwell_error", "peak_reaction", "stroke"][:n_obj]
    with h5py.File(p, "r+") as f:
        n = f["candidates/status"].shape[0]
        for o in obj:
            f[f"metrics/{o}"][...] = rng.integers(1, 25, n) * (0.01 if o == "dwell_error" else 10)
        feas = rng.random(n) < 0.6
        f["candidates/feasible"][...] = feas
        f.attrs["objectives"] = obj
    analyze(p, n_representatives=3, max_samples=200)   # small models: ranks are the point
    F, feas = objectives(p)
    ref = brute_force_rank(F, feas, jit=True)
    with h5py.File(p, "r") as f:
        np.testing.assert_array_equal(f["analysis/pareto_rank"][()], ref)
        assert set(f["analysis/front1/index"][()]) == set(np.flatnonzero(ref == 1))
        assert f["analysis/front1/objectives"].shape[1] == n_obj


def test_reference_design_standing(analyzed):
    """Which candidates dominate the study's own design, by a plain loop."""
    p, _ = analyzed
    F, feas = objectives(p)
    with h5py.File(p, "r") as f:
        r = reference_objectives(f)
        g = f["analysis/reference"]
        rank = f["analysis/pareto_rank"][()]
        dom = [i for i in range(len(F)) if feas[i] and dominates_ref(F[i], r)]
        assert list(g["dominated_by"][()]) == dom
        assert g["dominated_by_count"][()] == len(dom)
        assert list(g["dominators_front1"][()]) == [i for i in dom if rank[i] == 1]
        assert g["rank"][()] == (max(rank[dom]) + 1 if dom else 1)
        np.testing.assert_array_equal(g["objectives"][()], r)
        assert bool(g["feasible"][()])   # mechanism B meets the study's constraints


def test_analysis_group_describes_itself(analyzed):
    p, summary = analyzed
    with h5py.File(p, "r") as f:
        g = f["analysis"]
        assert g.attrs["complete"] and list(g.attrs["objectives"]) == ["dwell_error",
                                                                        "peak_reaction"]
        datasets = []
        g.visititems(lambda n, o: datasets.append(o) if isinstance(o, h5py.Dataset) else None)
        assert len(datasets) >= 15
        for d in datasets:
            assert "units" in d.attrs and d.attrs["long_name"], d.name
        names = list(f["candidates/params"].attrs["names"])
        for o in ("dwell_error", "peak_reaction"):
            m = g["importance"][o]
            assert m.attrs["fitted"], m.attrs["reason"]
            assert m["mean"].shape == m["std"].shape == (len(names),)
            assert list(m["mean"].attrs["names"]) == names
            assert 0.0 < m["r2_test"][()] <= 1.0
            assert m.attrs["n_train"] + m.attrs["n_test"] == int(f["candidates/feasible"][()].sum())
        reps = g["representatives/index"][()]
        front = set(g["front1/index"][()])
        assert len(reps) == min(5, len(front)) == len(set(reps)) and set(reps) <= front
        crowd = g["crowding"][()]
        assert (crowd[g["pareto_rank"][()] == 0] == 0).all()
    assert summary["front 1"] == len(front) and summary["candidates"] == N


def test_analysis_is_reproducible(analyzed, tmp_path):
    """Same file -> same numbers: ranks, crowding, knee, models, importances,
    representatives; and a re-run replaces /analysis."""
    p, _ = analyzed
    q = copy_of(p, tmp_path)
    analyze(q)
    a, b = h5_items(p, "analysis"), h5_items(q, "analysis")
    assert a.keys() == b.keys()
    for name in a:
        (aa, da), (ab, db) = a[name], b[name]
        assert aa.keys() == ab.keys(), name
        for k in aa:
            assert np.array_equal(aa[k], ab[k]), (name, k)
        if da is not None:
            np.testing.assert_array_equal(da, db, err_msg=name)


def test_few_feasible_candidates_skip_the_models(sweep_file, tmp_path):
    p = copy_of(sweep_file, tmp_path)
    with h5py.File(p, "r+") as f:
        feas = f["candidates/feasible"][()]
        keep = np.flatnonzero(feas)[:10]
        feas[:] = False
        feas[keep] = True
        f["candidates/feasible"][...] = feas
    s = analyze(p)
    assert "skipped" in s["model dwell_error"] and "10" in s["model dwell_error"]
    with h5py.File(p, "r") as f:
        m = f["analysis/importance/peak_reaction"]
        assert not m.attrs["fitted"] and "only 10" in m.attrs["reason"]
        assert len(f["analysis/front1/index"]) >= 1
    # and with none at all
    with h5py.File(p, "r+") as f:
        f["candidates/feasible"][...] = False
    s = analyze(p)
    with h5py.File(p, "r") as f:
        assert f["analysis/knee"][()] == -1
        assert f["analysis/front1/index"].shape == (0,)
        assert f["analysis/representatives/index"].shape == (0,)
        assert (f["analysis/pareto_rank"][()] == 0).all()
    assert s["front 1"] == 0


# ---------------------------------------------------------------- the commands
def test_commands_succeed_on_the_main_job_file(cli_run):
    for key in ("browse_before", "analyze", "browse", "json", "csv", "candidate",
                "candidate_json", "show", "report"):
        code, _, err = cli_run[key]
        assert code == 0, (key, err)
    out = cli_run["browse_before"][1]
    assert "pipeline analyze" in out and "ranked on the fly" in out
    for word in ("/candidates/params", "mm (all 9)", "redrawn before solving", "feasible", "knee",
                 "front 1", "best dwell_error", "best peak_reaction"):
        assert word in out, word
    info = json.loads(cli_run["analyze"][1])
    assert info["candidates"] == N and info["front 1"] >= 1
    assert "ranked on the fly" not in cli_run["browse"][1]
    # without --wide everything fits an 80-column terminal, and the dataset listing
    # waits for --wide
    for key in ("browse", "browse10", "candidate"):
        assert max(len(ln) for ln in cli_run[key][1].splitlines()) <= 80, key
    assert "/candidates/params" not in cli_run["browse"][1] and "--wide" in cli_run["browse"][1]
    assert "representative" in cli_run["browse"][1]


def test_browse_gives_every_value_its_unit_and_no_minus_zero(cli_run):
    """Each number of a metric or a constraint is followed by its unit (unless
    it is a pure number), each column of the compact tables names its unit in
    its header (the candidate's number and its front are counts), and no
    output prints -0."""
    with h5py.File(cli_run["file"], "r") as f:
        units = {m: attr_text(f["metrics"][m].attrs["units"]) for m in variables(f["metrics"])}
        g = f["candidates/constraints"]
        names = [n.decode() if isinstance(n, bytes) else n for n in g.attrs["names"]]
        units.update(zip(names, read_units(g, len(names))))
    number = r"-?(?:\d+(?:\.\d*)?(?:e[-+]?\d+)?|inf)"
    for key in ("browse10", "candidate"):
        text = cli_run[key][1]
        seen = 0
        for name, unit in units.items():
            if unit == "1":
                continue
            for m in re.finditer(rf"(?<![\w\[])\b{name}(?: =)? +({number})( [^\s,;)]+)?", text):
                seen += 1
                assert m.group(2) == f" {unit}", (key, m.group(0))
        assert seen >= 1, key
        for ln in text.splitlines():
            if ln.strip().startswith("candidate  "):
                for col in re.split(r"\s{2,}", ln.strip())[2:]:
                    assert re.fullmatch(r".+ \[.+\]", col), (key, col)
    assert re.search(r"reference design: .*peak_reaction \S+ N\b", cli_run["browse10"][1])
    for key, (_, out, _) in ((k, v) for k, v in cli_run.items() if isinstance(v, tuple)):
        assert not re.search(r"(?<![\w.])-0(?:\.0*)?(?![\w.])", out), key


def test_browse_formats_parse(cli_run):
    d = json.loads(cli_run["json"][1])
    assert d["info"]["objectives"] == ["dwell_error", "peak_reaction"]
    assert d["status"]["feasible"]["count"] > 0 and d["analysis"]["stored"] is True
    assert any(r["selection"] == "knee" for r in d["designs"])
    df = pd.read_csv(StringIO(cli_run["csv"][1]))
    assert {"selection", "candidate", "front", "dwell_error [1]", "peak_reaction [N]",
            "L12 [mm]", "L57 [mm]"} <= set(df.columns)
    assert (df.loc[df.selection == "front 1", "front"] == 1).all()
    best = df[df.selection == "best dwell_error"]["dwell_error [1]"].to_numpy()
    assert len(best) == 3 and np.all(np.diff(best) >= 0)
    c = json.loads(cli_run["candidate_json"][1])
    assert c["candidate"] == 0 and c["status"] and c["reason"]
    assert [p["units"] for p in c["params"]] == ["mm"] * 9
    text = cli_run["candidate"][1]
    assert "reason: feasible" in text and "L12 =" in text and "peak_reaction" in text


def test_show_redraws_the_design(cli_run, sweep_file):
    png = cli_run["dir"] / "knee.png"
    assert png.exists() and png.stat().st_size > 30_000
    # the re-run scene gives the sweep's numbers back
    with h5py.File(cli_run["file"], "r") as f:
        k = int(f["analysis/knee"][()])
        stored = f["metrics/dwell_error"][k]
    run = rerun_candidate(cli_run["file"], k)
    assert run.dwell_error == pytest.approx(stored, rel=SWEEP_VS_SCENE_REL)
    # default output next to the results file
    assert main(["show", str(cli_run["file"]), "--candidate", "reference", "-q"]) == 0
    assert cli_run["file"].with_name("ov7_synthesis_reference.png").exists()


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory, studies):
    out = tmp_path_factory.mktemp("scene") / "ov7_base.h5"
    assert main(["run", str(studies / "ov7_base.toml"), "-o", str(out), "-q",
                 "--no-pictures"]) == 0
    return out


@pytest.mark.parametrize("command", COMMANDS)
def test_wrong_files_exit_2(command, scene_file, tmp_path, capsys):
    text = tmp_path / "notes.h5"
    text.write_text("not an HDF5 file\n")
    extra = ["--candidate", "0"] if command == "show" else []
    for path, words in ((scene_file, "is a scene result, this command needs a sweep result"),
                        (text, "not a readable HDF5 file"),
                        (tmp_path / "missing.h5", "file not found")):
        assert main([command, str(path), *extra]) == 2
        err = capsys.readouterr().err
        assert f"pipeline {command}: error:" in err and words in err, err


def test_bad_candidate_ids_exit_2(sweep_file, capsys):
    for argv in (["browse", str(sweep_file), "--candidate", str(N)],
                 ["show", str(sweep_file), "--candidate", "best"],
                 ["browse", str(sweep_file), "--top", "0"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "error:" in err and ("does not exist" in err or "expects" in err
                                    or "--top" in err), err


# ---------------------------------------------------------------- the report
def test_report_is_self_contained(cli_run):
    info = json.loads(cli_run["report"][1])
    assert "run now" in info["analysis"] and info["report"].endswith("report.html")
    with h5py.File(cli_run["fresh"], "r") as f:
        assert f["analysis"].attrs["complete"]
    page = (cli_run["dir"] / "report.html").read_text()
    assert page.startswith("<!DOCTYPE html>")
    tags = markup_only(page)     # the scripts' text aside (plotly.js names addresses)
    assert not re.search(r"""(src|href)\s*=\s*["'](?!data:|#)""", tags), "external resource"
    assert "<link" not in tags and "@import" not in page
    assert not re.search(r"<script[^>]*\bsrc", tags)
    # a picture rendered here (the cyclogram); the charts, the designs' drawings and
    # the design in motion drawn by the page from their numbers
    assert page.count('src="data:image/png;base64,') >= 1
    # importances and comparison; no tolerance file beside the results: the command
    # that writes one instead of a tolerance chart (the report computes none)
    assert page.count('<div class="chart"') == 2
    assert "pipeline tolerance " in page and "--candidate" in page
    assert page.count('class="design-drawing"') >= 2          # representatives, reference
    assert page.count('class="design-animation"') == 1
    for words in ("Pareto fronts", "held-out", "Representative designs", "Front 1",
                  "Candidates by status", "Provenance", "[sweep]", "20261121", "sobol"):
        assert words in page, words
    # the stored study asks for 250,000; this run had N (--candidates): both said
    assert f"candidates in this run</td><td>{N:,} (the study below says 250,000" in page


def test_report_renders_in_chromium(cli_run, tmp_path):
    exe = chromium()
    html_path = cli_run["dir"] / "report.html"
    flags = ["--headless", "--no-sandbox", *WEBGL, "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             f"--user-data-dir={tmp_path / 'profile'}", "--virtual-time-budget=5000"]
    url = html_path.resolve().as_uri()
    env = dict(os.environ, HOME=str(tmp_path))
    dom = subprocess.run([exe, *flags, "--dump-dom", url], capture_output=True, text=True,
                         timeout=120, env=env)
    assert dom.returncode == 0, dom.stderr[-2000:]
    body = re.search(r"<body[^>]*>", dom.stdout)
    assert body, dom.stdout[:500]
    tag = body.group(0)
    assert 'data-images-loaded="true"' in tag, tag
    total = int(re.search(r'data-images-total="(\d+)"', tag).group(1))
    assert total >= 1 and f'data-images-ok="{total}"' in tag
    assert "data-js-errors" not in tag
    assert 'data-explorer="ready"' in tag, tag          # plotly.js drew the explorer
    assert 'data-charts="2"' in tag, tag                # and the two charts
    # every design's drawing and the design in motion hold a drawn plot
    cards = dom.stdout.count('class="design-drawing')
    assert cards >= 2 and dom.stdout.count('class="design-drawing js-plotly-plot"') == cards, \
        cards
    frames = re.search(r'class="design-animation js-plotly-plot"[^>]*data-frames="(\d+)"',
                       dom.stdout) or re.search(
        r'data-frames="(\d+)"[^>]*class="design-animation js-plotly-plot"', dom.stdout)
    assert frames and int(frames.group(1)) >= 30, frames
    shot = tmp_path / "report.png"
    r = subprocess.run([exe, *flags, "--window-size=1280,3000", f"--screenshot={shot}", url],
                       capture_output=True, text=True, timeout=120, env=env)
    assert r.returncode == 0 and shot.exists() and shot.stat().st_size > 50_000


def test_report_explorer_hover_click_zoom_select_filter(cli_run, tmp_path):
    """In a real headless Chromium (WebGL through SwiftShader), with real mouse and
    keyboard input: the explorer opens zoomed on fronts 1 to 3, the rest of the
    designs dimmed behind; hovering a front-1 point shows Plotly's label with its
    number; a click shows that design's drawing, motion and reactions (drawn by
    plotly.js from the embedded data) and the command that draws it, a click on
    each front-1 point at that first view opens that design, and the reference
    design's button opens it; a drag zooms, the wheel zooms, a double-click comes
    back to the first view and another to all the designs, where a click on a
    front-1 point still opens a front-1 design; a box selection fills
    the table and the parallel coordinates, front 1 drawn on top; an objective's
    upper bound hides designs; a header click sorts a table.  No script error, no
    console error, nothing fetched but the page."""
    import asyncio
    import shlex

    from tornado.websocket import websocket_connect

    exe = chromium()
    url = (cli_run["dir"] / "report.html").resolve().as_uri()
    proc, ws_url = devtools(exe, "about:blank", tmp_path)
    data = explorer_data((cli_run["dir"] / "report.html").read_text())
    seen = {}

    async def drive():
        ws = await websocket_connect(ws_url, max_message_size=64 << 20)
        page = Page(ws)
        await open_page(page, url, ("Runtime", "Network", "Page", "Log"))
        await page.centre("#ex-plot")
        count0 = int(await page.js("document.getElementById('ex-count').dataset.shown"))
        seen["count0"] = count0

        # the first view: the ranges hold every design of fronts 1 to 3 (traces 2 and
        # 3), and the feasible cloud (trace 1, dimmed) reaches beyond them
        seen["view"] = await page.js("""(function () {
            var gd = document.getElementById('ex-plot'), fl = gd._fullLayout;
            function inside(t) {
                var tr = gd._fullData[t], n = 0, xa = fl.xaxis, ya = fl.yaxis;
                for (var k = 0; k < tr.x.length; k++) {
                    var x = xa.d2l(tr.x[k]), y = ya.d2l(tr.y[k]);
                    if (x >= xa.range[0] && x <= xa.range[1] && y >= ya.range[0] &&
                        y <= ya.range[1]) { n += 1; }
                }
                return [n, tr.x.length];
            }
            return {near: inside(2), front: inside(3), cloud: inside(1),
                    names: gd._fullData.map(function (t) { return t.name; }),
                    dim: [gd._fullData[1].marker.opacity, gd._fullData[3].marker.opacity]};
        })()""")

        # hover: a front-1 design's label
        n_front = await page.js(
            f"document.getElementById('ex-plot')._fullData[{FRONT_TRACE}].x.length")
        assert n_front >= 1
        p = await page.js(f"{POINT}({FRONT_TRACE}, {await page.js(ISOLATED)})")
        await page.mouse("mouseMoved", p["x"] - 3, p["y"] - 3)
        await page.mouse("mouseMoved", p["x"], p["y"])
        await page.until("(document.querySelector('#ex-plot .hoverlayer') || {}).textContent"
                         f".indexOf('#{p['id']}') >= 0", f"hover label of #{p['id']}", 10)
        seen["hover"] = await page.js("document.querySelector('#ex-plot .hoverlayer')"
                                      ".textContent")
        seen["target"] = p["id"]

        # click: the design panel shows it, drawn, with its command
        await page.click(p["x"], p["y"])
        await page.until("document.getElementById('design-panel').dataset.drawn === 'true' && "
                         f"document.getElementById('design-panel').dataset.candidate === "
                         f"'{p['id']}'", "the clicked design's drawing", 20)
        seen["panel"] = await page.js("""(function () {
            var panel = document.getElementById('design-panel');
            var plots = panel.querySelectorAll('.ex-drawings > div');
            return {text: panel.textContent,
                    command: panel.querySelector('.ex-command').textContent,
                    plots: plots.length,
                    traces: Array.prototype.map.call(plots, function (d) {
                        return d.data ? d.data.length : 0; }),
                    svg: panel.querySelectorAll('.ex-drawings .main-svg').length};
        })()""")

        # at the first view, a click on each front-1 point opens that design
        seen["front_clicks"] = await click_each_front_1_design(page)

        # the reference design, opened by its button: drawn too, named 'reference'
        x, y = await page.centre("#ex-show-reference")
        await page.click(x, y)
        await page.until("document.getElementById('design-panel').dataset.drawn === 'true' && "
                         "document.getElementById('design-panel').dataset.candidate === "
                         "'reference'", "the reference design's drawing", 20)
        seen["reference"] = await page.js(
            "document.querySelector('#design-panel h3').textContent + '|' + "
            "document.querySelector('#design-panel .ex-command').textContent + '|' + "
            "document.querySelectorAll('#design-panel .ex-drawings .main-svg').length")

        # zoom: a drag in the plot narrows both axes; the wheel narrows x again;
        # a double-click gives the whole range back
        await page.centre("#ex-plot")
        a = await page.js(PLOT_AREA)
        n = await page.relayouts()
        await page.drag(a["l"] + 0.05 * a["w"], a["t"] + 0.05 * a["h"],
                        a["l"] + 0.6 * a["w"], a["t"] + 0.7 * a["h"])
        # (each read once the plot's ranges have moved and its relayout has finished: no
        # fixed wait, a loaded machine draws late)
        b = await page.moved(a, "the drag's zoom", n)
        n = await page.relayouts()
        await page.mouse("mouseWheel", a["l"] + 0.3 * a["w"], a["t"] + 0.3 * a["h"],
                         deltaX=0, deltaY=-240)
        c = await page.moved(b, "the wheel's zoom", n)
        n = await page.relayouts()
        e = await page.js(EMPTY_SPOT)
        await page.double_click(e["x"], e["y"])
        d = await page.moved(c, "the double-click's first view", n)
        await asyncio.sleep(CLICK_PACE_S)      # a double click of its own, not a third click
        n = await page.relayouts()
        e = await page.js(EMPTY_SPOT)
        await page.double_click(e["x"], e["y"])
        seen["ranges"] = (a, b, c, d, await page.moved(d, "the double-click's whole range", n))
        # there, with front 1 squeezed among the rest, a click on a front-1 point still
        # opens a front-1 design (the nearest of the best front; plotly.js alone gives
        # the design of any front drawn there: half of them on this sweep)
        seen["whole_clicks"] = await click_each_front_1_design(page, still=False)

        # box selection: the tool bar's box tool, then a box over the whole plot
        await page.mouse("mouseMoved", a["l"] + 0.5 * a["w"], a["t"] + 0.5 * a["h"])
        bx, by = await page.centre('#ex-plot .modebar-btn[data-val="select"]')
        a = await page.js(PLOT_AREA)
        await page.mouse("mouseMoved", a["l"] + 0.5 * a["w"], a["t"] + 0.5 * a["h"])
        await page.click(bx, by)
        await page.until("document.getElementById('ex-plot')._fullLayout.dragmode === 'select'",
                         "the box tool", 10)
        # (1.5 % inside the plot's corners, where Plotly's axis-end drag handles are not)
        await page.drag(a["l"] + 0.015 * a["w"], a["t"] + 0.015 * a["h"],
                        a["l"] + 0.985 * a["w"], a["t"] + 0.985 * a["h"])
        await page.until("Number(document.getElementById('ex-selection').dataset.parcoords) > 0",
                         "the selection's parallel coordinates", 20)
        seen["selection"] = await page.js("""(function () {
            var s = document.getElementById('ex-selection');
            return {hidden: s.classList.contains('hidden'), rows: Number(s.dataset.rows),
                    table: document.querySelectorAll('#ex-sel-table tbody tr').length,
                    first: (document.querySelector('#ex-sel-table tbody tr td') || {}).textContent,
                    parcoords: document.querySelectorAll('#ex-parcoords .parcoords').length,
                    dims: document.getElementById('ex-parcoords').data[0].dimensions.length,
                    note: document.getElementById('ex-sel-count').textContent};
        })()""")
        seen["lines"] = await page.js("""(function () {
            var line = document.getElementById('ex-parcoords')._fullData[0].line;
            return {color: Array.prototype.slice.call(line.color), cmax: line.cmax,
                    cmin: line.cmin, ticks: line.colorbar.ticktext};
        })()""")

        # a filter: typing an upper bound of the second objective hides designs
        second = [c for c in data["columns"] if c["key"] == data["objectives"][1]][0]
        values = second["values"][(data["feasible"] == 1) & ~np.isnan(second["values"])]
        bound = float(np.median(values))
        x, y = await page.centre("#ex-max-1")
        await page.click(x, y)
        await page.call("Input.insertText", text=f"{bound:.6g}")
        await page.until(f"Number(document.getElementById('ex-count').dataset.shown) < {count0}",
                         "the filtered count", 10)
        seen["filtered"] = (int(await page.js(
            "document.getElementById('ex-count').dataset.shown")), sum(v <= float(f"{bound:.6g}")
                                                                   for v in values))
        seen["count_text"] = await page.js("document.getElementById('ex-count').textContent")

        # the colour and the axes take any column (a select's change, as a user's pick
        # fires it): colour by a design variable, then a log x axis by its check box
        seen["colour"] = await page.js("""new Promise(function (done) {
            var gd = document.getElementById('ex-plot'), c = document.getElementById('ex-c');
            c.value = 'L12';
            c.dispatchEvent(new Event('change'));
            var lg = document.getElementById('ex-xlog');
            lg.click();
            setTimeout(function () {
                var colour = gd._fullData[1].marker.color;
                done([colour.length > 0 && typeof colour[0] === 'number',
                      gd._fullLayout.xaxis.type, !!gd.querySelector('.colorbar')]);
            }, 300);
        })""")

        # and the tables still sort
        seen["sorted"] = await page.js("""(function () {
            var t = document.querySelector('table.sortable'), th = t.tHead.rows[0].cells;
            var col = Array.prototype.findIndex.call(th, function (h) {
                return h.textContent.indexOf('peak_reaction') === 0; });
            th[col].click();
            var v = Array.prototype.map.call(t.tBodies[0].rows, function (r) {
                return parseFloat(r.cells[col].textContent); });
            for (var j = 1; j < v.length; j++) { if (v[j] < v[j - 1]) return false; }
            return v.length > 1;
        })()""")
        seen["errors"] = await page.js("document.body.dataset.jsErrors || ''")
        ws.close()
        return page.events

    try:
        events = asyncio.run(drive())
    finally:
        proc.kill()
        proc.wait()
    target = seen["target"]
    assert f"#{target}" in seen["hover"], seen["hover"]
    panel = seen["panel"]
    assert f"Candidate {target}" in panel["text"], panel["text"][:300]
    assert panel["command"] == f"pipeline show {shlex.quote(str(cli_run['fresh']))} " \
                               f"--candidate {target}", panel["command"]
    # mechanism (links at 12 positions, paths, points), motion, reactions: drawn by plotly.js
    assert panel["plots"] == 3 and panel["svg"] >= 3 and min(panel["traces"]) >= 3, panel
    head, command, svg = seen["reference"].split("|")
    assert head.startswith("Reference design") and int(svg) >= 3, seen["reference"]
    assert command.endswith(" --candidate reference"), command
    # the first view: zoomed on fronts 1 to 3, the rest of the cloud dimmed behind
    view = seen["view"]
    rank = [c for c in data["columns"] if c["key"] == "front"][0]["values"]
    n_front1 = int((rank == 1).sum())
    assert view["front"] == [n_front1, n_front1], view
    assert view["near"] == [int(((rank >= 2) & (rank <= 3)).sum())] * 2, view
    assert 0 < view["cloud"][0] < view["cloud"][1], view           # some of it beyond
    assert view["names"][1:4] == ["feasible", "fronts 2\u20133", "front 1"], view
    assert view["dim"][0] < 0.5 <= view["dim"][1], view
    # every front-1 design opens by a click where it is drawn at the first view
    clicked, opened = seen["front_clicks"]
    assert len(clicked) == n_front1 and opened == clicked, seen["front_clicks"]
    a, b, c, d, e = seen["ranges"]
    width = lambda r: abs(r[1] - r[0])                              # noqa: E731
    assert width(b["x"]) < 0.8 * width(a["x"]) and width(b["y"]) < 0.8 * width(a["y"]), (a, b)
    assert width(c["x"]) < width(b["x"]), (b, c)                    # the wheel zoomed in
    assert d["x"] == pytest.approx(a["x"]) and d["y"] == pytest.approx(a["y"]), (a, d)
    assert e["x"][0] < a["x"][0] and e["x"][1] > a["x"][1], (a, e)  # then all the designs
    assert e["y"][0] < a["y"][0] and e["y"][1] > a["y"][1], (a, e)
    front_ids = {str(i) for i in data["ids"][rank == 1]}
    clicked, opened = seen["whole_clicks"]
    assert set(clicked) == front_ids and set(opened) <= front_ids, seen["whole_clicks"]
    sel = seen["selection"]
    assert not sel["hidden"] and sel["rows"] >= seen["count0"] - 1, sel
    assert sel["table"] == min(sel["rows"], 200) and sel["first"].isdigit(), sel
    assert sel["parcoords"] == 1 and sel["dims"] == 9 and "selected" in sel["note"], sel
    # the lines' colours: one per kind of design, front 1's the highest, which
    # plotly.js draws on top (the line's depth is its colour value)
    lines = seen["lines"]
    colours = np.array(lines["color"])
    assert (colours == 3).sum() == n_front1 and colours.max() == 3 < lines["cmax"], lines["cmax"]
    assert (colours == 2).sum() == view["near"][1] and lines["ticks"][-1] == "front 1", lines
    shown, expected = seen["filtered"]
    assert 0 < shown == expected < seen["count0"], (seen["filtered"], seen["count0"])
    assert seen["count_text"].startswith(f"{shown:,} of "), seen["count_text"]
    assert seen["colour"] == [True, "log", True], seen["colour"]
    assert seen["sorted"]
    bad = [e for e in events if e.get("method") == "Runtime.exceptionThrown" or (
        e.get("method") == "Runtime.consoleAPICalled" and e["params"].get("type") == "error")
        or (e.get("method") == "Log.entryAdded" and e["params"]["entry"]["level"] == "error")]
    assert not bad and not seen["errors"], (bad, seen["errors"])
    fetched = {e["params"]["request"]["url"].split(":", 1)[0] for e in events
               if e.get("method") == "Network.requestWillBeSent"}
    assert fetched <= {"file", "data"}, fetched                    # one offline file
