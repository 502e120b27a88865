"""The mechanism in motion over one revolution: an animated GIF (Pillow, which
matplotlib's own GIF writer uses; the frames are blitted, six times faster than
redrawing each) or, when ffmpeg is installed and the file name ends in .mp4,
an MP4 through matplotlib's ffmpeg writer (`pipeline show FILE --animate`, and
the HTML report's animated view).

An animation is bounded: at most ``MAX_FRAMES`` frames, taken evenly from the
computed positions of the revolution, at a modest resolution (``DPI``), so a
GIF stays around a megabyte whatever the study's positions per revolution.
Every file is written to a temporary name beside its target and renamed when
complete (``files.replacing``).
"""

from __future__ import annotations

import math
import shutil
import textwrap
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..base.files import check_output, literal_text, replacing

MAX_FRAMES = 120        # frames per revolution, at most
FPS = 20                # frames per second: 120 frames = one revolution in 6 s
DPI = 80                # 480 pixels high, at most 848 wide
FIGSIZE = (7.8, 6.0)    # inches: the drawing's largest width, and the height
ZOOM_WIDTH = 2.8        # inches: the working point's path magnified, when it is small
FORMATS = (".gif", ".mp4")


@dataclass
class Motion:
    """What an animation draws: the named points over one revolution."""
    title: str
    names: list              # point names, in the order of ``pos``
    labels: list             # the names with the joint reported there, "P2 (R2)"
    pos: np.ndarray          # (n, points, 2) mm
    phi: np.ndarray          # (n,) rad, crank angle phi1
    segs: list               # (i, j): the links drawn, indices into ``names``
    fixed: list              # indices of the fixed pivots
    working: int             # index of the working point
    crank_tip: int
    rot: int                 # +1 / -1: the crank's direction
    note: str = ""           # e.g. where the mechanism fails
    solved: int = -1         # positions solved from the start, before any failure (-1: all)


def motion_of(res, title=None, note="") -> Motion:
    """The Motion of a computed revolution: a scene (pipeline.solve.scene.SceneResult)
    or anything with ``plan``, ``study`` and ``dense`` (a sweep candidate's
    ``CandidateRun.scene``)."""
    from .plots import _links_to_draw, joint_labels, point_label
    plan, study = res.plan, res.study
    nv = plan.n_visible
    joints = joint_labels(plan)
    return Motion(title=title or study.title, names=list(plan.point_names[:nv]),
                  labels=[point_label(plan, i, joints) for i in range(nv)],
                  pos=np.asarray(res.dense.pos[:, :nv], float), phi=np.asarray(res.dense.phi),
                  segs=[(a, b) for a, b in _links_to_draw(plan, study) if a < nv and b < nv],
                  fixed=[plan.point(p) for p in study.mechanism.fixed],
                  working=plan.point(study.output.working_point),
                  crank_tip=plan.point(study.mechanism.crank.tip),
                  rot=int(study.mechanism.crank.rot), note=note,
                  solved=_solved(res.dense.status))


def _solved(status) -> int:
    """Positions solved from the start of the revolution, before the first one
    that is not (-1: every one)."""
    bad = np.flatnonzero(np.asarray(status) != 0)
    return int(bad[0]) if bad.size else -1


def motion_from_scene_file(path) -> Motion:
    """The Motion stored in a scene's results file (its dense positions), drawn
    with the links of the study stored in the file."""
    from ..analysis.candidate import load_study_from_results
    from .plots import _links_to_draw, joint_labels, point_label
    from ..results.storage import attr_text, open_results
    from ..base.errors import ResultsError
    with open_results(path, "scene") as f:
        study = load_study_from_results(f)
        names = [str(attr_text(x)) for x in f["mechanism"].attrs["point_names"]]
        pos = f["dense/position"][()]
        phi = np.deg2rad(f["dense/phi1"][()])
        solved = _solved(f["dense/status"][()])
        status = attr_text(f.attrs.get("status", "OK"))
    plan = study.mechanism.compile()
    where = {n: i for i, n in enumerate(names)}
    pname = plan.point_names
    missing = [pname[i] for i in range(plan.n_visible) if pname[i] not in where]
    if missing:
        raise ResultsError(path, f"its positions lack the points {', '.join(missing)} of its "
                                 "stored study")
    joints = joint_labels(plan)
    labels = [n for n in names]
    for i in range(plan.n_visible):
        labels[where[pname[i]]] = point_label(plan, i, joints)
    segs = [(where[pname[a]], where[pname[b]]) for a, b in _links_to_draw(plan, study)]
    note = "" if status == "OK" else f"{status}: drawn up to where it fails"
    return Motion(title=study.title, names=names, labels=labels, pos=pos, phi=phi, segs=segs,
                  fixed=[where[p] for p in study.mechanism.fixed if p in where],
                  working=where[study.output.working_point],
                  crank_tip=where[study.mechanism.crank.tip],
                  rot=int(study.mechanism.crank.rot), note=note, solved=solved)


