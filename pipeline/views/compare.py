"""Designs side by side, for people: the comparison's table as text (`pipeline
compare`), as HTML (the report's section) and as JSON-ready rows, and one
picture that overlays the designs (the working point's path and its motion
over the crank angle, the peak |R| of every joint, M_bal over the crank
angle).  The rows and their matching are ``analysis.compare``'s."""

from __future__ import annotations

import html
import math

import numpy as np

from ..analysis.compare import Comparison
from ..base.units import unit_text


def _num(v, digits=5):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    return f"{v:.{digits}g}"


def _cell(row, k):
    """A design's value, with the crank angle of its peak and its item."""
    v = row.values[k]
    if v is None:
        return "-"
    extra = []
    if row.phi1[k] is not None:
        extra.append(f"at {row.phi1[k]:.1f}")
    if row.items[k] and row.items[k] not in row.quantity:
        extra.append(row.items[k])
    return _num(v) + (f" ({', '.join(extra)})" if extra else "")


def _change(row, k):
    c = row.change(k)
    if c is None:
        return "not compared" if k else ""
    d, rel = c
    return f"{d:+.4g}" + (f" ({100 * rel:+.1f} %)" if math.isfinite(rel) else "")


def _columns(cmp: Comparison):
    base = cmp.labels[0]
    head = ["quantity", "unit"] + cmp.labels + [f"{lab} - {base}" for lab in cmp.labels[1:]]
    body = [[r.quantity, r.unit] + [_cell(r, k) for k in range(len(cmp.labels))]
            + [_change(r, k) for k in range(1, len(cmp.labels))] for r in cmp.rows]
    return head, body


def comparison_text(cmp: Comparison) -> str:
    """The table as aligned text, the designs named above it and the notes below."""
    head, body = _columns(cmp)
    width = [max(len(str(x)) for x in col) for col in zip(head, *body)]
    lines = [f"{d.label}: {d.source} ({d.status}, omega1 {d.omega1:g} rad/s, working point "
             f"{d.working_point})" for d in cmp.designs]
    lines.append("peaks: value (at the crank angle phi1 [deg] of the peak, and its point, joint "
                 "or dyad)")
    lines.append("")
    fmt = lambda cells: "  ".join(  # noqa: E731
        (str(c).ljust(w) if i < 2 else str(c).rjust(w)) for i, (c, w) in enumerate(
            zip(cells, width))).rstrip()
    lines.append(fmt(head))
    lines.append("  ".join("-" * w for w in width))
    lines += [fmt(b) for b in body]
    if cmp.notes:
        lines.append("")
        lines += [f"note: {n}" for n in cmp.notes]
    return "\n".join(lines)


def comparison_records(cmp: Comparison) -> dict:
    """The comparison as plain data (``--format json``)."""
    def clean(v):
        return None if v is None or (isinstance(v, float) and not math.isfinite(v)) else v
    rows = []
    for r in cmp.rows:
        row = {"quantity": r.quantity, "key": r.key, "unit": r.unit, "compared": r.compared}
        for k, lab in enumerate(cmp.labels):
            row[lab] = {"value": clean(r.values[k]), "phi1_deg": clean(r.phi1[k]),
                        "item": r.items[k]}
            c = r.change(k)
            if c is not None:
                row[lab]["change"], row[lab]["relative_change"] = clean(c[0]), clean(c[1])
        rows.append(row)
    return {"designs": [{"label": d.label, "source": d.source, "status": d.status,
                         "omega1_rad_s": d.omega1, "working_point": d.working_point}
                        for d in cmp.designs], "rows": rows, "notes": list(cmp.notes)}


def comparison_html(cmp: Comparison) -> str:
    """The table and notes as HTML (the report's comparison section)."""
    head, body = _columns(cmp)
    out = ['<div class="wide"><table><tr>' + "".join(f"<th>{html.escape(h)}</th>"
                                                     for h in head) + "</tr>"]
    for b in body:
        out.append("<tr>" + "".join(f'<td class="l">{html.escape(str(c))}</td>' if i < 2 else
                                    f"<td>{html.escape(str(c))}</td>" for i, c in enumerate(b))
                   + "</tr>")
    out.append("</table></div>")
    if cmp.notes:
        out.append('<p class="note">' + "<br>".join(html.escape(n) for n in cmp.notes) + "</p>")
    return "".join(out)


