"""A '$' in a study's text (its title, a body's name) is a dollar sign in every
picture, never the start of a mathtext formula: an unclosed one made the
pictures fail after the whole computation (issue 58, case 9)."""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

from pipeline.base.files import literal_text, save_figure  # noqa: E402

STUDIES = Path(__file__).resolve().parents[2] / "studies"
NAMES = ["$x_1^{2$", "crank $A_B", "a $ b", r"$\alpha$"]


@pytest.mark.parametrize("name", NAMES)
def test_every_text_of_a_saved_figure_is_literal(tmp_path, name):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots()
    ax.set_title(name)
    ax.plot([0, 1], [0, 1], label=name)
    ax.legend()
    ax.set_yticks([0, 1], labels=[name, name])     # tick labels are made while drawing
    fig.text(0.1, 0.1, name)
    out = save_figure(fig, tmp_path / "p.png")
    assert out.stat().st_size > 0
    texts = [t for t in fig.findobj(matplotlib.text.Text) if t.get_text() == name]
    assert texts and not any(t.get_parse_math() for t in texts)
    plt.close(fig)


def test_an_unclosed_formula_fails_without_it(tmp_path):
    """The case the guard is for (matplotlib's own behaviour, so that the test
    above cannot pass for want of a failing input)."""
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots()
    ax.set_title(NAMES[0])
    with pytest.raises(ValueError):
        fig.savefig(tmp_path / "q.png")
    with literal_text(fig):
        fig.savefig(tmp_path / "q.png")
    plt.close(fig)


def test_a_scene_with_dollars_in_its_names_draws_its_pictures(tmp_path):
    from pipeline.runner import run_study
    from pipeline.views.animate import animate
    text = (STUDIES / "warp_feed_fourbar.toml").read_text()
    title = 'title = "Four-bar $x_1^{2$ and $\\\\alpha$"'      # TOML's \\ is one backslash
    text = re.sub(r'(?m)^title = .*$', lambda m: title, text)
    text = text.replace('name = "crank AB"', 'name = "crank $A_B"')
    assert "$A_B" in text and "$x_1" in text
    study = tmp_path / "dollars.toml"
    study.write_text(text)
    res = run_study(study, tmp_path / "dollars.h5", progress=False)
    assert len(res.pictures) >= 4 and all(p.stat().st_size > 0 for p in res.pictures)
    info = animate(res.results, None, tmp_path / "dollars.gif", frames=4)
    assert Path(info["animation"]).stat().st_size > 0
