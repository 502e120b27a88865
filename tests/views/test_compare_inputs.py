"""`pipeline compare` (issue 58, case 9): many files with long names give a
picture name within the file system's limit (cut, with a hash of the whole
name, decided before the designs are read); a damaged file is one line that
names it."""

from __future__ import annotations

import os
import shutil

import h5py
import pytest

from pipeline.cli import main
from pipeline.runner import COMPARE_NAME, compare_output

from conftest import STUDIES


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    out = tmp_path_factory.mktemp("scene") / "fourbar.h5"
    assert main(["run", str(STUDIES / "warp_feed_fourbar.toml"), "-o", str(out),
                 "--no-pictures", "-q"]) == 0
    return out


def test_long_names_are_cut_with_a_hash_that_tells_them_apart(tmp_path):
    paths = [tmp_path / f"{'machine_' * 12}{k}.h5" for k in range(8)]
    a = compare_output(paths)
    b = compare_output(paths[:-1] + [tmp_path / f"{'machine_' * 12}x.h5"])
    assert a == compare_output(list(paths))             # the same inputs: the same name
    assert a != b and a.parent == tmp_path
    assert len(a.name) <= COMPARE_NAME + len("_compare.png") and a.name.endswith("_compare.png")
    short = [tmp_path / "a.h5", tmp_path / "b.h5"]
    assert compare_output(short).name == "a_vs_b_compare.png"       # short names as before


def test_compare_of_many_files_with_long_names_writes_its_picture(scene, tmp_path, capsys):
    paths = []
    for k in range(6):
        p = tmp_path / f"{'warp_let_off_fourbar_variant_' * 2}{k}.h5"
        shutil.copy(scene, p)
        paths.append(str(p))
    assert main(["compare", *paths, "-q"]) == 0
    pics = list(tmp_path.glob("*_compare.png"))
    assert len(pics) == 1 and len(os.fsencode(pics[0].name)) <= 255


def test_a_damaged_file_in_compare_is_one_line_naming_it(scene, tmp_path, capsys):
    bad = tmp_path / "damaged.h5"
    shutil.copy(scene, bad)
    with h5py.File(bad, "a") as f:      # positions of one coordinate: h5py's ValueError
        n = f["dense/position"].shape[0]
        del f["dense/position"]
        f["dense/position"] = [1.0] * n
    capsys.readouterr()
    assert main(["compare", str(scene), str(bad), "--no-pictures"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(bad) in err[0] and "damaged" in err[0], err
