"""Refined peaks on the fronts (issue 53, item 2): `pipeline analyze` refines the
peak metrics of fronts 1-3 between positions as each design's scene refines
them, stores them beside the grid's and ranks the fronts on them; `pipeline show
--candidate` and the scene of an exported design print the same numbers.

The session's small sweep of the main job (studies/ov7_synthesis.toml)."""

import re

import h5py
import numpy as np
import pytest

from pipeline.analysis.candidate import candidate_scene
from pipeline.analysis.fronts import analyze
from pipeline.cli import main
from pipeline.solve.scene_study import solve_scene
from pipeline.study.reader import load_study
from support.naive_pareto import brute_force_rank
from support.sweep_helpers import copy_of
from support.tolerances import SWEEP_VS_SCENE_REL

REFINED = 1e-9           # the stored refined value against the scene's (the bound)
ROUNDING = 1e-12         # the sweep's grid peak against the scene's grid: rounding only


@pytest.fixture(scope="module")
def analyzed(synthesis_sweep, tmp_path_factory):
    d = tmp_path_factory.mktemp("refined")
    p = copy_of(synthesis_sweep, d, "ov7_synthesis.h5")
    return p, analyze(p)


def ranked_objectives(path):
    """The objectives with the stored refined values where analyze has them, the
    refined objectives' names, and the feasible candidates."""
    with h5py.File(path, "r") as f:
        obj = [str(o) for o in f.attrs["objectives"]]
        F = np.stack([f[f"metrics/{o}"][()] for o in obj], axis=1)
        g = f["analysis/refined"]
        rows = g["index"][()]
        ranked = [str(o) for o in g.attrs["ranked_on"]]
        for j, o in enumerate(obj):
            if o in ranked:
                F[rows, j] = g[o][()]
        return F, ranked, f["candidates/feasible"][()]


def test_fronts_1_to_3_carry_refined_peaks_beside_the_grid(analyzed, synthesis_sweep):
    p, summary = analyzed
    with h5py.File(p, "r") as f, h5py.File(synthesis_sweep, "r") as src:
        rank = f["analysis/pareto_rank"][()]
        g = f["analysis/refined"]
        rows = g["index"][()]
        assert set(np.flatnonzero((rank >= 1) & (rank <= 3))) <= set(rows)
        assert (g["status"][()] == 0).all()
        for m in ("peak_reaction", "peak_M_bal"):
            grid = f[f"metrics/{m}"][()]
            np.testing.assert_array_equal(grid, src[f"metrics/{m}"][()])   # the grid's kept
            assert "grid's positions" in f[f"metrics/{m}"].attrs["refined"]
            d = g[m]
            assert d.attrs["units"] == f[f"metrics/{m}"].attrs["units"]
            assert "refined between the grid's positions" in d.attrs["long_name"]
            # a refined maximum is never below the grid's largest sample (the two grids
            # agree to rounding: the sweep's lanes against the scene's path)
            assert (d[()] >= grid[rows] * (1.0 - ROUNDING)).all(), m
            assert (d[()] > grid[rows]).any(), m     # and usually above it
        assert g["peak_phi"].attrs["units"] == "deg"
        assert list(g.attrs["ranked_on"]) == ["peak_reaction"]
    assert "fronts ranked on the refined peak_reaction" in summary["refined peaks"]


def test_fronts_are_ranked_on_the_refined_values(analyzed):
    p, _ = analyzed
    F, ranked, feas = ranked_objectives(p)
    with h5py.File(p, "r") as f:
        rank = f["analysis/pareto_rank"][()]
        front = f["analysis/front1/index"][()]
        np.testing.assert_array_equal(f["analysis/front1/objectives"][()], F[front])
    np.testing.assert_array_equal(rank[(rank >= 1) & (rank <= 3)],
                                  brute_force_rank(F, feas)[(rank >= 1) & (rank <= 3)])


