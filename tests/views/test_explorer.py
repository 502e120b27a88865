"""The report's explorer (views/explorer.py, explorer_designs.py, page.py): the
data it gives plotly.js, compact (a block of binary arrays, packed) and
script-safe, and the rules it draws by (the fronts it opens on, log axes, which
designs carry their cycle, the command's path).  The browser side is tested in
tests/analysis/test_analysis.py (headless Chromium)."""

import json
import re
import shlex
from pathlib import Path
from types import SimpleNamespace

import h5py
import numpy as np
import pytest

from pipeline.views import explorer as ex
from pipeline.views.page import (ArrayBlock, block_array, json_numbers, packed, render,
                                 rounded, script_json, unpacked)
from pipeline.results.storage import variables
from support.html_page import explorer_data


# ---------------------------------------------------------------- numbers and text
def test_numbers_keep_five_significant_digits_and_no_minus_zero():
    v = [0.0400312345, 715.2345678, 123456789.0, -1.234567e-5, 1.23456e-25, -0.0, -1e-300 * 0,
         99999.7, 1 / 3, 2 / 3 * 1e-7, np.nan, np.inf]
    got = json_numbers(v)
    assert got[:10] == [0.040031, 715.23, 123460000.0, -1.2346e-05, 1.2346e-25, 0.0, 0.0,
                        100000.0, 0.33333, 6.6667e-08]
    assert got[10:] == [None, None]
    text = json.dumps(got)
    assert not re.search(r"(?<![\d.e])-0(\.0+)?(?![\d.e])", text), text      # no -0
    for x in np.random.default_rng(1).lognormal(0, 6, 2000) * np.sign(np.random.default_rng(2)
                                                                        .normal(size=2000)):
        r = float(rounded([x])[0])
        assert len(repr(abs(r)).replace(".", "").lstrip("0").split("e")[0].rstrip("0")) <= 5
        assert r == pytest.approx(x, rel=5e-5)
    assert json_numbers([1.0, 2.0, -0.0]) == [1, 2, 0]            # whole columns as integers


def test_json_inside_a_script_never_closes_it():
    text = str(script_json({"unit": "</script><img src=x onerror=alert(1)>&amp;",
                            "sep": "\u2028"}))
    assert "<" not in text and ">" not in text and "&" not in text and "\u2028" not in text
    assert json.loads(text)["unit"].startswith("</script>")


def test_packed_text_round_trips_and_holds_no_markup():
    text = "var a = '</script><b>' && 1 < 2;\u2028" * 50
    page = str(packed(text))
    assert re.fullmatch(r"[A-Za-z0-9+/=]+", page)       # nothing to close a <script> early
    assert unpacked(page).decode("utf-8") == text
    assert str(packed(text)) == page                     # the same page for the same text
    assert len(page) < len(text) / 3                      # gzip at work on repeated text
    assert unpacked(packed(b"\x00\xff" * 10)) == b"\x00\xff" * 10


def test_an_array_block_holds_each_array_in_the_smallest_type():
    block = ArrayBlock()
    cases = [([0, 1, 2, 127], "i1"), ([0, 200], "u1"), ([-5, 300], "i2"), ([0, 60000], "u2"),
             ([-1, 70000], "i4"), ([3, 2 ** 40 + 1], "f8"), (np.array([True, False]), "i1"),
             ([0.5, 1.0], "f4"), ([1.0, np.nan], "f4"), ([2.0, np.inf], "f4"), ([], "f4")]
    specs = [block.add(v) for v, _ in cases]
    assert [sp["dtype"] for sp in specs] == [t for _, t in cases]
    raw = unpacked(block.packed())
    assert len(raw) == block.size
    ends = 0
    for (values, _), sp in zip(cases, specs):
        assert sp["offset"] % 8 == 0 and sp["offset"] >= ends     # aligned, no overlap
        got = block_array(raw, sp)
        ends = sp["offset"] + got.nbytes
        want = np.asarray(values, float)
        want = np.where(np.isfinite(want), want, np.nan)           # missing: NaN
        np.testing.assert_array_equal(got.astype(float), want)


def test_an_array_block_keeps_five_significant_digits():
    x = np.random.default_rng(3).lognormal(0, 4, 5000) * np.where(
        np.random.default_rng(4).random(5000) < 0.5, -1, 1)
    block = ArrayBlock()
    spec = block.add(x)
    got = block_array(unpacked(block.packed()), spec).astype(float)
    assert spec["dtype"] == "f4"
    np.testing.assert_allclose(got, x, rtol=5e-5)
    np.testing.assert_array_equal(got, rounded(x).astype(np.float32))   # the page's digits


