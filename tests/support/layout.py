"""The layout of a picture, checked through matplotlib's own renderer (issue 28
item 3): every text the figure draws (titles, suptitles, axis and tick labels,
annotations, legend texts, free texts), every legend's frame and every peak
marker (a Line2D whose gid starts with ``PEAK_GID``) are placed by a draw
without output, and ``layout_problems`` says:

* two texts that overlap (by more than ``TOLERANCE_PX`` on each side);
* a text over a legend it is not part of, or over a peak marker;
* a legend over a peak marker;
* a text or a legend that reaches past the figure's edge (cut).

Rotated texts are compared as the rotated rectangles they are, not as their
upright bounding boxes (the cyclogram's texts run along its rings).  A text's
box is its frame when it has one (``bbox=dict(...)``)."""

from __future__ import annotations

from contextlib import contextmanager

import numpy as np
from matplotlib.legend import Legend
from matplotlib.lines import Line2D
from matplotlib.text import Text

TOLERANCE_PX = 1.5      # overlaps and overhangs this small are antialiasing, not layout
PEAK_GID = "peak"       # gid prefix of the markers of curves' peaks (plots.PEAK_GID)


class Drawn:
    """One text as drawn: its artist, its corners in pixels and whose it is."""

    def __init__(self, artist, corners, legend=None):
        self.artist, self.corners, self.legend = artist, corners, legend

    @property
    def text(self):
        return self.artist.get_text()

    def describe(self):
        where = _place(self.artist)
        kind = type(self.artist).__name__
        text = self.text if len(self.text) <= 80 else self.text[:77] + "..."
        return f"{kind} {text!r}" + (f" ({where})" if where else "")


def _place(artist):
    ax = getattr(artist, "axes", None)
    return f"in axes {_axes_name(ax)!r}" if ax is not None else ""


def _axes_name(ax):
    """An axes as the reader knows it: its label, else its title's first line."""
    name = ax.get_label() or ax.get_title() or ax.get_title("left") or "?"
    name = name.splitlines()[0]
    return name if len(name) <= 50 else name[:47] + "..."


def _corners(text, renderer):
    """The four corners (pixels) of what ``text`` covers: its frame if it has
    one, else its glyphs' box, turned with the text."""
    patch = text.get_bbox_patch()
    if patch is not None:
        e = patch.get_window_extent(renderer)
        return _box(e)
    with _wrapped(text):
        e = text.get_window_extent(renderer)
        angle = text.get_rotation() % 180.0
        if min(angle % 90.0, 90.0 - angle % 90.0) < 0.5:
            return _box(e)
        # the upright box of a turned rectangle shares its centre; the rectangle's
        # own size is the text's extent at rotation 0
        rot = text.get_rotation()
        text.set_rotation(0.0)
        try:
            flat = text.get_window_extent(renderer)
        finally:
            text.set_rotation(rot)
    c = np.array([(e.x0 + e.x1) / 2, (e.y0 + e.y1) / 2])
    w, h = flat.width / 2, flat.height / 2
    t = np.deg2rad(rot)
    r = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    return c + np.array([[-w, -h], [w, -h], [w, h], [-w, h]]) @ r.T


@contextmanager
def _wrapped(text):
    """The text as it is drawn (a ``wrap=True`` text breaks its lines at draw)."""
    if text.get_wrap():
        with text._cm_set(text=text._get_wrapped_text()):
            yield
    else:
        yield


def _box(e):
    return np.array([[e.x0, e.y0], [e.x1, e.y0], [e.x1, e.y1], [e.x0, e.y1]], float)


def _shrunk(corners, by):
    """The rectangle ``corners`` with each side moved ``by`` pixels inward."""
    u = corners[1] - corners[0]
    v = corners[3] - corners[0]
    lu, lv = np.hypot(*u), np.hypot(*v)
    su = u / lu * min(by, lu / 2) if lu > 0 else u
    sv = v / lv * min(by, lv / 2) if lv > 0 else v
    return np.array([corners[0] + su + sv, corners[1] - su + sv, corners[2] - su - sv,
                     corners[3] + su - sv])


def _overlap(a, b, tol=TOLERANCE_PX):
    """Whether two convex quadrilaterals (pixel corners) overlap by more than
    ``tol`` pixels (separating-axis test on the rectangles shrunk by tol/2)."""
    a, b = _shrunk(a, tol / 2), _shrunk(b, tol / 2)
    for poly in (a, b):
        for k in range(4):
            edge = poly[(k + 1) % 4] - poly[k]
            axis = np.array([-edge[1], edge[0]])
            if not axis.any():
                continue
            pa, pb = a @ axis, b @ axis
            if pa.max() <= pb.min() or pb.max() <= pa.min():
                return False
    return True


