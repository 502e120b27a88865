"""The pictures of the thesis (issue 14 item 7): small multiples of the kinematics,
the circular cyclogram, eps1 against phi1, the drawings' colour key, joint names and
arrows, and the animation (`pipeline show --animate`, the report's animated view).

The scenes are solved once per module; the sweep for `show --animate` and the report
is small.  Figures are checked through their artists (labels and gids the plot
functions set), never by pixels."""

import base64
import io
import math
import re
import shutil

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from PIL import Image  # noqa: E402

from pipeline.views import plots  # noqa: E402
from pipeline.views.animate import MAX_FRAMES, frame_indices, motion_of, write_animation  # noqa: E402
from pipeline.views.show import OV7_PHASES  # noqa: E402
from pipeline.cli import main  # noqa: E402
from pipeline.solve.scene_study import solve_scene  # noqa: E402
from pipeline.solve.cyclogram import DWELL_RESIDUAL, output_motion  # noqa: E402
from pipeline.study.reader import load_study  # noqa: E402
from support import naive  # noqa: E402

SCENES = ("ov7_base", "warp_feed_fourbar", "takeup_dynamics")
# links of [output] links x 3 panels + moving named points x 2 panels
PANELS = {"ov7_base": 7 * 3 + 5 * 2,            # P2 P3 P5 P7 P9
          "warp_feed_fourbar": 3 * 3 + 3 * 2,   # P2 P3 P5
          "takeup_dynamics": 3 * 3 + 5 * 2}     # P2 P3 P4 P6 P7


@pytest.fixture(scope="module")
def scenes(studies):
    return {s: solve_scene(load_study(studies / f"{s}.toml")) for s in SCENES}


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _gif(data_or_path):
    im = Image.open(io.BytesIO(data_or_path) if isinstance(data_or_path, bytes)
                    else data_or_path)
    assert im.format == "GIF"
    return im


# ---------------------------------------------------------------- small multiples
@pytest.mark.parametrize("name", SCENES)
def test_small_multiples_have_a_panel_per_link_quantity_and_point(scenes, name):
    res = scenes[name]
    fig = plots.kinematics_figure(res)
    assert isinstance(fig, Figure)
    panels = [ax for ax in fig.axes if ax.get_label().startswith(("link ", "point "))]
    links = list(res.study.output.link_labels)
    points = [res.plan.point_names[i] for i in plots.moving_points(res)]
    assert len(panels) == len(links) * 3 + len(points) * 2 == PANELS[name]
    labels = {ax.get_label() for ax in panels}
    for lab in links:
        assert {f"link {lab} angle", f"link {lab} omega", f"link {lab} eps"} <= labels
    for p in points:
        assert {f"point {p} velocity", f"point {p} acceleration"} <= labels
    for ax in panels:      # every panel has its curve, finite over the revolution
        y = ax.get_lines()[0].get_ydata()
        assert len(y) == res.dense.phi.shape[0] and np.isfinite(y).all(), ax.get_label()


def test_small_multiples_mark_the_refined_peaks(scenes):
    res = scenes["ov7_base"]
    fig = plots.kinematics_figure(res)
    ax = next(a for a in fig.axes if a.get_label() == "point P9 acceleration")
    peak = next(p for p in res.peaks if (p.quantity, p.item) == ("acceleration", "P9"))
    dots = [ln for ln in ax.get_lines() if ln.get_marker() == "o"]
    assert len(dots) == 1
    assert dots[0].get_xdata()[0] == pytest.approx(peak.phi1)
    assert dots[0].get_ydata()[0] == pytest.approx(peak.value)
    assert any(f"{peak.value:.4g}" in t.get_text() for t in ax.texts)


# ---------------------------------------------------------------- cyclogram
def _wedges(fig, kind):
    ax = next(a for a in fig.axes if a.get_label() == "cyclogram")
    return {p.get_gid().split(" ", 2)[2]: p for p in ax.patches
            if (p.get_gid() or "").startswith(f"phase {kind} ")}