# ----------------------------------------------------------------- the picture
def displacement(path):
    """The working point's displacement along the main direction of its path
    [mm] (the path's first principal axis, from its first position; the sign
    that makes the largest excursion positive)."""
    p = np.asarray(path, float)
    ok = np.isfinite(p).all(axis=1)
    if not ok.any():
        return np.full(len(p), np.nan)
    q = p - p[ok].mean(axis=0)
    _, _, vt = np.linalg.svd(q[ok], full_matrices=False)
    s = (p - p[ok][0]) @ vt[0]
    k = int(np.nanargmax(np.abs(s)))
    return s if s[k] >= 0 else -s


def comparison_figure(cmp: Comparison):
    """Overlaid: the working point's path (centred on its mean), its
    displacement along the path's main direction and M_bal against the crank
    angle, and the peak |R| of every joint as grouped bars.  Returns the Figure."""
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(2, 2, figsize=(13, 8.5), layout="constrained")
    (ax_path, ax_s), (ax_r, ax_m) = axes
    descending = False
    for k, d in enumerate(cmp.designs):
        c = f"C{k}"
        p = d.path - np.nanmean(d.path, axis=0)
        ax_path.plot(p[:, 0], p[:, 1], "-", color=c, lw=1.4,
                     label=f"{d.label} ({d.working_point})")
        ax_path.plot(p[0, 0], p[0, 1], "o", color=c, ms=4)
        stroke = d.motion.get("stroke")
        ax_s.plot(d.phi, displacement(d.path), "-", color=c, lw=1.4,
                  label=d.label + (f": stroke {stroke:.2f} mm" if stroke is not None else ""))
        descending |= len(d.phi) > 1 and d.phi[-1] < d.phi[0]
        if d.M_bal is None:     # said in the legends of both force panels
            for ax in (ax_m, ax_r):
                ax.plot([], [], "-", color=c, label=f"{d.label}: no force analysis")
        else:
            k_pk = int(np.nanargmax(np.abs(d.M_bal)))
            ax_m.plot(d.phi, d.M_bal, "-", color=c, lw=1.4,
                      label=f"{d.label}: peak |M_bal| {abs(d.M_bal[k_pk]):.2f} "
                            f"{unit_text('N*m')} at {d.phi[k_pk]:.0f} deg")
    ax_path.set_aspect("equal", adjustable="datalim")
    ax_path.set_xlabel("x - mean [mm]")
    ax_path.set_ylabel("y - mean [mm]")
    ax_path.set_title("Working point's path (dot: phi1 = first position)", fontsize=10)
    ax_s.set_ylabel("displacement along the path [mm]")
    ax_s.set_title("Working point's motion: displacement along its path's main direction",
                   fontsize=10)
    ax_m.set_ylabel(f"M_bal [{unit_text('N*m')}]")
    ax_m.set_title("Balancing moment on the crank", fontsize=10)
    for ax in (ax_s, ax_m):
        ax.set_xlabel("crank angle phi1 [deg]")
        if descending:
            ax.invert_xaxis()
    if not any(d.M_bal is not None for d in cmp.designs):
        ax_m.text(0.5, 0.5, "no force analysis in any design", ha="center", va="center",
                  transform=ax_m.transAxes)
    _reaction_bars(ax_r, cmp)
    for ax in axes.flat:
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8, loc="best")
    fig.suptitle(" vs ".join(cmp.labels), fontsize=11)
    return fig


def _reaction_bars(ax, cmp):
    """Peak |R| per joint row of the comparison (matched joints side by side)."""
    rows = [r for r in cmp.rows if r.key.startswith("reaction[")]
    ax.set_title("Peak |R| per joint", fontsize=10)
    if not rows:
        ax.text(0.5, 0.5, "no force analysis in any design", ha="center", va="center",
                transform=ax.transAxes)
        return
    n = len(cmp.designs)
    width = 0.8 / n
    x = np.arange(len(rows))
    for k, d in enumerate(cmp.designs):
        v = [np.nan if r.values[k] is None else r.values[k] for r in rows]
        if np.isfinite(v).any():
            ax.bar(x + (k - (n - 1) / 2) * width, v, width, color=f"C{k}", label=d.label)
    ax.set_xticks(x, [r.quantity.removeprefix("peak |R| ") for r in rows], fontsize=8,
                  rotation=30 if len(rows) > 8 else 0)
    ax.set_ylabel("peak |R| [N]")
