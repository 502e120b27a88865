"""`pipeline compare` (issue 29 item 4): designs side by side.

The independent reference is the scene files themselves: every number of the
table is read here from the HDF5 datasets with h5py (not through the package's
readers), the pin diameters recomputed from DOMAIN.md's formula.  The two OV-7
scenes are solved once per module (about 2 s); the sweep is the session's."""

import json
import math
import shutil

import h5py
import numpy as np
import pytest

from pipeline.cli import main
from pipeline.runner import run_scene_study
from pipeline.study.reader import load_study

SCENES = ("ov7_base", "ov7_class3", "warp_feed_fourbar")


@pytest.fixture(scope="module")
def scenes(studies, tmp_path_factory):
    folder = tmp_path_factory.mktemp("scenes")
    return {s: run_scene_study(load_study(studies / f"{s}.toml"), folder / f"{s}.h5",
                               pictures=False).results for s in SCENES}


def _text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def _stored(path):
    """What a scene file stores, read with h5py alone: {key: (value, phi1)}."""
    out = {}
    with h5py.File(path, "r") as f:
        wp = _text(f["mechanism"].attrs["working_point"])
        if "motion" in f:
            out["stroke"] = (float(f["motion/stroke"][()]), None)
            out["dwell_error"] = (float(f["motion/dwell_error"][()]), None)
        p = f["peaks"]
        for q in ("velocity", "acceleration"):
            names = [_text(x) for x in p[q].dims[0][0][()]]
            k = names.index(wp)
            out[f"working_point_{q}"] = (float(p[q][k]), float(p[f"{q}_phi1"][k]))
        k = int(np.argmin(p["min_transmission_angle"][()]))
        out["min_transmission_angle"] = (float(p["min_transmission_angle"][k]),
                                         float(p["min_transmission_angle_phi1"][k]))
        if "reaction" in p:
            R, phi = p["reaction"][()], p["reaction_phi1"][()]
            joints = [_text(x) for x in f["dense/reactions"].attrs["joints"]]
            for j, name in enumerate(joints):
                out[f"reaction[{j}]"] = (float(R[j]), float(phi[j]))
                # DOMAIN.md section 5: l = 10 mm, sigma = 200 MPa
                d = (32.0 * R[j] * 10.0 / (math.pi * 200.0)) ** (1.0 / 3.0)
                out[f"pin_d_min[{j}]"] = (d, float(phi[j]))
            j = int(np.argmax(R))
            out["reaction_max"] = (float(R[j]), float(phi[j]))
            out["pin_d_min_max"] = out[f"pin_d_min[{j}]"]
            for q in ("M_bal", "shaking_force", "shaking_moment"):
                out[q] = (float(p[q][()]), float(p[f"{q}_phi1"][()]))
    return out