@pytest.mark.parametrize("name", SCENES)
def test_cyclogram_phases_fill_the_revolution(scenes, name):
    res = scenes[name]
    fig = plots.cyclogram_figure(res)
    assert isinstance(fig, Figure)
    w = _wedges(fig, "design")
    assert set(w) == {"dwell", "forward", "back"}
    widths = {k: math.degrees(p.get_width()) for k, p in w.items()}
    assert sum(widths.values()) == pytest.approx(360.0, abs=1e-9)
    assert widths["dwell"] == pytest.approx(res.study.output.dwell_deg)
    # consecutive: forward starts where the dwell ends, back where forward ends
    start = {k: math.degrees(p.get_x()) for k, p in w.items()}
    assert start["forward"] == pytest.approx(start["dwell"] + widths["dwell"])
    assert start["back"] == pytest.approx(start["forward"] + widths["forward"])
    # the required ring: the eyelet's phases of the study's [cycle] (ov7_base), else none
    assert bool(_wedges(fig, "cycle")) == (res.study.cycle is not None)


def test_cyclogram_dwell_is_the_scenes_dwell_window(scenes):
    """Where the design dwells is peaks.scene_motion's window; with the OV-7 cycle
    its dwell is turned to start there too, and its phases fill the revolution."""
    res = scenes["ov7_base"]
    m = output_motion(res)
    assert m["error"] == pytest.approx(res.motion["dwell_error"], rel=1e-12)
    assert math.degrees(res.dense.phi[m["start"]]) == pytest.approx(res.motion["dwell_start"])
    fig = plots.cyclogram_figure(res, OV7_PHASES, "OV-7 cycle")
    design, cycle = _wedges(fig, "design"), _wedges(fig, "cycle")
    travel = -(res.motion["dwell_start"] - 0.0)          # rot = -1: travel = -phi1
    assert math.degrees(design["dwell"].get_x()) == pytest.approx(travel)
    assert set(cycle) == {"dwell", "swing forward", "swing back"}
    assert sum(math.degrees(p.get_width()) for p in cycle.values()) == pytest.approx(360.0)
    assert math.degrees(cycle["dwell"].get_width()) == pytest.approx(150.0)
    assert cycle["dwell"].get_x() == pytest.approx(design["dwell"].get_x())
    # the best 150 deg window of mechanism A's rocker at the scene's 360 positions
    # (phi1 = -k deg, rot = -1), by naive.py's fsolve revolution
    _, k = naive.naive_mech_a_dwell(360)
    assert f"the design dwells from phi1 = {-k:g} deg for 150 deg" in fig.axes[0].get_title()


def test_cyclogram_shows_the_cycle_the_study_states(scenes):
    """The phases of a study's [output.motion_law] (here the OV-7 cycle as such a
    law states it) on the outer ring: turned to the design's dwell when the law is
    aligned at its best, at psi = rot * (phi1 - phi0) + phase when it is fixed."""
    from dataclasses import fields
    from types import SimpleNamespace as NS
    res = scenes["ov7_base"]
    law = NS(phases=(NS(start=240.0, length=150.0, law="dwell", level0=0.0, level1=0.0),
                     NS(start=30.0, length=100.0, law="cycloidal", level0=0.0, level1=1.0),
                     NS(start=130.0, length=110.0, law="cycloidal", level0=1.0, level1=0.0)),
             align="best", phase=0.0)
    out = res.study.output
    spec = NS(**{f.name: getattr(out, f.name) for f in fields(out)})
    spec.motion_law = law
    scene = NS(study=NS(title=res.study.title, mechanism=res.study.mechanism, output=spec),
               plan=res.plan, dense=res.dense, motion=res.motion)
    fig = plots.cyclogram_figure(scene)
    design, cycle = _wedges(fig, "design"), _wedges(fig, "cycle")
    assert set(cycle) == {"dwell", "forward (cycloidal)", "back (cycloidal)"}
    assert sum(math.degrees(p.get_width()) for p in cycle.values()) == pytest.approx(360.0)
    assert cycle["dwell"].get_x() == pytest.approx(design["dwell"].get_x())
    law.align, law.phase = "fixed", 20.0
    cycle = _wedges(plots.cyclogram_figure(scene), "cycle")
    assert math.degrees(cycle["dwell"].get_x()) == pytest.approx(240.0 - 20.0)
    assert math.degrees(cycle["forward (cycloidal)"].get_x()) == pytest.approx(30.0 - 20.0)