def test_templates_escape_the_study_text():
    col = SimpleNamespace(key="x", label="<b>L12</b>", unit="mm")
    html = render("explorer.html.j2", columns=[col], objectives=[], x="x", y="x", n_points=1,
                  n_designs=0, feasible_note="", all_note="", data=packed(script_json({})),
                  arrays=ArrayBlock().packed(), zoom_fronts=3, has_knee=False,
                  has_reference=True)
    assert "<b>L12</b>" not in html and "&lt;b&gt;L12&lt;/b&gt;" in html


@pytest.mark.parametrize("values, log", [([0.01, 0.5, 3.0], True), ([1.0, 50.0], False),
                                         ([0.01, 0.0, 30.0], False), ([-1.0, 500.0], False),
                                         ([1e-3, np.nan, 1.0], True), ([2.0], False)])
def test_a_log_axis_where_positive_data_spans_more_than_two_decades(values, log):
    assert ex.log_axis(values) is log


def test_the_command_names_the_file_from_the_current_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "results").mkdir()
    assert ex.command_path("results/ov7_synthesis.h5") == "results/ov7_synthesis.h5"
    assert ex.command_path(tmp_path / "results" / "a.h5") == "results/a.h5"
    assert ex.command_path("./results/../results/a.h5") == "results/a.h5"
    assert ex.command_path("../x.h5") == "../x.h5"                 # as the user typed it
    outside = Path("/somewhere/else/s.h5")
    assert ex.command_path(outside) == "/somewhere/else/s.h5"
    assert ex.command_path("my results/s 1.h5") == shlex.quote("my results/s 1.h5")
    assert ex.show_command("results/a.h5", 241851) == \
        "pipeline show results/a.h5 --candidate 241851"


def test_which_front_1_designs_carry_their_cycle():
    ana = SimpleNamespace(front1=np.arange(100, 110), knee=104, representatives=[])
    assert ex.design_picks(ana, 50) == list(range(100, 110))         # all of a small front
    assert ex.design_picks(ana, 3) == [100, 104, 109]                # spread: both ends
    ana.knee = 103
    assert ex.design_picks(ana, 3) == [100, 104, 109, 103]           # and the knee
    ana.representatives = [101, 109, 102]
    assert ex.design_picks(ana, 3) == [100, 104, 109, 103, 101, 102]   # and the report's cards
    assert ex.design_picks(ana, 0) == []


def test_the_explorer_caps_its_points_keeping_front_1(monkeypatch):
    monkeypatch.setattr(ex, "MAX_POINTS", 50)
    monkeypatch.setattr(ex, "MAX_INFEASIBLE", 20)
    rng = np.random.default_rng(0)
    n = 1000
    feasible = rng.random(n) < 0.3
    F = rng.random((n, 2))
    F[~feasible & (rng.random(n) < 0.5), 1] = np.nan     # failed designs: no objectives
    params = rng.random((n, 3))
    params[:5] = np.nan                                   # never evaluated
    data = SimpleNamespace(F=F, feasible=feasible, params=params, seed=7)
    front = np.flatnonzero(feasible)[:10]
    rows, n_feas, n_infeas = ex.explorer_rows(data, SimpleNamespace(front1=front))
    assert n_feas == feasible.sum() and n_infeas == (~feasible[5:]).sum()
    assert feasible[rows].sum() == 50 and (~feasible[rows]).sum() == 20
    assert set(front) <= set(rows) and len(set(rows)) == len(rows)
    again, _, _ = ex.explorer_rows(data, SimpleNamespace(front1=front))
    np.testing.assert_array_equal(rows, again)            # seeded


# ---------------------------------------------------------------- on the main job's sweep
@pytest.fixture(scope="module")
def page(synthesis_sweep, tmp_path_factory):
    """The explorer's section of a copy of the session's sweep, analyzed, with
    two front-1 designs' cycles (and the knee's and the reference design's)."""
    from pipeline.analysis.fronts import analyze, read_analysis, read_sweep
    from pipeline.results.storage import open_results
    from support.sweep_helpers import copy_of
    p = copy_of(synthesis_sweep, tmp_path_factory.mktemp("explorer"))
    analyze(p)
    data = read_sweep(p)
    with open_results(p, "sweep") as f:
        ana = read_analysis(f)
    html = ex.explorer_html(p, data, ana, drawings=2)
    return p, data, ana, html, explorer_data(html)