def test_a_grid_value_far_from_the_refined_one_does_not_rank(analyzed, tmp_path):
    """A front-1 design whose stored grid peak reaction is made half its value
    would dominate on the grid; ranked on its refined value (its scene's, which
    the file's /metrics do not change) it stands where it truly is."""
    p, _ = analyzed
    q = copy_of(p, tmp_path)
    with h5py.File(q, "r+") as f:
        i = int(f["analysis/front1/index"][0])
        f["metrics/peak_reaction"][i] *= 0.5
    analyze(q)
    F, _, feas = ranked_objectives(q)
    with h5py.File(q, "r") as f:
        rank = f["analysis/pareto_rank"][()]
        grid = np.stack([f[f"metrics/{o}"][()] for o in ("dwell_error", "peak_reaction")],
                        axis=1)
        g = f["analysis/refined"]
        refined_i = g["peak_reaction"][np.flatnonzero(g["index"][()] == i)[0]]
    assert refined_i > 1.9 * grid[i, 1]
    top = (rank >= 1) & (rank <= 3)
    np.testing.assert_array_equal(rank[top], brute_force_rank(F, feas)[top])
    on_grid = brute_force_rank(grid, feas)
    assert not np.array_equal(rank[top], on_grid[top]), "the grid's ranks differ here"


def test_show_and_the_exported_scene_print_the_stored_refined_peak(analyzed, tmp_path,
                                                                   capsys):
    p, _ = analyzed
    with h5py.File(p, "r") as f:
        front = f["analysis/front1/index"][()]
        g = f["analysis/refined"]
        stored = dict(zip(g["index"][()], g["peak_reaction"][()]))
        grid = f["metrics/peak_reaction"][()]
    for i in front:
        capsys.readouterr()
        assert main(["show", str(p), "--candidate", str(i), "-o",
                     str(tmp_path / f"c{i}.png")]) == 0
        line = re.search(r"refined peak reaction: ([0-9.e+]+) N", capsys.readouterr().out)
        assert float(line.group(1)) == pytest.approx(stored[i], rel=REFINED), i
    # the scene of an exported design (`pipeline export --study`), solved as `pipeline run`
    i = int(front[0])
    toml = tmp_path / "design.toml"
    assert main(["export", str(p), "--study", str(toml), "--candidate", str(i), "-q"]) == 0
    for study in (load_study(toml), candidate_scene(p, i)[0]):
        res = solve_scene(study)
        peaks = [q for q in res.peaks if q.quantity == "reaction"]
        best = max(peaks, key=lambda q: q.value)
        assert best.value == pytest.approx(stored[i], rel=REFINED)
        assert max(q.grid_value for q in peaks) == pytest.approx(grid[i], rel=SWEEP_VS_SCENE_REL)


def test_the_refinement_on_processes_gives_every_designs_own_numbers(analyzed, monkeypatch):
    """Fronts of many designs are refined on worker processes (``python -m
    pipeline.analysis.refined``), slices handed out in turn: the values and
    statuses of the designs to the bit as one process gives them, in their
    order, the progress told slice by slice; a worker that fails is an error
    naming what it said, not a hang."""
    from pipeline.analysis import refined as rf
    from pipeline.analysis.fronts import read_sweep
    from pipeline.study.reader import stored_study
    p, _ = analyzed
    data = read_sweep(p)
    study = stored_study(data.attrs, p)
    with h5py.File(p, "r") as f:
        params = data.params[f["analysis/refined/index"][:20]]
    metrics = ("peak_reaction", "peak_M_bal")
    alone = rf.refine_designs(study, params, metrics)
    monkeypatch.setattr(rf, "PROCESSES_FROM", 2)
    monkeypatch.setattr(rf, "SLICE", 8)
    told = []
    shared = rf.refine_designs(study, params, metrics, told.append, jobs=2)
    for a, b in zip(alone, shared):
        assert a.tobytes() == b.tobytes()
    assert told == sorted(told) and told[-1] == len(params) and len(told) == 3
    with pytest.raises(RuntimeError, match="a process refining the fronts' peaks ended: KeyError"):
        rf.refine_designs(study, params, ("no_such_metric",), jobs=2)    # (a KeyError there)