def test_a_design_without_a_dwell_is_not_said_to_dwell(scenes):
    res = scenes["warp_feed_fourbar"]        # a crank-rocker: no rocker declared, no dwell
    m = output_motion(res)
    assert "P5" in m["what"] and m["error"] > DWELL_RESIDUAL
    fig = plots.cyclogram_figure(res)
    assert "no dwell" in _wedges(fig, "design")["dwell"].get_label()
    assert "no dwell" in fig.axes[0].get_title()
    # ... and no best dwell window is drawn where it says so
    assert not [ln for ln in fig.axes[0].get_lines() if ln.get_label() == "best dwell window"]
    assert not [ln for ln in fig.axes[0].get_lines()
                if (ln.get_gid() or "").startswith("phase error")]


# ---------------------------------------------------------------- the machine's cyclogram
def _rocker_phase_errors(pos, points, rocker, dwell_deg, required, turn=None):
    """The eyelet's phase errors from the stored positions alone (numpy, every
    window tried): the rocker angle, its best dwell window (its first start on a
    tie), forward to the sample farthest from the window's mean, back to the dwell;
    the required phases' starts ``required`` (dwell, forward, back; deg of the
    cycle angle) turned to the design's dwell, or by ``turn``."""
    ip, iq = points.index(rocker[0]), points.index(rocker[1])
    r = pos[:, iq] - pos[:, ip]
    theta = np.degrees(np.unwrap(np.arctan2(r[:, 1], r[:, 0])))
    n = len(theta)
    w = int(round(dwell_deg * n / 360))
    idx = (np.arange(n)[:, None] + np.arange(w + 1)[None, :]) % n
    s = int(np.argmin(np.ptp(theta[idx], axis=1)))
    rest = [(s + j) % n for j in range(w + 1, n)]
    far = w + 1 + int(np.argmax(np.abs(theta[rest] - theta[idx[s]].mean())))
    actual = np.array([s, s + w, s + far]) * 360.0 / n
    turn = actual[0] - required[0] if turn is None else turn
    err = (actual - (np.asarray(required) + turn) + 180.0) % 360.0 - 180.0
    return actual, err


def test_the_machine_cyclogram_has_a_ring_per_organ(scenes):
    """ov7_base's [cycle]: the eyelet's required ring and the needle's, sinker's and
    presser's, each its declared phases round the whole turn, and the eyelet's
    three phase errors marked."""
    from collections import Counter
    from pipeline.solve.cyclogram import BOUNDARIES
    res = scenes["ov7_base"]
    fig = plots.cyclogram_figure(res)
    ax = next(a for a in fig.axes if a.get_label() == "cyclogram")
    rings = [p for p in ax.patches if (p.get_gid() or "").startswith(("phase cycle ",
                                                                      "phase organ"))]
    organ = [p.get_label().split(": ")[0] for p in rings]
    assert Counter(organ) == {"eyelet": 3, "needle": 4, "sinker": 6, "presser": 4}
    for name in ("eyelet", "needle", "sinker", "presser"):
        assert sum(math.degrees(p.get_width()) for p, o in zip(rings, organ)
                   if o == name) == pytest.approx(360.0)
    assert "sinker: dwell 70-190 deg" in [p.get_label() for p in rings]
    cycle, design = _wedges(fig, "cycle"), _wedges(fig, "design")
    assert cycle["dwell"].get_x() == pytest.approx(design["dwell"].get_x())  # dwells aligned
    err = res.cyclogram.error
    marks = {ln.get_gid(): ln for ln in ax.get_lines() if (ln.get_gid() or "").startswith(
        "phase error")}
    texts = {t.get_gid(): t.get_text() for t in ax.texts}
    for b, e in zip(BOUNDARIES, err):
        arc = np.degrees(marks[f"phase error {b}"].get_xdata())
        assert arc[-1] - arc[0] == pytest.approx(e)          # required -> actual boundary
        assert texts[f"phase error {b} text"] == f"{e:+.1f}"


