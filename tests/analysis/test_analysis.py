"""Analysis, browsing, show and report of a sweep (`pipeline analyze|browse|show|report`).

The session's small sweep of the main job's study (conftest.py: synthesis_sweep)
is copied once per module; tests that write into a file work on copies of it.
"""

import json
import os
import re
import shutil
import subprocess
from io import StringIO

import h5py
import numpy as np
import pandas as pd
import pytest

from support.naive_pareto import brute_force_rank, dominates_ref
from pipeline.analysis.fronts import analyze
from pipeline.views.browse import rerun_candidate
from pipeline.cli import main
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
    with h5py.File(path, "r") as f:
        obj = [str(o) for o in f.attrs["objectives"]]
        F = np.stack([f[f"metrics/{o}"][()] for o in obj], axis=1)
        return F, f["candidates/feasible"][()]


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
        r = np.array([f["reference"][o][0] for o in f.attrs["objectives"]])
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
    # without --wide everything fits 100 columns, and the dataset listing waits for --wide
    for key in ("browse", "candidate"):
        assert max(len(ln) for ln in cli_run[key][1].splitlines()) <= 100, key
    assert "/candidates/params" not in cli_run["browse"][1] and "--wide" in cli_run["browse"][1]
    assert "representative" in cli_run["browse"][1]


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
def chromium():
    for name in ("/usr/bin/chromium", "chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    pytest.fail("headless Chromium is not installed (.ci/run installs it: apt-get install chromium)")


def test_report_is_self_contained(cli_run):
    info = json.loads(cli_run["report"][1])
    assert "run now" in info["analysis"] and info["report"].endswith("report.html")
    with h5py.File(cli_run["fresh"], "r") as f:
        assert f["analysis"].attrs["complete"]
    page = (cli_run["dir"] / "report.html").read_text()
    assert page.startswith("<!DOCTYPE html>")
    assert not re.search(r"""(src|href)\s*=\s*["'](?!data:|#)""", page), "external resource"
    assert "<link" not in page and "@import" not in page
    assert page.count('src="data:image/png;base64,') >= 4
    for words in ("Pareto fronts", "held-out", "Representative designs", "Front 1",
                  "Candidates by status", "Provenance", "[sweep]", "20261121", "sobol"):
        assert words in page, words
    # the stored study asks for 250,000; this run had N (--candidates): both said
    assert f"candidates in this run</td><td>{N:,} (the study below says 250,000" in page


def test_report_renders_in_chromium(cli_run, tmp_path):
    exe = chromium()
    html_path = cli_run["dir"] / "report.html"
    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
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
    assert total >= 4 and f'data-images-ok="{total}"' in tag
    assert "data-js-errors" not in tag
    shot = tmp_path / "report.png"
    r = subprocess.run([exe, *flags, "--window-size=1280,3000", f"--screenshot={shot}", url],
                       capture_output=True, text=True, timeout=120, env=env)
    assert r.returncode == 0 and shot.exists() and shot.stat().st_size > 50_000


def _devtools(exe, url, tmp_path):
    """A headless Chromium showing ``url``, driven over the DevTools protocol
    (its own WebSocket: no extra driver).  Yields (call, events)."""
    import asyncio
    import json as _json
    import urllib.request

    from tornado.websocket import websocket_connect

    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             f"--user-data-dir={tmp_path / 'cdp-profile'}", "--remote-debugging-port=0",
             "--window-size=1280,1800", url]
    proc = subprocess.Popen([exe, *flags], stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ, HOME=str(tmp_path)))
    port = None
    for _ in range(200):
        line = proc.stderr.readline()
        m = re.search(r"DevTools listening on ws://[^:]+:(\d+)/", line)
        if m:
            port = int(m.group(1))
            break
    assert port, "Chromium did not open its DevTools port"
    pages = _json.loads(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list").read())
    ws_url = [p for p in pages if p.get("type") == "page"][0]["webSocketDebuggerUrl"]
    return proc, ws_url


def test_report_click_on_a_front_point_shows_that_design(cli_run, tmp_path):
    """In a real headless Chromium: the page loads without console errors; a
    mouse click on a front-1 point of the explorer shows that design; a header
    click sorts a table."""
    import asyncio
    import json as _json

    from tornado.websocket import websocket_connect

    exe = chromium()
    url = (cli_run["dir"] / "report.html").resolve().as_uri()
    proc, ws_url = _devtools(exe, url, tmp_path)

    async def drive():
        ws = await websocket_connect(ws_url, max_message_size=64 << 20)
        seq, events = [0], []

        async def call(method, **params):
            seq[0] += 1
            ws.write_message(_json.dumps({"id": seq[0], "method": method, "params": params}))
            while True:
                msg = _json.loads(await ws.read_message())
                if msg.get("id") == seq[0]:
                    return msg.get("result", {})
                events.append(msg)

        async def js(expr):
            r = await call("Runtime.evaluate", expression=expr, returnByValue=True)
            assert "exceptionDetails" not in r, r["exceptionDetails"]
            return r["result"].get("value")

        await call("Runtime.enable")
        # the page (a few MB: pictures and an animation inline) is loaded and its
        # explorer drawn; on a loaded 2-core machine this can take seconds
        ready = ("document.readyState === 'complete' && "
                 "!!document.querySelector('#explorer circle.f1')")
        for _ in range(600):
            if await js(ready):
                break
            await asyncio.sleep(0.1)
        assert await js(ready), "the report did not load within 60 s"
        target = _json.loads(await js("""(function () {
            var c = document.querySelector('#explorer circle.f1');
            c.scrollIntoView({block: 'center'});
            var r = c.getBoundingClientRect(), k = Number(c.dataset.k);
            var d = JSON.parse(document.getElementById('explorer-data').textContent);
            return JSON.stringify({x: r.left + r.width / 2, y: r.top + r.height / 2,
                                   i: d.points[k].i});
        })()"""))
        x, y = target["x"], target["y"]
        await call("Input.dispatchMouseEvent", type="mouseMoved", x=x, y=y)
        tip = await js("document.getElementById('tip').style.display + '|' + "
                       "document.getElementById('tip').textContent")
        for kind in ("mousePressed", "mouseReleased"):
            await call("Input.dispatchMouseEvent", type=kind, x=x, y=y, button="left",
                       clickCount=1)
        shown = await js("document.getElementById('design-panel').dataset.candidate + '|' + "
                         "document.getElementById('design-panel').textContent")
        sorted_ok = await js("""(function () {
            var t = document.querySelector('table.sortable'), th = t.tHead.rows[0].cells;
            var col = Array.prototype.findIndex.call(th, function (h) {
                return h.textContent.indexOf('peak_reaction') === 0; });
            th[col].click();
            var v = Array.prototype.map.call(t.tBodies[0].rows, function (r) {
                return parseFloat(r.cells[col].textContent); });
            for (var j = 1; j < v.length; j++) { if (v[j] < v[j - 1]) return false; }
            return v.length > 1;
        })()""")
        errors = await js("document.body.dataset.jsErrors || ''")
        ws.close()
        return target, tip, shown, sorted_ok, errors, events

    try:
        target, tip, shown, sorted_ok, errors, events = asyncio.run(drive())
    finally:
        proc.kill()
        proc.wait()
    assert tip.startswith("block|#" + str(target["i"])), tip
    cid, text = shown.split("|", 1)
    assert cid == str(target["i"]) and f"Candidate {target['i']}" in text, shown
    assert sorted_ok
    bad = [e for e in events if e.get("method") == "Runtime.exceptionThrown" or (
        e.get("method") == "Runtime.consoleAPICalled" and e["params"].get("type") == "error")]
    assert not bad and not errors, (bad, errors)