def _rows(argv, capsys):
    assert main(argv + ["--format", "json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_the_table_is_what_each_scene_file_stores(scenes, capsys, tmp_path):
    a, b = scenes["ov7_base"], scenes["ov7_class3"]
    out = _rows(["compare", str(a), str(b), "-o", str(tmp_path)], capsys)
    ref = {"ov7_base": _stored(a), "ov7_class3": _stored(b)}
    rows = {r["key"]: r for r in out["rows"]}
    for lab, stored in ref.items():
        for key, (value, phi) in stored.items():
            if key.startswith(("reaction[", "pin_d_min[")):
                j = int(key[key.index("[") + 1:-1])
                key = f"{key[:key.index('[')]}[R{j + 1}@ov7_class3]"
            cell = rows[key][lab]
            assert cell["value"] == pytest.approx(value, rel=1e-12), (lab, key)
            if phi is not None:
                assert cell["phi1_deg"] == pytest.approx(phi, abs=1e-9), (lab, key)
    # compared where both have it, with the change against the first design
    s = rows["stroke"]
    assert s["compared"] and s["unit"] == "mm"
    assert s["ov7_class3"]["change"] == pytest.approx(
        ref["ov7_class3"]["stroke"][0] - ref["ov7_base"]["stroke"][0], rel=1e-12)
    assert rows["reaction_max"]["unit"] == "N" and rows["M_bal"]["unit"] == "N·m"
    assert rows["pin_d_min_max"]["unit"] == "mm"
    assert rows["min_transmission_angle"]["unit"] == "deg"
    # the base design has no mass data: its forces are said to be left out, not zero
    assert not rows["reaction_max"]["compared"]
    assert rows["reaction_max"]["ov7_base"]["value"] is None
    assert any(n.startswith("not compared: reactions") and "ov7_base" in n
               for n in out["notes"])
    assert out["pictures"] == [str(tmp_path / "ov7_base_vs_ov7_class3_compare.png")]


def test_the_command_prints_the_table_and_writes_the_picture(scenes, capsys):
    a, b = scenes["ov7_base"], scenes["ov7_class3"]
    assert main(["compare", str(a), str(b)]) == 0
    text = capsys.readouterr().out
    for words in ("stroke", "dwell error", "peak |v| working point", "peak |R| R1",
                  "pin d_min R7", "peak |M_bal|", "peak shaking force",
                  "smallest transmission angle", "not compared"):
        assert words in text, words
    pic = a.with_name("ov7_base_vs_ov7_class3_compare.png")
    assert f"picture: {pic}" in text
    assert pic.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_joints_of_different_counts_keep_their_own_names(scenes, capsys):
    b, d = scenes["ov7_class3"], scenes["warp_feed_fourbar"]
    out = _rows(["compare", str(b), str(d), "--no-pictures"], capsys)
    rows = {r["key"]: r for r in out["rows"]}
    with h5py.File(d, "r") as f:
        joints = [_text(x) for x in f["dense/reactions"].attrs["joints"]]
        R = f["peaks/reaction"][()]
    assert len(joints) != 7
    for j, name in enumerate(joints):       # the four-bar's joints under their own names
        r = rows[f"reaction[{name}@warp_feed_fourbar]"]
        assert not r["compared"] and r["ov7_class3"]["value"] is None
        assert r["warp_feed_fourbar"]["value"] == pytest.approx(R[j], rel=1e-12)
    assert rows["reaction_max"]["compared"]          # the largest is compared
    assert rows["reaction_max"]["warp_feed_fourbar"]["value"] == pytest.approx(R.max(),
                                                                               rel=1e-12)
    assert any("joints not matched one to one" in n for n in out["notes"])


def test_mismatched_designs_are_refused_in_one_line(scenes, tmp_path, capsys):
    # a scene file that stores no peaks and no motion (a revolution that does not
    # assemble has none) shares nothing with another scene
    bare = tmp_path / "bare.h5"
    shutil.copy(scenes["ov7_base"], bare)
    with h5py.File(bare, "r+") as f:
        del f["peaks"], f["motion"]
    assert main(["compare", str(bare), str(scenes["ov7_class3"])]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    assert err.startswith("pipeline compare: error: nothing to compare")
    assert f"{bare} (OK): nothing" in err and "reactions" in err
    bad = [(["compare", str(scenes["ov7_base"])], "give two scene results files"),
           (["compare", str(scenes["ov7_base"]), "--candidate", "3"],
            "is a scene result: it has one design"),
           (["compare", str(scenes["ov7_base"]), str(tmp_path / "none.h5")], "file not found")]
    for argv, words in bad:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert words in err and "Traceback" not in err, (argv, err)


def test_a_candidate_against_the_reference_design(synthesis_sweep, tmp_path, capsys):
    """The sweep's reference design re-run as a scene: its stroke and dwell error
    are the sweep's stored ones (same positions), its refined peak reaction and
    peak M_bal at least the sweep's grid peaks and within 0.5 % of them."""
    import pipeline
    cmp = pipeline.compare(synthesis_sweep, candidate="knee")
    assert [d.label for d in cmp.designs][0] == "reference design"
    assert cmp.designs[1].label.startswith("candidate #")
    rows = {r.key: r for r in cmp.rows}
    assert all(r.compared for r in cmp.rows)      # one mechanism: every joint matched
    with h5py.File(synthesis_sweep, "r") as f:
        ref = {k: float(f[f"reference/{k}"][0]) for k in ("stroke", "dwell_error",
                                                          "peak_reaction", "peak_M_bal")}
    assert rows["stroke"].values[0] == pytest.approx(ref["stroke"], rel=1e-9)
    assert rows["dwell_error"].values[0] == pytest.approx(ref["dwell_error"], rel=1e-9)
    for key, stored in (("reaction_max", ref["peak_reaction"]), ("M_bal", ref["peak_M_bal"])):
        assert stored * (1 - 1e-9) <= rows[key].values[0] <= stored * 1.005, key
    assert main(["compare", str(synthesis_sweep), "--candidate", "reference"]) == 2
    assert "the reference design is what a candidate is compared with" in capsys.readouterr().err
    assert main(["compare", str(synthesis_sweep)]) == 2
    assert "is a sweep: compare one of its designs" in capsys.readouterr().err