def test_phase_errors_are_stored_and_match_the_rocker_angle(scenes, tmp_path):
    """/cyclogram/phase_error (deg, long_name, the boundaries as its dimension)
    against the errors computed here from the file's own dense positions; held
    fixed (align = "fixed", phase), the cycle is placed at psi = tau + phase."""
    import copy
    from dataclasses import replace

    import h5py

    from pipeline.results.scene_file import write_scene
    from pipeline.solve.cyclogram import scene_cyclogram
    res = scenes["ov7_base"]
    path = write_scene(res, tmp_path / "ov7_base.h5")
    with h5py.File(path, "r") as f:
        d = f["cyclogram/phase_error"]
        assert d.attrs["units"] == "deg" and "phase error" in d.attrs["long_name"]
        assert [x.decode() if isinstance(x, bytes) else x for x in d.dims[0][0][()]] == [
            "dwell start", "forward start", "back start"]
        stored, actual = d[()], f["cyclogram/actual"][()]
        assert f["cyclogram/actual"].attrs["units"] == "deg"
        assert f["cyclogram"].attrs["organ"] == "eyelet"
        pos = f["dense/position"][()]
        points = [x.decode() if isinstance(x, bytes) else x for x in f["point"][()]]
    ours, err = _rocker_phase_errors(pos, points, ("P8", "P7"), 150.0, (240.0, 30.0, 130.0))
    assert actual == pytest.approx(ours, abs=1e-9)
    assert stored == pytest.approx(err, abs=1e-9)
    assert stored[0] == 0.0 and stored[2] != 0.0        # the dwells aligned; the back swing late
    fixed = copy.copy(res)
    fixed.study = replace(res.study, cycle=replace(res.study.cycle, align="fixed", phase=20.0))
    cg = scene_cyclogram(fixed)
    _, err = _rocker_phase_errors(pos, points, ("P8", "P7"), 150.0, (240.0, 30.0, 130.0),
                                  turn=-20.0)
    assert cg.error == pytest.approx(err, abs=1e-9)
    assert cg.required == pytest.approx([220.0, 10.0, 110.0])


# ---------------------------------------------------------------- the drawing
def test_drawing_has_a_crank_angle_key_joint_names_and_arrows(scenes):
    res = scenes["warp_feed_fourbar"]
    fig = plots.scene_figure(res)
    key = [a for a in fig.axes if a.get_label() == "crank angle key"]
    assert len(key) == 1
    ticks = [t.get_text() for t in key[0].get_yticklabels()]
    assert ticks == [str(k) for k in range(0, 360, 30)]       # the 12 drawn positions
    ax = fig.axes[0]
    texts = [t.get_text() for t in ax.texts]
    for j in ("P1 (R1)", "P2 (R2)", "P3 (R3)", "P4 (R4)"):     # joints named at their points
        assert j in texts
    assert any("R2: crank AB / coupler BC at P2" in t for t in texts)
    arrows = [t for t in ax.texts if getattr(t, "arrow_patch", None) is not None]
    assert len(arrows) >= 3 * 2                 # every moving point's path shows its way
    # the crank tip's marks are labelled with their crank angles
    assert {"0", "90", "180", "270"} <= set(texts)


