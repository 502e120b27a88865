"""One unit style (issue 55, item 4): every shipped study's run summary and
every CSV header write N·m, m/s², rad/s², kg·m² (pipeline.base.units), never
the ASCII forms; a file written with the ASCII forms still reads, in the one
style."""

import csv
import json
from pathlib import Path

import h5py
import pytest

from pipeline.api import load_study
from pipeline.base.units import ASCII_FORMS, unit_text
from pipeline.runner import run_scene_study
from pipeline.runs.sweep import run_sweep
from pipeline.views.export import export


def _ascii_units(text):
    return [a for a in ASCII_FORMS if a in text]


def _shipped(studies, kind):
    out = []
    for path in sorted(studies.glob("*.toml")):
        study = load_study(path)
        if study.kind == kind and (kind == "scene" or study.search is None):
            out.append(path.name)
    return out


def _check(summary, csv_folder, what):
    text = json.dumps(summary, ensure_ascii=False, default=str)
    assert not _ascii_units(text), (what, _ascii_units(text), text)
    for f in sorted(csv_folder.glob("*.csv")):
        with open(f, newline="", encoding="utf-8") as fh:
            header = ",".join(next(csv.reader(fh)))
        assert not _ascii_units(header), (what, f.name, header)


STUDIES = Path(__file__).resolve().parent.parent / "studies"
def _cases(kind):
    return list(_shipped(STUDIES, kind))


@pytest.mark.slow
@pytest.mark.parametrize("name", _cases("scene"))
def test_every_shipped_scene_says_its_units_in_one_style(studies, tmp_path, name):
    out = tmp_path / f"{name}.h5"
    summary = run_scene_study(load_study(studies / name), out, pictures=False).summary
    export(out, tmp_path / name)
    _check(summary, tmp_path / name, name)


@pytest.mark.slow
@pytest.mark.parametrize("name", _cases("sweep"))
def test_every_shipped_sweep_says_its_units_in_one_style(studies, tmp_path, name):
    out = tmp_path / f"{name}.h5"
    summary = run_sweep(load_study(studies / name), out, candidates=40,
                        progress=False).summary
    export(out, tmp_path / name)
    _check(summary, tmp_path / name, name)


def test_the_one_style():
    assert [unit_text(u) for u in ("N*m", "m/s^2", "rad/s^2", "kg*m^2", "N*m*s", "mm", "1")] \
        == ["N·m", "m/s²", "rad/s²", "kg·m²", "N·m·s", "mm", "1"]
    assert all(not _ascii_units(unit_text(a)) for a in ASCII_FORMS)


def test_a_file_with_ascii_units_reads_in_the_one_style(studies, tmp_path):
    """A scene file written before the one style (its units attributes set
    back to N*m, m/s^2) opens, and its CSV headers read N·m, m/s²."""
    out = tmp_path / "scene.h5"
    run_scene_study(load_study(studies / "ov7_class3.toml"), out, pictures=False)
    old = 0
    with h5py.File(out, "r+") as f:
        def back(name, obj):
            nonlocal old
            u = obj.attrs.get("units") if isinstance(obj, h5py.Dataset) else None
            if isinstance(u, str) and ("·" in u or "²" in u):
                obj.attrs["units"] = u.replace("·", "*").replace("²", "^2")
                old += 1
        f.visititems(back)
    assert old > 0
    export(out, tmp_path / "csv")
    _check({}, tmp_path / "csv", "an old file")
