"""What the pictures write and where: one style of units, one name per link, the
markers of curves' peaks, and labels placed clear of each other once the layout
is known.
Only drawing; no number is changed here."""

from __future__ import annotations

import numpy as np
from matplotlib.artist import Artist

PEAK_GID = "peak"       # gid prefix of a curve's peak marker (tests/support/layout.py finds them)


def link_name(study, label: str) -> str:
    """The name of the link ``label`` ('2_3', the vector P2 -> P3 of ``[output]
    links``) in every picture: the body that carries it as the forces name it
    ('lead 2-3'; 'ternary 3-4-5 (3_5)' where the body has more joints or runs
    the other way), else 'link 2_3'."""
    links = dict(zip(study.output.link_labels, study.output.links))
    a, b = links.get(label, (None, None))
    for body in getattr(study.mechanism, "bodies", ()) or ():
        if a in body.joints and b in body.joints:
            if tuple(body.joints) == (a, b):
                return body.name
            return f"{body.name} ({label})"
    return f"link {label}"


def is_constant(y) -> bool:
    """Whether a curve has nothing to mark: no finite sample, or the same value
    everywhere (to rounding)."""
    y = np.asarray(y, float)
    y = y[np.isfinite(y)]
    return not y.size or float(np.ptp(y)) <= 1e-9 * max(float(np.abs(y).max()), 1e-300)


def mark_peak(ax, x, y, colour="C3", ms=3.5, what=""):
    """The marker of a curve's peak, with the gid the layout test knows."""
    return ax.plot([x], [y], "o", color=colour, ms=ms, gid=f"{PEAK_GID} {what}".strip())[0]


# ----------------------------------------------------------------- labels placed at draw time
POINT_OFFSETS = ((4, 4, "left", "bottom"), (-4, 4, "right", "bottom"),
                 (4, -4, "left", "top"), (-4, -4, "right", "top"),
                 (0, 8, "center", "bottom"), (0, -8, "center", "top"),
                 (9, 0, "left", "center"), (-9, 0, "right", "center"),
                 (10, 12, "left", "bottom"), (-10, 12, "right", "bottom"),
                 (10, -12, "left", "top"), (-10, -12, "right", "top"))


def around(dx, dy, distance=9.0):
    """Offsets (points) to try for a label pushed along (dx, dy) from its point:
    that way first, then turned either side, then farther."""
    d = np.array([dx, dy], float)
    d = d / np.hypot(*d) if np.hypot(*d) > 0 else np.array([1.0, 0.0])
    out = []
    for scale in (1.0, 1.6):
        for turn in (0, 40, -40, 80, -80, 130, -130, 180):
            t = np.deg2rad(turn)
            r = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]]) @ d
            out.append((*(distance * scale * r), "center", "center"))
    return tuple(out)


class LabelPlacer(Artist):
    """Places its labels when the axes is drawn, after the layout is settled:
    each label (an Annotation in offset points) takes the first of its
    offsets where it covers no label placed before it, no legend and no peak
    marker of the axes, inside the axes' frame; a label marked ``optional`` that finds no such place is
    left out, the others keep their first offset.  Labels are placed in the
    order they were added (the more important first)."""

    def __init__(self):
        super().__init__()
        self.labels = []
        self.set_zorder(-100)          # drawn before the labels it moves
        self.set_in_layout(False)

    def add(self, annotation, offsets, optional=False):
        self.labels.append((annotation, tuple(offsets), optional))

    def draw(self, renderer):
        ax = self.axes
        taken = [t.get_window_extent(renderer) for t in (ax.title, ax._left_title, ax._right_title)
                 if t.get_visible() and t.get_text()]
        frame = ax.bbox
        legend = ax.get_legend()
        if legend is not None and legend.get_visible():
            taken.append(legend.get_window_extent(renderer))
        for line in ax.get_lines():
            if (line.get_gid() or "").startswith(PEAK_GID):
                half = line.get_markersize() * ax.figure.dpi / 72.0 / 2
                for x, y in line.get_transform().transform(np.column_stack(line.get_data())):
                    taken.append(_box(x - half, y - half, x + half, y + half))
        for ann, offsets, optional in self.labels:
            ann.set_visible(True)
            chosen = None
            for dx, dy, ha, va in offsets:
                ann.xyann = (dx, dy)
                ann.set_horizontalalignment(ha)
                ann.set_verticalalignment(va)
                box = ann.get_window_extent(renderer)
                inside = (box.x0 >= frame.x0 - 1 and box.x1 <= frame.x1 + 1
                          and box.y0 >= frame.y0 - 1 and box.y1 <= frame.y1 + 1)
                if inside and not any(_meet(box, other) for other in taken):
                    chosen = box
                    break
            if chosen is None:
                if optional:
                    ann.set_visible(False)
                    continue
                dx, dy, ha, va = offsets[0]
                ann.xyann = (dx, dy)
                ann.set_horizontalalignment(ha)
                ann.set_verticalalignment(va)
                chosen = ann.get_window_extent(renderer)
            taken.append(chosen)


def placer(ax) -> LabelPlacer:
    """The axes' label placer (made and added on first use)."""
    for child in ax.get_children():
        if isinstance(child, LabelPlacer):
            return child
    p = LabelPlacer()
    ax.add_artist(p)
    return p


def _box(x0, y0, x1, y1):
    from matplotlib.transforms import Bbox
    return Bbox([[x0, y0], [x1, y1]])


def _meet(a, b, margin=1.0):
    return (min(a.x1, b.x1) - max(a.x0, b.x0) > -margin
            and min(a.y1, b.y1) - max(a.y0, b.y0) > -margin)