def test_drawing_without_mass_data_names_points_only(scenes):
    fig = plots.scene_figure(scenes["ov7_base"])
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert "P9" in texts and not any("(R" in t for t in texts)
    assert any(a.get_label() == "crank angle key" for a in fig.axes)


def test_forces_legend_says_what_each_joint_joins(scenes):
    fig = plots.forces_figure(scenes["warp_feed_fourbar"])
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert legend[0] == "R1: ground / crank AB at P1"


def test_forces_figure_draws_the_loads_and_marks_the_polar_diagram(scenes):
    """The loads as the study gives them (formulas of phi and t) against phi1,
    and crank-angle marks on the polar diagram beside its arrows."""
    from pipeline.solve.reactions import sample_loads
    res = scenes["warp_feed_fourbar"]
    fig = plots.forces_figure(res)
    ax = next(a for a in fig.axes if a.get_title().startswith("External loads"))
    line = ax.get_lines()[0]
    ld = res.study.mechanism.loads[0]
    assert ld.fy.text in line.get_label()
    np.testing.assert_array_equal(line.get_ydata(), sample_loads(res.study.mechanism,
                                                                 res.dense.phi)[:, 0, 1])
    polar = next(a for a in fig.axes if a.get_title().startswith("Polar diagram"))
    labels = [t.get_text() for t in polar.texts if t.get_text().isdigit()]
    assert labels and labels[0] == "0"
    assert "dots every 30 deg" in polar.get_title()


# ---------------------------------------------------------------- eps1 against phi1
def test_eps1_against_phi1_per_dynamics_case(scenes):
    res = scenes["takeup_dynamics"]
    assert [c.name for c in res.dynamics] == ["runup", "free"]
    for case in res.dynamics:
        fig = plots.eps1_figure(case)
        ax = next(a for a in fig.axes if a.get_label() == "eps1 against phi1")
        assert any(a.get_label() == "time key" for a in fig.axes)
        pts = ax.collections[0].get_offsets()
        assert len(pts) == len(case.t)
        np.testing.assert_array_equal(np.asarray(pts[:, 1]), case.eps1)
        x = np.asarray(pts[:, 0])
        if case.name == "runup":      # a rotation: over one revolution
            assert x.min() >= 0.0 and x.max() < 360.0 and "steady" in ax.get_title()
        else:                          # an oscillation: about the equilibrium
            assert x.max() - x.min() < 30.0 and "oscillation" in ax.get_title()


# ---------------------------------------------------------------- animation
def test_animation_writes_a_gif_with_the_frames_asked(scenes, tmp_path):
    res = scenes["ov7_base"]
    out = tmp_path / "a.gif"
    info = write_animation(motion_of(res), out, frames=12)
    im = _gif(out)
    assert im.n_frames == info["frames"] == 12
    assert f"{im.size[0]} x {im.size[1]}" == info["pixels"] and im.info["loop"] == 0
    assert not list(tmp_path.glob(".*partial*"))          # written beside, then renamed
    # the frames differ: the mechanism moves
    im.seek(0)
    a = np.asarray(im.convert("RGB"))
    im.seek(6)
    assert (np.asarray(im.convert("RGB")) != a).any()
    # bounded: at most MAX_FRAMES, evenly over the revolution
    idx = frame_indices(motion_of(res), MAX_FRAMES)
    assert len(idx) == MAX_FRAMES and np.all(np.diff(idx) == 3)
    with pytest.raises(ValueError, match="between 2 and 120"):
        frame_indices(motion_of(res), MAX_FRAMES + 1)
    with pytest.raises(ValueError, match=".gif"):
        write_animation(motion_of(res), tmp_path / "a.avi", frames=4)
    # MP4 through ffmpeg (.ci/run installs it: never skipped): an MP4 container
    # holding the 4 frames asked for (counted by ffprobe)
    assert shutil.which("ffmpeg") and shutil.which("ffprobe"), "apt-get install ffmpeg"
    write_animation(motion_of(res), tmp_path / "a.mp4", frames=4)
    assert (tmp_path / "a.mp4").read_bytes()[4:8] == b"ftyp"
    import subprocess
    probe = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0",
                            "-show_entries", "stream=nb_read_frames", "-of", "csv=p=0",
                            str(tmp_path / "a.mp4")], capture_output=True, text=True, check=True)
    assert probe.stdout.strip() == "4"
    # and without ffmpeg, a clear error
    import pipeline.views.animate as an
    real_which = an.shutil.which
    try:
        an.shutil.which = lambda name, *a, **k: None if name == "ffmpeg" else real_which(name)
        with pytest.raises(ValueError, match="ffmpeg"):
            write_animation(motion_of(res), tmp_path / "b.mp4", frames=4)
    finally:
        an.shutil.which = real_which


