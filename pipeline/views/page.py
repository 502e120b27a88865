"""What the HTML report is made of besides its pictures: the Jinja2 templates
(``views/templates/``, package data), the inline assets they take (style
sheet, scripts, the plotly.js bundle) and data for the page's scripts written
as compact, script-safe JSON.

Why a template engine: the page is HTML laid out in HTML files a reader can
open, with autoescape on, so a name or unit from a study file is always text,
never markup (it used to be f-strings, where each ``html.escape`` was one
forgotten call away from an injection).

Why Plotly (plotly.js) for the explorer: one library gives what the explorer
needs and nothing has to be hand-written: WebGL scatter (``scattergl``) draws
10^5 designs smoothly, box and lasso selection, zoom and pan, log axes, hover
labels, and parallel coordinates (``parcoords``) for the selection, all
offline from one inlined bundle.  The price is size: the bundle is about
4.8 MB (plotly.js 4, as shipped by the ``plotly`` Python package, whose
``get_plotlyjs()`` is the only thing used from it).  Bokeh needs its own
server or a larger set of bundles for the same; Vega-Lite has no WebGL and
slows down past a few 10^4 points.

Why packed: the bundle and the explorer's data go into the page gzip-compressed
and base64-written (``packed``), and the browser inflates them with its own
DecompressionStream (templates/unpack.js): the bundle is 1.9 MB instead of 4.8,
and the page of the main job's 250,000 candidates stays under 5 MB.  The
explorer's columns are one block of binary arrays (``ArrayBlock``), which the
page views as typed arrays without reading a number as text.
"""

from __future__ import annotations

import base64
import gzip
import json
import math
import re
from functools import lru_cache
from importlib import resources

import numpy as np

DIGITS = 5          # significant digits of the numbers the page's scripts get


@lru_cache(maxsize=1)
def environment():
    """The Jinja2 environment of the report's templates (autoescape on)."""
    import jinja2
    env = jinja2.Environment(loader=jinja2.PackageLoader("pipeline.views", "templates"),
                             autoescape=True, undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True)
    env.globals["asset"] = asset
    return env


def render(template, **context) -> str:
    """``templates/<template>`` rendered with ``context``."""
    return environment().get_template(template).render(**context)


def markup(text):
    """HTML the package wrote itself (from its own escaped parts), to go into a
    template unescaped."""
    from markupsafe import Markup
    return Markup(text)


def _inline(text):
    """``text`` safe to stand inside <script> or <style>: no closing tag of
    either (nothing the HTML parser would end the element at)."""
    if re.search(r"</(script|style)", text, re.IGNORECASE):
        text = re.sub(r"</(script|style)", r"<\\/\1", text, flags=re.IGNORECASE)
    return markup(text)


@lru_cache(maxsize=None)
def asset(name):
    """A style sheet or script of ``templates/`` as it goes inline."""
    text = (resources.files("pipeline.views") / "templates" / name).read_text("utf-8")
    return _inline(text)


@lru_cache(maxsize=1)
def plotly_js():
    """The plotly.js bundle of the installed ``plotly`` package, ``packed``
    (templates/unpack.js runs it)."""
    from plotly.offline import get_plotlyjs
    return packed(get_plotlyjs())


def packed(content):
    """``content`` (text, or bytes) gzip-compressed and written in base64, for
    a <script> element that templates/unpack.js inflates (the alphabet of
    base64 holds no ``<``, ``>`` or ``&``: nothing in it can close the element
    or start markup).  The same content gives the same page (no time stamp in
    the gzip header)."""
    data = content if isinstance(content, bytes) else str(content).encode("utf-8")
    return markup(base64.b64encode(gzip.compress(data, compresslevel=9, mtime=0))
                  .decode("ascii"))


def unpacked(text) -> bytes:
    """What ``packed`` packed, as bytes (for tests and tools that read a page)."""
    return gzip.decompress(base64.b64decode(str(text)))


# the typed arrays' short names (plotly.js's, in its {dtype, bdata} format), the
# bytes little-endian as in every browser
ARRAY_TYPES = {"i1": "i1", "u1": "u1", "i2": "<i2", "u2": "<u2", "i4": "<i4", "f4": "<f4",
               "f8": "<f8"}


