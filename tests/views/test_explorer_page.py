"""The report of the README's main job at its full size (studies/ov7_synthesis.toml,
250,000 candidates) in headless Chromium (issue 55): the page is at most 5 MB, its
explorer is ready for use soon after plotly.js itself is, and at the first view a
click on each front-1 point opens that design.

Slow: the sweep, its analysis and its report take tens of seconds on two cores,
the browser half a minute more.  Times are compared with the same browser's load
of plotly.js alone (the page's fixed cost), never with a number of seconds."""

import asyncio

import pytest

from pipeline.cli import main
from pipeline.views.page import asset, plotly_js
from support.browser import Page, chromium, click_each_front_1_design, devtools, open_page
from support.html_page import explorer_data

STUDY = "ov7_synthesis.toml"
MAX_PAGE_BYTES = 5_000_000       # issue 55: the page of the 250,000-candidate sweep
# the explorer ready (data inflated and viewed, the scatter drawn, clicks wired) within
# this many times the load of plotly.js alone with one WebGL scatter drawn: the page's
# own work at most as much again as the library's (about 1.3 on the 2-core machine)
MAX_READY_RATIO = 2.0

# plotly.js, packed and run as the report runs it, and one WebGL scatter
BASELINE = """<!DOCTYPE html><html><head><meta charset="utf-8"></head><body>
<div id="p"></div>
<script type="application/octet-stream" id="plotly-js">{plotly}</script>
<script>{unpack}</script>
<script>
window.plotlyReady.then(function () {{
  return Plotly.newPlot('p', [{{type: 'scattergl', mode: 'markers', x: [1, 2], y: [2, 1]}}]);
}}).then(function () {{ document.body.dataset.explorer = 'ready'; }});
</script></body></html>
"""


@pytest.mark.slow
def test_the_main_jobs_page_is_small_ready_soon_and_opens_every_front_1_design(
        studies, tmp_path, capsys):
    results, html = tmp_path / "ov7_synthesis.h5", tmp_path / "report.html"
    assert main(["run", str(studies / STUDY), "-o", str(results), "-q"]) == 0
    assert main(["report", str(results), "-o", str(html), "-q"]) == 0
    page = html.read_text()
    data = explorer_data(page)
    assert data["counts"]["candidates"] == 250_000
    n_front1 = len(data["front1"])
    assert n_front1 >= 10
    size = html.stat().st_size
    assert size <= MAX_PAGE_BYTES, size

    baseline = tmp_path / "baseline.html"
    baseline.write_text(BASELINE.format(plotly=plotly_js(), unpack=asset("unpack.js")))
    seen = {"page": [], "baseline": []}

    async def load(path, ws_url, clicks):
        from tornado.websocket import websocket_connect
        ws = await websocket_connect(ws_url, max_message_size=64 << 20)
        page = Page(ws)
        ready = await open_page(page, path.resolve().as_uri())
        if clicks:
            seen["clicks"] = await click_each_front_1_design(page)
            seen["errors"] = await page.js("document.body.dataset.jsErrors || ''")
        ws.close()
        return ready

    # each load a first one, as a newcomer's: its own browser and profile (a browser
    # that ran plotly.js once runs it again from its cache, several times faster);
    # each twice, in turn, the best of each compared
    for k in range(2):
        for name, path in (("baseline", baseline), ("page", html)):
            folder = tmp_path / f"{name}{k}"
            folder.mkdir()
            proc, ws_url = devtools(chromium(), "about:blank", folder)
            try:
                seen[name].append(asyncio.run(load(path, ws_url, name == "page" and k == 1)))
            finally:
                proc.kill()
                proc.wait()
    ready, base = min(seen["page"]), min(seen["baseline"])
    with capsys.disabled():
        print(f"\nthe main job's report: {size:,} bytes, explorer ready in {ready:.0f} ms, "
              f"plotly.js alone {base:.0f} ms ({ready / base:.2f}x), "
              f"front-1 clicks {sum(a == b for a, b in zip(*seen['clicks']))} of {n_front1}")
    assert ready <= MAX_READY_RATIO * base, (seen["page"], seen["baseline"])
    clicked, opened = seen["clicks"]
    assert len(clicked) == n_front1 and opened == clicked, seen["clicks"]
    assert not seen["errors"], seen["errors"]