def test_every_feasible_design_and_column_is_there(page):
    p, data, ana, html, d = page
    n_feas = int((data.feasible & np.isfinite(data.F).all(axis=1)).sum())
    assert int(d["feasible"].sum()) == d["counts"]["feasible_shown"] == n_feas
    assert len(d["ids"]) == len(d["feasible"]) == n_feas + d["counts"]["infeasible_shown"]
    with h5py.File(p, "r") as f:
        metrics = set(variables(f["metrics"]))      # the metrics, not the coordinate
        cv = f["candidates/cv"][()]
    cols = {c["key"]: c for c in d["columns"]}
    assert metrics | {"front", "cv"} | set(data.names) == set(cols)
    assert [c["key"] for c in d["columns"][:2]] == list(data.objectives)
    assert d["variables"] == list(data.names)
    ids = d["ids"]
    assert ids.dtype.kind == "i" and d["feasible"].dtype.kind in "iu"
    np.testing.assert_allclose(cols["cv"]["values"], cv[ids], rtol=5e-5, atol=0)
    dwell = cols["dwell_error"]["values"]
    feasible = d["feasible"].astype(bool)
    np.testing.assert_allclose(dwell[feasible], data.F[ids[feasible], 0], rtol=5e-5)
    assert np.isnan(dwell[~feasible]).sum() == np.isnan(data.F[ids[~feasible], 0]).sum()
    assert sorted(ids[d["front1"]]) == sorted(data.id(i) for i in ana.front1)
    assert ids[d["knee"]] == data.id(ana.knee)
    np.testing.assert_array_equal(cols["front"]["values"], ana.rank[ids])
    # the select inputs offer every column, the filters every objective
    assert html.count('<option value="dwell_error"') == 3
    assert 'id="ex-max-1"' in html and 'data-key="peak_reaction"' in html


def test_the_explorer_opens_on_fronts_1_to_3_with_their_log_axes(page):
    """The page opens zoomed on fronts 1 to ZOOM_FRONTS (explorer.js takes the
    axis ranges from them), so a column's log axis is decided by them."""
    p, data, ana, html, d = page
    assert d["zoom_fronts"] == ex.ZOOM_FRONTS == 3
    rank = {c["key"]: c for c in d["columns"]}["front"]["values"]
    near = ex.zoomed_rows(rank)
    np.testing.assert_array_equal(near, (rank >= 1) & (rank <= 3))
    assert 0 < near.sum() < (rank >= 1).sum()
    for c in d["columns"]:
        assert c["log"] == ex.log_axis(c["values"][near]), c["key"]
    assert "opened zoomed on fronts 1 to 3" in " ".join(html.split())


def test_front_designs_carry_their_cycle_and_command(page):
    p, data, ana, html, d = page
    keys = set(d["designs"])
    assert "reference" in keys and str(data.id(ana.knee)) in keys
    assert len(keys) == len(set(ex.design_picks(ana, 2))) + 1
    assert d["command"] == f"pipeline show {ex.command_path(p)} --candidate "
    for key, c in d["designs"].items():
        m = c["mechanism"]
        n = len(m["names"])
        assert len(m["x"]) == len(m["y"]) == len(m["phi"]) == 12
        assert all(len(row) == n for row in m["x"])
        assert all(0 <= a < n and 0 <= b < n for a, b in m["segments"])
        assert m["working_point"] < n and set(m["fixed"]) < set(range(n))
        mo = c["motion"]
        assert len(mo["phi"]) == len(mo["theta"]) == len(mo["dx"]) <= 180
        r = c["reactions"]
        assert r is not None and len(r["joints"]) == len(r["R"]) == len(r["peak"]) == 7
        assert max(r["peak"]) >= max(max(v for v in row if v is not None) for row in r["R"])
        assert c["status"] == "OK"
    # the embedded peak of the knee is the sweep's peak reaction (the scene's
    # reactions at every position against the sweep's)
    knee = d["designs"][str(data.id(ana.knee))]
    assert max(knee["reactions"]["peak"]) == pytest.approx(data.F[ana.knee, 1], rel=1e-3)


def test_no_drawings_embeds_no_cycle(page):
    p, data, ana, _, _ = page
    d, _, _ = ex.explorer_payload(p, data, ana, drawings=0)
    assert d["designs"] == {}
    text = str(script_json(d))
    assert not re.search(r"[\[,:]-0[,\]}]", text) and "NaN" not in text
