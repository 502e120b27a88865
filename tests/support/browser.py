"""Headless Chromium for the report's browser tests, driven over the DevTools
protocol (its own WebSocket, through tornado: no extra driver), and where the
explorer draws its designs (views/templates/explorer.js)."""

import asyncio
import json
import os
import re
import shutil
import subprocess

import pytest

# explorer.js's traces, in the order drawn: infeasible, feasible, fronts 2 to Z, front 1,
# knee, reference design, the design shown
FRONT_TRACE = 3
# plotly.js takes two clicks closer than its doubleClickDelay (500 ms, the explorer
# keeps plotly's default) for a double click, which zooms out: a person's clicks on one
# design after another are further apart
CLICK_PACE_S = 0.6

# WebGL (the explorer's scattergl and parcoords) without a GPU: SwiftShader, which
# headless Chromium takes only when asked (its automatic fallback is deprecated)
WEBGL = ["--disable-gpu", "--enable-unsafe-swiftshader"]


def chromium():
    """The headless Chromium here (.ci/run installs it)."""
    for name in ("/usr/bin/chromium", "chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    pytest.fail("headless Chromium is not installed "
                "(.ci/run installs it: apt-get install chromium)")


def devtools(exe, url, tmp_path):
    """A headless Chromium showing ``url``, driven over the DevTools protocol
    (its own WebSocket: no extra driver).  Returns (process, page WebSocket URL)."""
    import urllib.request

    flags = ["--headless", "--no-sandbox", *WEBGL, "--no-first-run",
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
    pages = json.loads(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list").read())
    ws_url = [p for p in pages if p.get("type") == "page"][0]["webSocketDebuggerUrl"]
    return proc, ws_url


class Page:
    """One page over the DevTools protocol: ``call`` a method, evaluate ``js``,
    send real mouse and keyboard input; every event is kept in ``events``."""

    def __init__(self, ws):
        self.ws, self.seq, self.events = ws, 0, []

    async def call(self, method, **params):
        return (await self.calls([(method, params)]))[0]

    async def calls(self, requests):
        """Every (method, params) of ``requests`` sent at once, then their results
        read, in order (each answered once the page has handled it)."""
        sent = {}
        for method, params in requests:
            self.seq += 1
            sent[self.seq] = method
            self.ws.write_message(json.dumps({"id": self.seq, "method": method,
                                              "params": params}))
        results = {}
        while len(results) < len(sent):
            msg = json.loads(await self.ws.read_message())
            if msg.get("id") in sent:
                assert "error" not in msg, (sent[msg["id"]], msg["error"])
                results[msg["id"]] = msg.get("result", {})
            else:
                self.events.append(msg)
        return [results[i] for i in sent]

    async def js(self, expr):
        r = await self.call("Runtime.evaluate", expression=expr, returnByValue=True,
                            awaitPromise=True)
        assert "exceptionDetails" not in r, r["exceptionDetails"]
        return r["result"].get("value")

    async def until(self, expr, what, seconds=60):
        import asyncio
        for _ in range(int(seconds * 10)):
            if await self.js(expr):
                return
            await asyncio.sleep(0.1)
        raise AssertionError(f"{what} within {seconds} s")

    async def relayouts(self):
        """How many relayouts the explorer's plot has finished (counted from the
        first call): plotly.js applies a wheel's zoom a moment after the wheel,
        and an input sent before that is undone by it."""
        return await self.js("""(function () {
            var gd = document.getElementById('ex-plot');
            if (window.__relayouts === undefined) {
                window.__relayouts = 0;
                gd.on('plotly_relayout', function () { window.__relayouts += 1; });
            }
            return window.__relayouts; })()""")

    async def moved(self, before, what, relayouts):
        """The plot's area (PLOT_AREA) once its axes' ranges differ from ``before``'s
        and a relayout has finished since ``relayouts`` were counted."""
        was = json.dumps(before["x"] + before["y"])
        await self.until(f"window.__relayouts > {relayouts} && (function (a, b) {{ return "
                         f"a.x.concat(a.y).some(function (v, i) {{ return v !== b[i]; }}); "
                         f"}})({PLOT_AREA}, {was})", what, 20)
        return await self.js(PLOT_AREA)

    async def mouse(self, kind, x, y, **kw):
        await self.call("Input.dispatchMouseEvent", type=kind, x=x, y=y, **kw)

    async def click(self, x, y):
        await self.mouse("mousePressed", x, y, button="left", buttons=1, clickCount=1)
        await self.mouse("mouseReleased", x, y, button="left", buttons=0, clickCount=1)

    async def double_click(self, x, y, tries=5):
        """A double click on the explorer's plot that plotly.js saw (its
        ``plotly_doubleclick``): two presses sent at once, their answers read after.
        plotly.js counts them as one double click only within its doubleClickDelay
        (500 ms) of the page's clock; a loaded machine drawing between the two presses
        can part them, and plotly.js then sees two single clicks, which do nothing
        at an empty spot (EMPTY_SPOT): the double click is sent again, past the window."""
        import asyncio
        await self.js("""(function () {
            if (window.__doubleclicks === undefined) {
                window.__doubleclicks = 0;
                document.getElementById('ex-plot').on('plotly_doubleclick',
                    function () { window.__doubleclicks += 1; });
            }})()""")
        for _ in range(tries):
            seen = await self.js("window.__doubleclicks")
            await self.calls([("Input.dispatchMouseEvent",
                               dict(type=kind, x=x, y=y, button="left", buttons=buttons,
                                    clickCount=k))
                              for k in (1, 2)
                              for kind, buttons in (("mousePressed", 1), ("mouseReleased", 0))])
            if await self.js(f"window.__doubleclicks > {seen}"):
                return
            await asyncio.sleep(CLICK_PACE_S)
        raise AssertionError(f"plotly.js saw no double click in {tries} tries")

    async def drag(self, x0, y0, x1, y1, steps=8):
        await self.mouse("mouseMoved", x0, y0)
        await self.mouse("mousePressed", x0, y0, button="left", buttons=1, clickCount=1)
        for k in range(1, steps + 1):
            await self.mouse("mouseMoved", x0 + (x1 - x0) * k / steps,
                             y0 + (y1 - y0) * k / steps, button="left", buttons=1)
        await self.mouse("mouseReleased", x1, y1, button="left", buttons=0, clickCount=1)

    async def centre(self, selector):
        """Scroll ``selector`` into view; its centre in the viewport."""
        r = await self.js(f"""(function () {{
            var e = document.querySelector({selector!r});
            e.scrollIntoView({{block: 'center'}});
            var r = e.getBoundingClientRect();
            return [r.left + r.width / 2, r.top + r.height / 2];
        }})()""")
        return r[0], r[1]


# where a design of the explorer's plot is, in viewport pixels: trace ``t``'s point ``k``
POINT = """(function (t, k) {
    var gd = document.getElementById('ex-plot'), fl = gd._fullLayout;
    var r = gd.getBoundingClientRect(), tr = gd._fullData[t], xa = fl.xaxis, ya = fl.yaxis;
    return {x: r.left + xa._offset + xa.l2p(xa.d2l(tr.x[k])),
            y: r.top + ya._offset + ya.l2p(ya.d2l(tr.y[k])), id: tr.text[k]};
})"""
# the front-1 design farthest, in pixels, from every other design drawn (the cloud
# and the fronts, traces 0 to FRONT_TRACE): the one a hover must name (front 1 can
# be crowded)
ISOLATED = """(function () {
    var gd = document.getElementById('ex-plot'), fl = gd._fullLayout, xa = fl.xaxis, ya = fl.yaxis;
    function px(t, k) { return [xa.l2p(xa.d2l(t.x[k])), ya.l2p(ya.d2l(t.y[k]))]; }
    var front = gd._fullData[%(front)d], best = -1, far = -1;
    for (var k = 0; k < front.x.length; k++) {
        var p = px(front, k), near = Infinity;
        for (var t = 0; t <= %(front)d; t++) {
            var tr = gd._fullData[t];
            for (var j = 0; j < tr.x.length; j++) {
                if (!isFinite(tr.x[j]) || !isFinite(tr.y[j]) ||
                    (t === %(front)d && j === k)) continue;
                var q = px(tr, j);
                near = Math.min(near, Math.hypot(q[0] - p[0], q[1] - p[1]));
            }
        }
        if (near > far) { far = near; best = k; }
    }
    return best;
})()""" % {"front": FRONT_TRACE}
# a spot of the plot's zoom surface (plotly's drag rectangle there, not the legend or
# the mode bar over it) as far, in pixels, from every design drawn as a coarse grid
# finds: a press there opens no design (a design drawn on a loaded machine between the
# two presses of a double click would part them)
EMPTY_SPOT = """(function () {
    var gd = document.getElementById('ex-plot'), fl = gd._fullLayout, xa = fl.xaxis, ya = fl.yaxis;
    var r = gd.getBoundingClientRect(), pts = [], best = null, far = -1;
    gd._fullData.forEach(function (tr) {
        for (var j = 0; tr.x && j < tr.x.length; j++) {
            var x = xa.l2p(xa.d2l(tr.x[j])), y = ya.l2p(ya.d2l(tr.y[j]));
            if (isFinite(x) && isFinite(y)) pts.push([x, y]);
        }
    });
    for (var i = 1; i < 20; i++) {
        for (var k = 1; k < 20; k++) {
            var x = fl._size.w * i / 20, y = fl._size.h * k / 20, near = Infinity;
            var on = document.elementFromPoint(r.left + xa._offset + x, r.top + ya._offset + y);
            if (!on || !on.classList.contains('nsewdrag')) continue;
            pts.forEach(function (p) { near = Math.min(near, Math.hypot(p[0] - x, p[1] - y)); });
            if (near > far) { far = near; best = [x, y]; }
        }
    }
    return {x: r.left + xa._offset + best[0], y: r.top + ya._offset + best[1], px: far};
})()"""
PLOT_AREA = """(function () {
    var gd = document.getElementById('ex-plot'), fl = gd._fullLayout;
    var r = gd.getBoundingClientRect();
    return {l: r.left + fl._size.l, t: r.top + fl._size.t, w: fl._size.w, h: fl._size.h,
            x: fl.xaxis.range.slice(), y: fl.yaxis.range.slice()};
})()"""


# where the page records when the explorer became ready to use (ms from the start of
# the navigation, the browser's own clock): installed before the page's scripts run
WATCH_READY = """(function () {
    new MutationObserver(function () {
        if (document.body && document.body.dataset.explorer === 'ready' && !window.__readyMs) {
            window.__readyMs = performance.now();
        }
    }).observe(document, {attributes: true, subtree: true, attributeFilter: ['data-explorer']});
})();"""


async def open_page(page, url, events=("Runtime", "Page")):
    """Navigate ``page`` to ``url`` and wait until its explorer is ready; returns
    how long that took (ms, by the page's clock)."""
    for domain in events:
        await page.call(f"{domain}.enable")
    await page.call("Page.addScriptToEvaluateOnNewDocument", source=WATCH_READY)
    await page.call("Page.navigate", url=url)
    # the page (MBs: plotly.js, pictures and an animation inline) is loaded and its
    # explorer drawn; on a loaded 2-core machine this takes seconds
    await page.until("document.readyState === 'complete' && "
                     "document.body.dataset.explorer === 'ready' && !!window.__readyMs",
                     "the explorer drew")
    return await page.js("window.__readyMs")


async def click_each_front_1_design(page, still=True):
    """Click every front-1 design where the plot draws it, at the view as it is
    (the page scrolled to the plot first); returns (the ids clicked, the ids
    the design panel then showed, one per click).  ``still``: the view must not
    move (an autoranged view may: it takes in the ring around the design shown)."""
    await page.centre("#ex-plot")
    view = await page.js(PLOT_AREA)
    n = await page.js(f"document.getElementById('ex-plot')._fullData[{FRONT_TRACE}].x.length")
    panel = "document.getElementById('design-panel')"
    clicked, opened = [], []
    for k in range(n):
        await asyncio.sleep(CLICK_PACE_S)
        p = await page.js(f"{POINT}({FRONT_TRACE}, {k})")
        await page.js(f"delete {panel}.dataset.candidate")      # a click that opens sets it
        await page.click(p["x"], p["y"])
        await page.until(f"{panel}.dataset.candidate !== undefined && "
                         f"{panel}.dataset.drawn !== 'pending'",
                         f"a design opened by the click on #{p['id']}", 20)
        clicked.append(p["id"])
        opened.append(await page.js(f"{panel}.dataset.candidate"))
        now = await page.js(PLOT_AREA)
        assert not still or (now["x"], now["y"]) == (view["x"], view["y"]), \
            ("the view moved", view, now)
    return clicked, opened