@contextmanager
def _recording(into):
    """Record every Text as it is drawn (with the renderer that drew it)."""
    original = Text.draw

    def draw(self, renderer):
        original(self, renderer)
        if self.get_visible() and self.get_text().strip():
            into.append((self, renderer))
    Text.draw = draw
    try:
        yield
    finally:
        Text.draw = original


def drawn_texts(fig, dpi=None):
    """Draw ``fig`` (no output) and return (the Drawn texts, the legends with
    their pixel frames, the peak markers as pixel boxes, the figure's box)."""
    if dpi is not None:
        fig.set_dpi(dpi)
    got = []
    with _recording(got):
        fig.draw_without_rendering()
    legends = [lg for lg in fig.findobj(Legend) if lg.get_visible()]
    owner = {}
    for lg in legends:
        for t in list(lg.get_texts()) + [lg.get_title()]:
            owner[id(t)] = lg
    texts = [Drawn(t, _corners(t, r), owner.get(id(t))) for t, r in got]
    renderer = fig.canvas.get_renderer()
    frames = [(lg, _box(lg.get_window_extent(renderer))) for lg in legends]
    markers = []
    for line in fig.findobj(Line2D):
        gid = line.get_gid() or ""
        if not (gid.startswith(PEAK_GID) and line.get_visible()):
            continue
        half = line.get_markersize() * fig.dpi / 72.0 / 2
        xy = line.get_transform().transform(np.column_stack(line.get_data()).astype(float))
        for x, y in xy[np.isfinite(xy).all(axis=1)]:
            markers.append((line, _box(_Ext(x - half, y - half, x + half, y + half))))
    return texts, frames, markers, _box(fig.bbox)


class _Ext:
    def __init__(self, x0, y0, x1, y1):
        self.x0, self.y0, self.x1, self.y1 = x0, y0, x1, y1


def layout_problems(fig, name="figure", dpi=None) -> list[str]:
    """What is wrong with the layout of ``fig`` (see the module's docstring),
    one line per problem naming the figure, the artists and their text."""
    texts, frames, markers, page = drawn_texts(fig, dpi)
    out = []
    boxes = np.array([np.r_[t.corners.min(axis=0), t.corners.max(axis=0)] for t in texts]
                     ).reshape(-1, 4)
    # pairs whose upright boxes meet: the only ones the exact test has to look at
    lo = np.maximum(boxes[:, None, :2], boxes[None, :, :2])
    hi = np.minimum(boxes[:, None, 2:], boxes[None, :, 2:])
    meet = ((hi - lo) > TOLERANCE_PX).all(axis=2)
    for i, j in zip(*np.nonzero(np.triu(meet, 1))):
        a, b = texts[i], texts[j]
        if _overlap(a.corners, b.corners):
            out.append(f"{name}: text overlaps text: {a.describe()} and {b.describe()}")
    for a in texts:
        for lg, frame in frames:
            if a.legend is not lg and _overlap(a.corners, frame):
                out.append(f"{name}: text over a legend: {a.describe()} over the legend of "
                           f"{_legend_name(lg)}")
        for line, box in markers:
            if _overlap(a.corners, box):
                out.append(f"{name}: text over a peak marker: {a.describe()} over "
                           f"{line.get_gid()!r}")
        if _outside(a.corners, page):
            out.append(f"{name}: text cut at the figure's edge: {a.describe()}")
    for lg, frame in frames:
        for line, box in markers:
            if _overlap(frame, box):
                out.append(f"{name}: legend over a peak marker: the legend of "
                           f"{_legend_name(lg)} over {line.get_gid()!r}")
        if _outside(frame, page):
            out.append(f"{name}: legend cut at the figure's edge: {_legend_name(lg)}")
    return out


def _legend_name(lg):
    labels = [t.get_text() for t in lg.get_texts()][:2]
    ax = lg.axes
    where = f"axes {_axes_name(ax)!r}" if ax is not None else "the figure"
    return f"{where} ({', '.join(repr(s) for s in labels)}{', ...' if len(lg.get_texts()) > 2 else ''})"


def _outside(corners, page, tol=TOLERANCE_PX):
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    return bool((lo < page.min(axis=0) - tol).any() or (hi > page.max(axis=0) + tol).any())
