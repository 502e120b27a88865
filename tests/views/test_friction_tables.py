"""A scene's joint friction for people (issue 52): friction.csv (`pipeline export
--csv`) holds the /dense friction datasets column by column with their units in
the headers, and `pipeline run` draws <name>_friction.png (loss per joint and
slide over phi1, p*v per pin against pv_max)."""

import h5py
import numpy as np
import pandas as pd
import pytest

from pipeline.cli import main
from pipeline.views.tables import FRICTION_JOINT_COLUMNS, FRICTION_SLIDE_COLUMNS
from support.friction_sections import TAKEUP_FRICTION

@pytest.fixture(scope="module")
def runs(studies, tmp_path_factory):
    """Mechanism B with friction at its pins (ov7_friction) and the take-up with
    friction at its pins and its two slides, run with their pictures and
    exported as CSV."""
    d = tmp_path_factory.mktemp("friction_tables")
    base = (studies / "takeup_dynamics.toml").read_text()
    base = base[:base.index("[dynamics]")]
    assert "[output]" in base
    takeup = d / "takeup_friction.toml"
    takeup.write_text(base.replace("[output]", TAKEUP_FRICTION + "\n[output]", 1))
    out = {}
    for key, study in (("b", studies / "ov7_friction.toml"), ("takeup", takeup)):
        h5 = d / f"{key}.h5"
        assert main(["run", str(study), "-o", str(h5), "-q"]) == 0
        assert main(["export", str(h5), "--csv", str(d / f"{key}_csv"), "-q"]) == 0
        out[key] = (h5, d / f"{key}_csv" / "friction.csv")
    return out


@pytest.mark.parametrize("key", ["b", "takeup"])
def test_friction_csv_columns_are_the_datasets(runs, key):
    h5, csv = runs[key]
    df = pd.read_csv(csv)
    with h5py.File(h5, "r") as f:
        g = f["dense"]
        joints = list(g["reactions"].attrs["joints"])
        slides = list(g["slide_friction_force"].attrs["slides"]) \
            if "slide_friction_force" in g else []
        assert len(slides) == (2 if key == "takeup" else 0)
        n = g["phi1"].shape[0]
        assert len(df) == n
        np.testing.assert_allclose(df["phi1 [deg]"], g["phi1"][()], rtol=1e-11)
        assert (df["friction_status"] == "OK").all()
        expected = 2 + 6 * len(joints) + 3 * len(slides) + 2
        assert len(df.columns) == expected
        from pipeline.solve.reactions import slide_label
        for names, columns in ((joints, FRICTION_JOINT_COLUMNS),
                               ([slide_label(s) for s in slides], FRICTION_SLIDE_COLUMNS)):
            for dataset, short in columns if names else ():
                data, unit = g[dataset][()], g[dataset].attrs["units"]
                assert data.shape == (n, len(names))
                for j, name in enumerate(names):
                    col = df[f"{short}[{name}] [{unit}]"].to_numpy()
                    # %.12g in the CSV: 12 significant digits (a -0 is written as 0)
                    np.testing.assert_allclose(col, data[:, j], rtol=1e-11,
                                               atol=1e-11 * np.abs(data).max(),
                                               err_msg=f"{dataset} {name}")
        for dataset in ("friction_loss_total", "M_bal_frictionless"):
            unit = g[dataset].attrs["units"]
            np.testing.assert_allclose(df[f"{dataset} [{unit}]"], g[dataset][()], rtol=1e-11,
                                       atol=1e-11 * np.abs(g[dataset][()]).max())
        assert "pv[R1] [MPa·m/s]" in df.columns and "loss[R1] [W]" in df.columns


@pytest.mark.parametrize("key", ["b", "takeup"])
def test_the_friction_picture_is_drawn(runs, key):
    h5, _ = runs[key]
    png = h5.with_name(f"{h5.stem}_friction.png")
    assert png.exists() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    import matplotlib.image as mpimg
    img = mpimg.imread(png)
    assert img.shape[0] > 400 and img.shape[1] > 800 and np.ptp(img[..., :3]) > 0.5


def test_a_scene_without_friction_has_neither(studies, tmp_path):
    h5 = tmp_path / "c3.h5"
    assert main(["run", str(studies / "ov7_class3.toml"), "-o", str(h5), "-q"]) == 0
    assert main(["export", str(h5), "--csv", str(tmp_path / "csv"), "-q"]) == 0
    assert not (tmp_path / "csv" / "friction.csv").exists()
    assert (tmp_path / "csv" / "reactions.csv").exists()
    assert not h5.with_name("c3_friction.png").exists() and h5.with_name("c3_forces.png").exists()