def test_a_failing_mechanism_is_animated_up_to_where_it_fails(studies, tmp_path):
    """A four-bar whose crank (45 mm) cannot pass 155-205 deg: the frames stop at
    the failure, though the walk solves positions again after it."""
    text = (studies / "warp_feed_fourbar.toml").read_text()
    assert "length = 15.0              # AB" in text
    study = tmp_path / "locked.toml"
    study.write_text(text.replace("length = 15.0              # AB", "length = 45.0"))
    res = solve_scene(load_study(study))
    assert res.failure["status"] == "SINGULAR" and 150 < res.failure["phi_deg"] < 160
    motion = motion_of(res)
    info = write_animation(motion, tmp_path / "f.gif", frames=20)
    assert info["frames"] == _gif(tmp_path / "f.gif").n_frames == 9     # 0, 18, ..., 144 deg
    assert "up to where it fails" in info["duration"]
    assert output_motion(res) is None
    assert "does not assemble" in plots.cyclogram_figure(res).axes[0].texts[0].get_text()


# ---------------------------------------------------------------- pipeline run / show
def test_run_writes_the_new_pictures_and_show_animates_the_scene(studies, tmp_path, capsys):
    out = tmp_path / "t.h5"
    assert main(["run", str(studies / "takeup_dynamics.toml"), "-o", str(out)]) == 0
    said = capsys.readouterr().out
    names = ["t.png", "t_kinematics.png", "t_cyclogram.png", "t_runup.png",
             "t_runup_eps1.png", "t_free.png", "t_free_eps1.png", "t_reduced.png"]
    for n in names:
        p = tmp_path / n
        assert p.exists() and p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", n
        assert str(p) in said
    assert f"pipeline show {out} --animate" in said
    assert not list(tmp_path.glob(".*partial*"))

    assert main(["show", str(out), "--animate", "--frames", "10", "-q"]) == 0
    assert _gif(tmp_path / "t_animation.gif").n_frames == 10
    gif = tmp_path / "mine.gif"
    assert main(["show", str(out), "--animate", "--frames", "8", "-o", str(gif),
                 "--format", "json"]) == 0
    assert '"frames": 8' in capsys.readouterr().out and _gif(gif).n_frames == 8

    bad = [(["show", str(out)], f"is a scene result, this command needs a sweep result "
                                "(`pipeline run` wrote the scene's pictures; `pipeline show "
                                f"{out} --animate` animates it)"),
           (["show", str(out), "--animate", "--candidate", "3"], "--candidate applies to a sweep"),
           (["show", str(out), "--animate", "-o", str(tmp_path / "x.avi")], ".gif"),
           (["show", str(out), "--animate", "--frames", "500"], "between 2 and 120"),
           (["show", str(tmp_path / "none.h5"), "--animate"], "file not found")]
    for argv, words in bad:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert words in err and "Traceback" not in err, (argv, err)