class ArrayBlock:
    """Numeric arrays packed into one binary block for a page's script (binary:
    no number written and parsed as text; one block: gzip works across all of
    them).  ``add`` appends an array and gives its place, ``{"dtype", "offset",
    "length"}``, where the script views the inflated block through a typed
    array of that type; ``packed`` is the block for the page.  Whole numbers go
    as the smallest integer type that holds them (float64 beyond int32: exact to
    2^53, as JavaScript's numbers); anything else to ``digits`` significant
    digits (``rounded``: gzip packs these much tighter than the full float) as
    float32, NaN where a value is missing.  Each array starts at a multiple of
    8 bytes, as a typed array's view needs."""

    def __init__(self, digits=DIGITS):
        self.digits, self.parts, self.size = digits, [], 0

    def add(self, values) -> dict:
        x = np.asarray(values, dtype=np.float64).ravel()
        dtype = "f4"
        if x.size and np.isfinite(x).all() and (x == np.rint(x)).all():
            lo, hi = x.min(), x.max()
            dtype = next((k for k in ("i1", "u1", "i2", "u2", "i4")
                          if np.iinfo(ARRAY_TYPES[k]).min <= lo
                          and hi <= np.iinfo(ARRAY_TYPES[k]).max), "f8")
        y = x if dtype != "f4" else np.where(np.isfinite(x), rounded(x, self.digits), np.nan)
        data = y.astype(ARRAY_TYPES[dtype]).tobytes()
        spec = {"dtype": dtype, "offset": self.size, "length": int(x.size)}
        data += bytes(-len(data) % 8)
        self.parts.append(data)
        self.size += len(data)
        return spec

    def packed(self):
        return packed(b"".join(self.parts))


def block_array(block: bytes, spec) -> np.ndarray:
    """One array of an ``ArrayBlock`` (its bytes, ``unpacked``) at ``spec``."""
    return np.frombuffer(block, dtype=ARRAY_TYPES[spec["dtype"]], count=spec["length"],
                         offset=spec["offset"])


def script_json(obj):
    """``obj`` as JSON to stand inside <script type="application/json">:
    ``<``, ``>`` and ``&`` written as \\u003c, \\u003e, \\u0026 (and the two
    line separators JavaScript once choked on), so that no text of a user's
    (a name, a unit) can close the element or start markup."""
    text = json.dumps(obj, separators=(",", ":"), allow_nan=False)
    for ch, esc in (("&", "\\u0026"), ("<", "\\u003c"), (">", "\\u003e"),
                    ("\u2028", "\\u2028"), ("\u2029", "\\u2029")):
        text = text.replace(ch, esc)
    return markup(text)


# ----------------------------------------------------------------- compact numbers
def rounded(values, digits=DIGITS) -> np.ndarray:
    """``values`` to ``digits`` significant digits, as the floats nearest those
    decimals (so that JSON writes at most ``digits`` digits), with -0 made 0."""
    x = np.array(values, dtype=np.float64, copy=True).ravel()
    ok = np.isfinite(x) & (x != 0)
    if ok.any():
        y = x[ok]
        d = (digits - 1) - np.floor(np.log10(np.abs(y))).astype(np.int64)
        r = np.empty_like(y)
        up = (d >= 0) & (d <= 22)   # an integer over an exact power of ten: the nearest float
        s = 10.0 ** d[up]
        r[up] = np.rint(y[up] * s) / s
        down = d < 0                # an integer times a power of ten
        s = 10.0 ** -d[down]
        r[down] = np.rint(y[down] / s) * s
        for k in np.flatnonzero(d > 22):   # below 1e-18: rare enough for a loop
            r[k] = float(f"{y[k]:.{digits}g}")
        x[ok] = r
    return x + 0.0            # -0.0 + 0.0 is +0.0


def json_numbers(values, digits=DIGITS) -> list:
    """A JSON-ready list of ``values``: ``digits`` significant digits, whole
    numbers as integers when every value is whole, NaN and infinities as null."""
    x = rounded(values, digits)
    finite = np.isfinite(x)
    if finite.all() and (x == np.rint(x)).all() and (np.abs(x) < 2.0 ** 53).all():
        return x.astype(np.int64).tolist()
    out = x.tolist()
    for k in np.flatnonzero(~finite):
        out[k] = None
    return out


def json_number(v, digits=DIGITS):
    """One number the way ``json_numbers`` writes it (None for NaN)."""
    v = float(v)
    if not math.isfinite(v):
        return None
    return json_numbers([v], digits)[0]