def frame_indices(motion: Motion, frames=MAX_FRAMES) -> np.ndarray:
    """Up to ``frames`` positions taken evenly over the revolution, only those
    solved, before any failure (a failing mechanism is drawn up to where it
    fails)."""
    if not 2 <= frames <= MAX_FRAMES:
        raise ValueError(f"--frames must be between 2 and {MAX_FRAMES} (an animation is "
                         f"bounded), got {frames}")
    n = motion.pos.shape[0]
    idx = np.unique(np.floor(np.arange(min(frames, n)) * n / min(frames, n)).astype(np.int64))
    ok = np.isfinite(motion.pos[idx]).all(axis=(1, 2))
    if motion.solved >= 0:
        ok &= idx < motion.solved
    idx = idx[ok]
    if idx.size == 0:
        raise ValueError("nothing to animate: the mechanism is solved at no position of the "
                         "revolution")
    return idx


def animation_figure(motion: Motion, dpi=DPI):
    """The figure of the animation, ``draw(k)``, which moves it to the
    position k of ``motion``, and the artists ``draw`` changes.  The
    figure's shape follows the mechanism's (6 inches high, an even number of
    pixels each way), with the working point's path magnified beside it when
    that path is small beside the mechanism (the OV-7 eyelet moves 13 mm on a
    550 mm mechanism).  Returns (fig, draw, changing)."""
    import matplotlib.pyplot as plt
    pos = motion.pos
    n = pos.shape[0]
    upto = motion.solved if motion.solved >= 0 else n     # nothing past a failure
    every = pos[:upto].reshape(-1, 2)
    every = every[np.isfinite(every).all(axis=1)]
    lo, hi = every.min(axis=0), every.max(axis=0)
    span = float(max(hi - lo)) or 1.0
    pad = 0.08 * span
    lo, hi = lo - pad, hi + pad
    path = pos[:upto, motion.working]
    path = path[np.isfinite(path).all(axis=1)]
    size = float(np.ptp(path, axis=0).max()) if len(path) else 0.0
    zoom = 0.0 < size < 0.15 * span
    height = FIGSIZE[1]
    main = float(np.clip((height - 0.9) * (hi[0] - lo[0]) / (hi[1] - lo[1]) + 0.9, 4.4,
                         FIGSIZE[0]))
    width = main + (ZOOM_WIDTH if zoom else 0.0)
    width, height = (2 * round(x * dpi / 2) / dpi for x in (width, height))
    fig = plt.figure(figsize=(width, height), dpi=dpi, layout="constrained")
    gs = fig.add_gridspec(1, 2 if zoom else 1, width_ratios=[main, ZOOM_WIDTH] if zoom else [1])
    ax = fig.add_subplot(gs[0, 0])
    ax.set_label("animation")
    ax.update_datalim([lo, hi])     # the limits of every frame (the aspect widens one)
    ax.autoscale_view()
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.tick_params(labelsize=8)
    fixed = set(motion.fixed)
    wname = motion.names[motion.working]
    for i in range(len(motion.names)):
        if i not in fixed:     # the paths, dotted; the working point's in red
            ax.plot(pos[:upto, i, 0], pos[:upto, i, 1], ":",
                    lw=1.0 if i == motion.working else 0.7,
                    color="C3" if i == motion.working else "0.55")
    for i in fixed:
        ax.plot(*pos[0, i], "s", color="k", ms=7, zorder=4)
    links = [ax.plot([], [], "-", color="C0", lw=2.2, solid_capstyle="round")[0]
             for _ in motion.segs]
    joints, = ax.plot([], [], "o", color="k", ms=4, zorder=5)
    wp, = ax.plot([], [], "o", color="C3", ms=7, zorder=6)
    tail = max(n // 8, 2)
    trail, = ax.plot([], [], "-", color="C3", lw=1.8, alpha=0.7)
    labels = [ax.annotate(motion.labels[i], (0, 0), xytext=(4, 4), textcoords="offset points",
                          fontsize=7.5, zorder=7) for i in range(len(motion.names))]
    dot = ztrail = None
    if zoom:
        z = fig.add_subplot(gs[0, 1])
        z.set_label("working point magnified")
        z.plot(path[:, 0], path[:, 1], ":", color="C3", lw=1.0)
        c, half = (path.min(axis=0) + path.max(axis=0)) / 2, 0.6 * size
        z.update_datalim([c - half, c + half])
        z.autoscale_view()
        z.set_aspect("equal", adjustable="datalim")
        z.tick_params(labelsize=7)
        z.grid(alpha=0.3)
        z.set_title(f"{wname} (working point),\nmagnified [mm]", fontsize=8)
        dot, = z.plot([], [], "o", color="C3", ms=7)
        ztrail, = z.plot([], [], "-", color="C3", lw=1.8, alpha=0.7)
    chars = max(int(width * 72 / (0.56 * 9)), 30)     # the title wrapped to the figure
    fig.suptitle(textwrap.fill(motion.title, chars) + (
        "\n" + textwrap.fill(motion.note, chars) if motion.note else ""), fontsize=9)
    moving = [i for i in range(len(motion.names)) if i not in fixed]
    head = ax.text(0.0, 1.01, "", transform=ax.transAxes, fontsize=9, family="monospace",
                   va="bottom")
    ax.set_title(" ", fontsize=9)        # room for the crank angle above the drawing

    def draw(k):
        p = pos[k]
        for line, (a, b) in zip(links, motion.segs):
            line.set_data(p[[a, b], 0], p[[a, b], 1])
        joints.set_data(p[moving, 0], p[moving, 1])
        wp.set_data(p[[motion.working], 0], p[[motion.working], 1])
        back = [(k - j) % n for j in range(tail) if upto == n or k - j >= 0][::-1]
        trail.set_data(pos[back, motion.working, 0], pos[back, motion.working, 1])
        for i, t in enumerate(labels):
            t.xy = (p[i, 0], p[i, 1])
            t.set_visible(bool(np.isfinite(p[i]).all()))
        if dot is not None:
            dot.set_data(p[[motion.working], 0], p[[motion.working], 1])
            ztrail.set_data(pos[back, motion.working, 0], pos[back, motion.working, 1])
        turn = motion.rot * (motion.phi[k] - motion.phi[0])
        head.set_text(f"phi1 = {math.degrees(motion.phi[k]):7.1f} deg "
                      f"({math.degrees(turn) % 360.0:5.1f} of 360 turned)")

    changing = links + [joints, wp, trail] + labels + [head] + (
        [dot, ztrail] if dot is not None else [])
    return fig, draw, changing


def _writer(out: Path):
    """None for a GIF (written with Pillow here), matplotlib's ffmpeg writer
    for an MP4; a clear error for anything else, or for an MP4 without ffmpeg."""
    from matplotlib.animation import FFMpegWriter
    suffix = out.suffix.lower()
    if suffix not in FORMATS:
        raise ValueError(f"{out}: an animation is written as .gif (or .mp4 with ffmpeg); "
                         f"got {out.suffix or 'no suffix'!r}")
    if suffix == ".mp4":
        if shutil.which("ffmpeg") is None:
            raise ValueError(f"{out}: writing MP4 needs ffmpeg, which is not installed; "
                             "write a .gif instead")
        return FFMpegWriter(fps=FPS, codec="h264", extra_args=["-pix_fmt", "yuv420p"])
    return None


def _gif_frames(fig, draw, changing, idx):
    """The frames as RGB images, blitted: the still parts are drawn once and
    only ``changing`` is drawn on them for each frame (6x faster than a full
    redraw)."""
    from PIL import Image
    draw(int(idx[0]))
    fig.canvas.draw()                  # the layout, once
    fig.set_layout_engine("none")
    for a in changing:
        a.set_animated(True)
    fig.canvas.draw()
    still = fig.canvas.copy_from_bbox(fig.bbox)
    size = fig.canvas.get_width_height()
    for k in idx:
        draw(int(k))
        fig.canvas.restore_region(still)
        for a in changing:
            fig.draw_artist(a)
        yield Image.frombuffer("RGBA", size, bytes(fig.canvas.buffer_rgba()), "raw", "RGBA", 0,
                               1).convert("RGB")


def write_animation(motion: Motion, out, frames=MAX_FRAMES, dpi=DPI) -> dict:
    """Write the animation of ``motion`` to ``out``: a GIF (Pillow, one
    palette of at most 128 colours for all frames, looping), or an MP4 through
    matplotlib's ffmpeg writer when ``out`` ends in .mp4 and ffmpeg is
    installed.  Returns {animation, frames, size, pixels, duration}."""
    import matplotlib.pyplot as plt
    out = Path(out)
    writer = _writer(out)
    idx = frame_indices(motion, frames)
    fig, draw, changing = animation_figure(motion, dpi)
    try:
        w, h = fig.canvas.get_width_height()
        with replacing(out) as tmp:
            if writer is None:
                _save_gif(fig, draw, changing, idx, tmp)
            else:
                with writer.saving(fig, str(tmp), dpi), literal_text(fig):
                    for k in idx:
                        draw(int(k))
                        writer.grab_frame()
    finally:
        plt.close(fig)
    return {"animation": str(out), "frames": int(idx.size),
            "size": f"{out.stat().st_size / 1024:.0f} KiB", "pixels": f"{w} x {h}",
            "duration": f"{idx.size / FPS:.1f} s at {FPS} frames/s" + (
                " per revolution" if motion.solved < 0 else ", up to where it fails")}


def _save_gif(fig, draw, changing, idx, dest):
    """The frames ``idx`` as a looping GIF (one palette of at most 128 colours
    for all frames) into ``dest``, a path or a file object."""
    from PIL import Image
    with literal_text(fig):
        images = list(_gif_frames(fig, draw, changing, idx))
    palette = images[0].quantize(colors=128, method=Image.Quantize.MEDIANCUT)
    images = [im.quantize(palette=palette, dither=Image.Dither.NONE) for im in images]
    images[0].save(dest, format="GIF", save_all=True, append_images=images[1:],
                   duration=round(1000 / FPS), loop=0)


def gif_bytes(motion: Motion, frames=60, dpi=60) -> bytes:
    """The animation as GIF bytes (for a page that embeds it), made in memory:
    no temporary file for a kill to leave behind."""
    import io

    import matplotlib.pyplot as plt
    fig, draw, changing = animation_figure(motion, dpi)
    buf = io.BytesIO()
    try:
        _save_gif(fig, draw, changing, frame_indices(motion, frames), buf)
    finally:
        plt.close(fig)
    return buf.getvalue()


def results_kind(path) -> str:
    """'scene' or 'sweep': the kind of a results file (its errors are the
    usual ResultsError)."""
    from ..results.storage import attr_text, open_results
    with open_results(path) as f:
        return str(attr_text(f.attrs.get("kind", "?")))


def default_animation_output(path, index=None) -> Path:
    path = Path(path)
    if index is None:
        return path.with_name(f"{path.stem}_animation.gif")
    tag = "reference" if index == "reference" else f"candidate{index}"
    return path.with_name(f"{path.stem}_{tag}.gif")


def animate(path, candidate=None, out=None, frames=MAX_FRAMES) -> dict:
    """`pipeline show FILE --animate`: the mechanism of a scene results file,
    or one candidate of a sweep (``candidate``: an index, 'knee' or
    'reference'), over one revolution.  Returns a summary."""
    from ..base.progress import ticking
    with ticking("animate", after=0.2, say_done=False):  # a live line, soon
        return _animate(path, candidate, out, frames)


def _animate(path, candidate, out, frames):
    if out is not None:     # before the motion is computed: never over a results file
        out = check_output(out, inputs=(path,))
        _writer(out)
    kind = results_kind(path)
    if kind == "scene":
        if candidate is not None:
            raise ValueError(f"{path} is a scene (one design): --candidate applies to a sweep's "
                             "results file")
        motion = motion_from_scene_file(path)
        out = Path(out) if out else default_animation_output(path)
        info = {"design": motion.title}
    elif kind == "sweep":
        if candidate is None:
            raise ValueError(f"{path} is a sweep: say which design to animate with --candidate "
                             "ID (an index, 'knee' or 'reference')")
        from ..analysis.candidate import rerun_candidate
        from ..kernels import config as kc
        run = rerun_candidate(path, candidate, forces=False)
        note = "" if run.status == kc.OK else (
            f"{kc.STATUS_NAMES.get(run.status, run.status)}: drawn up to where it fails")
        motion = motion_of(run.scene, f"{run.study.title}: {run.label}", note)
        out = Path(out) if out else default_animation_output(path, run.index)
        info = {"candidate": run.index, "status": kc.STATUS_NAMES.get(run.status, run.status)}
    else:
        raise ValueError(f"{path}: a {kind} results file has nothing to animate")
    info.update(write_animation(motion, check_output(out, inputs=(path,)), frames=frames))
    return info
