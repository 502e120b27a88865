"""No picture we ship has text over text, text over a legend or a peak marker,
a legend over a peak, or a text cut at the figure's edge (issue 28 item 3).

The checker (support.layout) asks matplotlib's renderer where every text,
legend and peak marker of a Figure is drawn.  It runs over every picture of
every scene study in studies/ (those `pipeline run` writes), the picture of
`pipeline show` and of `pipeline compare` (two scenes; a sweep's candidate
against its reference design), and the two of `pipeline tolerance`; the
report's own pictures are checked where the report is written
(tests/views/test_pictures.py).  Figures are built in process, never read
back from PNG files, at the resolution the commands save them."""

from dataclasses import replace

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from conftest import STUDIES  # noqa: E402
from pipeline.runner import constant_forces  # noqa: E402
from pipeline.solve.scene_study import solve_scene  # noqa: E402
from pipeline.solve.cyclogram import output_motion  # noqa: E402
from pipeline.study.reader import load_study  # noqa: E402
from pipeline.views import plots  # noqa: E402
from support.layout import layout_problems  # noqa: E402

SCENE_STUDIES = sorted(p.stem for p in STUDIES.glob("*.toml")
                       if "[sweep]" not in p.read_text())
SAVED_DPI = 110         # pipeline run / compare / tolerance save at 110 dpi, show at 100


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def scene_pictures(res):
    """(name, maker) of every picture `pipeline run` draws of a scene (the list
    pipeline.runner._write_scene_study saves)."""
    from pipeline.views.dynamics_plots import dynamics_figure, motion_forces_figure, \
        reduced_figure
    from pipeline.views.shaking_plots import shaking_figure
    out = [("scene", lambda: plots.scene_figure(res)),
           ("kinematics", lambda: plots.kinematics_figure(res))]
    if output_motion(res) is not None:
        out.append(("cyclogram", lambda: plots.cyclogram_figure(res)))
    if res.dense.forces is not None:
        out.append(("forces", lambda: plots.forces_figure(res)))
        if res.dense.forces.shaking is not None:
            out.append(("shaking", lambda: shaking_figure(res)))
    constant = constant_forces(res) if res.motion_forces else None
    for case in res.dynamics or ():
        out.append((case.name, lambda case=case: dynamics_figure(case)))
        out.append((f"{case.name}_eps1", lambda case=case: plots.eps1_figure(case)))
        if (res.motion_forces or {}).get(case.name):
            out.append((f"{case.name}_forces", lambda case=case: motion_forces_figure(
                case.name, res.motion_forces[case.name], constant)))
    if res.reduced is not None:
        out.append(("reduced", lambda: reduced_figure(res.reduced)))
    return out


def _check(name, make, dpi=SAVED_DPI):
    fig = make()
    try:
        return layout_problems(fig, name, dpi=dpi)
    finally:
        plt.close(fig)


def test_every_scene_study_is_checked():
    assert len(SCENE_STUDIES) >= 10 and "ov7_base" in SCENE_STUDIES


@pytest.fixture(scope="module")
def solved():
    """The module's scenes, each solved once when first asked for."""
    cache = {}

    def get(study):
        if study not in cache:
            cache[study] = solve_scene(load_study(STUDIES / f"{study}.toml"))
        return cache[study]
    return get


@pytest.mark.parametrize("study", SCENE_STUDIES)
def test_every_picture_of_a_scene_study_is_laid_out_clear(study, solved):
    res = solved(study)
    problems = []
    for name, make in scene_pictures(res):
        problems += _check(f"{study}: {name}", make)
    assert not problems, "\n".join(problems)


def test_a_constant_curve_has_no_peak_and_links_have_the_forces_names(solved):
    """The uniform crank's omega and eps are constant: no 'peak 0 1/s² at 0.00
    deg'; a link carried by a body is named as the forces name it."""
    from pipeline.views.labels import PEAK_GID
    fig = plots.kinematics_figure(solved("ppr_cross_slide"))
    for what in ("omega", "eps"):
        ax = next(a for a in fig.axes if a.get_label() == f"link 1_2 {what}")
        assert not ax.texts and not [ln for ln in ax.get_lines()
                                     if (ln.get_gid() or "").startswith(PEAK_GID)]
    fig = plots.kinematics_figure(solved("ov7_class3"))
    ax = next(a for a in fig.axes if a.get_label() == "link 2_3 omega")
    assert ax.get_title("left").startswith("lead 2-3: omega [1/s]")
    assert any(t.get_text().startswith("peak ") for t in ax.texts)
    legend = [t.get_text() for t in plots.forces_figure(solved("ov7_class3")).axes[0]
              .get_legend().get_texts()]
    assert any("lead 2-3" in t for t in legend)