@pytest.fixture(scope="module")
def small_sweep(tmp_path_factory, synthesis_sweep):
    """This module's copy of the session's sweep of the main job's study."""
    from support.sweep_helpers import copy_of
    return copy_of(synthesis_sweep, tmp_path_factory.mktemp("sweep"), "s.h5")


def test_show_animates_a_sweep_candidate(small_sweep, tmp_path, capsys):
    gif = tmp_path / "ref.gif"
    assert main(["show", str(small_sweep), "--candidate", "reference", "--animate",
                 "--frames", "6", "-o", str(gif)]) == 0
    assert "reference" in capsys.readouterr().out and _gif(gif).n_frames == 6
    assert main(["show", str(small_sweep), "--animate"]) == 2
    assert "is a sweep: say which design to animate with --candidate" in capsys.readouterr().err


def test_report_embeds_the_animation_and_stays_offline(small_sweep, tmp_path, monkeypatch):
    from pipeline.views import report, report_figures
    from support.layout import layout_problems
    monkeypatch.setattr(report, "EXPLORER_DRAWINGS", 1)      # the test's time, not the page's
    # every picture of the report is laid out clear (support.layout), checked as it is saved
    problems, png = [], report_figures._png

    checked_names = []

    def checked(fig, dpi=100):
        title = fig._suptitle.get_text() if fig._suptitle else ""
        checked_names.append(title or fig.axes[0].get_title())
        problems.extend(layout_problems(fig, f"report picture {checked_names[-1]!r}", dpi=dpi))
        return png(fig, dpi)
    monkeypatch.setattr(report_figures, "_png", checked)
    monkeypatch.setattr(report, "_png", checked)
    p = tmp_path / "s.h5"
    shutil.copy(small_sweep, p)
    info = report.write_report(p, tmp_path / "r.html")
    page = (tmp_path / "r.html").read_text()
    assert info["report"].endswith("r.html") and "A design in motion" in page
    # the Pareto picture, which a page without the explorer shows
    from pipeline.analysis.fronts import read_analysis, read_sweep
    from pipeline.results.storage import open_results
    with open_results(p, "sweep") as f:
        ana = read_analysis(f)
    report_figures.pareto_figure(read_sweep(p), ana)
    assert len(problems) == 0 and len(checked_names) >= 2, (checked_names, problems)
    # the comparison section: the knee against the reference design (pipeline compare)
    assert "<h2>Against the reference design</h2>" in page
    section = page.split("<h2>Against the reference design</h2>")[1].split("<h2>")[0]
    assert "--candidate" in section and "largest peak |R|" in section
    assert '<div class="chart" role="img" aria-label="the design against the reference ' \
        'design"' in section
    # the knee's cycle is in the explorer: the page animates it from those numbers
    motion = page.split("<h2>A design in motion</h2>")[1].split("<h2>")[0]
    assert re.search(r'<div class="design-animation" data-design="\d+" data-frames-asked="'
                     f'{report.ANIMATION_FRAMES}"', motion), motion[:2000]
    assert "data:image/gif" not in page and 'alt="cyclogram of ' in motion
    # without the explorer's cycles (--drawings 0), an animated GIF as before
    report.write_report(p, tmp_path / "r0.html", drawings=0)
    gifs = re.findall(r'<img class="animation" src="data:image/gif;base64,([A-Za-z0-9+/=]+)"',
                      (tmp_path / "r0.html").read_text())
    assert len(gifs) == 1
    assert _gif(base64.b64decode(gifs[0])).n_frames == report.ANIMATION_FRAMES
    # one offline file: nothing fetched, no http(s) address in any tag (the scripts'
    # own text aside: plotly.js names addresses it never fetches here)
    from support.html_page import markup_only
    tags = markup_only(page)
    assert not re.search(r"""(src|href)\s*=\s*["'](?!data:|#)""", tags)
    assert not re.search(r"<[^>]*https?://[^>]*>", tags)
    assert "<link" not in tags and "@import" not in page
