"""A picture is laid out once and drawn once (pipeline.base.files.save_figure):
the same bytes as matplotlib's own savefig, which draws a laid-out figure twice."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.layout_engine import ConstrainedLayoutEngine  # noqa: E402

from pipeline.base.files import laid_out_once, save_figure  # noqa: E402


def many_panels():
    """Small multiples with titles, labels of differing widths, subfigures and
    a legend: the layout has something to do."""
    fig = plt.figure(figsize=(9, 6), layout="constrained")
    left, right = fig.subfigures(1, 2, width_ratios=[3, 2])
    x = np.linspace(0.0, 360.0, 200)
    for sub, scale in ((left, 1e4), (right, 1e-3)):
        axes = sub.subplots(3, 2, sharex=True)
        for k, ax in enumerate(axes.flat):
            ax.plot(x, scale * (k + 1) * np.sin(np.deg2rad(x) * (k + 1)), label="y")
            ax.set_title(f"panel {k}: a quantity [unit]", fontsize=8, loc="left")
        axes[0, 0].legend()
        sub.suptitle("a subfigure's title")
    fig.suptitle("a figure's title")
    return fig


@pytest.mark.parametrize("dpi", [110, None])
def test_one_layout_one_drawing_and_matplotlib_s_own_bytes(tmp_path, monkeypatch, dpi):
    kw = {} if dpi is None else {"dpi": dpi}
    own = many_panels()
    own.savefig(tmp_path / "own.png", **kw)
    plt.close(own)

    draws = []
    real = Figure.draw

    def counted(self, renderer):
        draws.append(self)
        return real(self, renderer)
    monkeypatch.setattr(Figure, "draw", counted)
    fig = many_panels()
    save_figure(fig, tmp_path / "once.png", **kw)
    assert len(draws) == 1          # (matplotlib's savefig: 2)
    assert (tmp_path / "once.png").read_bytes() == (tmp_path / "own.png").read_bytes()
    assert isinstance(fig.get_layout_engine(), ConstrainedLayoutEngine)   # given back
    plt.close(fig)


def test_a_figure_without_a_layout_engine_is_saved_as_it_is(tmp_path):
    fig, ax = plt.subplots()
    ax.plot([0, 1], [1, 0])
    fig.savefig(tmp_path / "own.png", dpi=80)
    with laid_out_once(fig, 80):
        assert fig.get_layout_engine() is None
        fig.savefig(tmp_path / "here.png", dpi=80)
    assert (tmp_path / "here.png").read_bytes() == (tmp_path / "own.png").read_bytes()
    plt.close(fig)