def test_the_run_up_is_drawn_as_bands_with_every_extreme(solved):
    from pipeline.views.dynamics_plots import dynamics_figure
    case = next(c for c in solved("takeup_dynamics").dynamics if c.name == "runup")
    fig = dynamics_figure(case)
    ax = fig.axes[2]                      # eps1(t)
    assert ax.get_ylabel() == "eps1 [rad/s²]"
    edges = [ln.get_ydata() for ln in ax.get_lines()]
    assert max(len(y) for y in edges) < len(case.t) / 5         # thinned
    top = max(float(np.nanmax(y)) for y in edges)
    assert top == max(float(np.nanmax(case.eps1)), float(np.nanmax(case.tail_eps1)))


def test_the_pictures_of_show_compare_and_tolerance_are_laid_out_clear(synthesis_sweep,
                                                                         tmp_path):
    from pipeline.analysis.candidate import rerun_candidate
    from pipeline.results.scene_file import write_scene
    from pipeline.runner import comparison
    from pipeline.runs.tolerance import analyse
    from pipeline.study.tolerance_spec import ToleranceSpec
    from pipeline.views.compare import comparison_figure
    from pipeline.views.show import candidate_figure
    from pipeline.views.tolerance_plots import histograms_figure, tornado_figure
    problems = _check("show reference", lambda: candidate_figure(
        rerun_candidate(synthesis_sweep, "reference")), dpi=100)
    files = []
    for s in ("ov7_base", "ov7_class3"):
        files.append(tmp_path / f"{s}.h5")
        write_scene(solve_scene(load_study(STUDIES / f"{s}.toml")), files[-1])
    problems += _check("compare two scenes", lambda: comparison_figure(comparison(files)))
    problems += _check("compare the knee", lambda: comparison_figure(
        comparison([synthesis_sweep], "knee")))
    study = load_study(STUDIES / "ov7_synthesis.toml")
    spec = replace(ToleranceSpec(), samples=64)
    a = analyse(study, study.mechanism, spec, sweep_spec=study.sweep, label="reference")
    problems += _check("tolerance histograms", lambda: histograms_figure(a))
    problems += _check("tolerance tornado", lambda: tornado_figure(a))
    assert not problems, "\n".join(problems)


# ----------------------------------------------------------------- the checker itself
def _figure():
    fig, ax = plt.subplots(figsize=(4, 3), layout="constrained")
    ax.plot([0, 1, 2], [0, 2, 1], label="curve")
    return fig, ax


def test_the_checker_passes_a_clear_figure_and_fails_each_kind_of_fault():
    fig, ax = _figure()
    ax.set_title("a title")
    ax.legend(loc="lower right")
    assert layout_problems(fig, "clear") == []

    fig, ax = _figure()        # two texts at the same spot
    ax.text(0.5, 0.5, "first words", transform=ax.transAxes)
    ax.text(0.5, 0.5, "second words", transform=ax.transAxes)
    got = layout_problems(fig, "same spot")
    assert got and "same spot: text overlaps text" in got[0]
    assert "'first words'" in got[0] and "'second words'" in got[0]

    fig, ax = _figure()        # a title wider than the figure
    ax.set_title("a title far too long for a figure four inches wide, cut at both of its "
                 "edges by the renderer")
    got = layout_problems(fig, "wide title")
    assert any("wide title: text cut at the figure's edge" in p and "a title far" in p
               for p in got)

    fig, ax = _figure()        # a label over a legend
    ax.legend(loc="upper left")
    ax.text(0.03, 0.95, "a note", transform=ax.transAxes, va="top")
    got = layout_problems(fig, "over legend")
    assert any("text over a legend" in p and "'a note'" in p and "'curve'" in p for p in got)

    fig, ax = _figure()        # a legend over a peak marker, and a text on it
    from pipeline.views.labels import mark_peak
    mark_peak(ax, 1, 2, what="of the curve")
    ax.legend(loc="upper center")
    ax.annotate("peak 2", (1, 2))
    got = layout_problems(fig, "peak")
    assert any("legend over a peak marker" in p and "'peak of the curve'" in p for p in got)
    assert any("text over a peak marker" in p and "'peak 2'" in p for p in got)

    fig, ax = _figure()        # turned texts are compared as turned rectangles
    ax.text(0.2, 0.2, "along one diagonal", rotation=45, transform=ax.transAxes)
    ax.text(0.05, 0.6, "beside it, clear", transform=ax.transAxes)
    assert layout_problems(fig, "turned") == []
