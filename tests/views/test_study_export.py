"""A sweep's design as a scene study of its own (`pipeline export RESULTS
--candidate knee --study OUT.toml`, issue 51): `pipeline run` of the written
study gives the sweep's metrics of that design and `pipeline show
--candidate`'s numbers; the TOML writer round-trips every study file."""

import math
import tomllib

import h5py
import numpy as np
import pytest

from pipeline.cli import main
from pipeline.study.writer import degrees_exact, toml_text
from support.sweep_helpers import copy_of
from support.tolerances import LANE_AGREEMENT_REL, LANE_MARGIN_REL


@pytest.fixture(scope="module")
def knee(synthesis_sweep, tmp_path_factory):
    """(sweep file with its analysis, the knee's exported study, its scene results)."""
    folder = tmp_path_factory.mktemp("study_export")
    sweep = copy_of(synthesis_sweep, folder)
    assert main(["analyze", str(sweep), "-q"]) == 0
    study = folder / "knee.toml"
    assert main(["export", str(sweep), "--candidate", "knee", "--study", str(study), "-q"]) == 0
    out = folder / "knee.h5"
    assert main(["run", str(study), "-o", str(out), "--no-pictures", "-q"]) == 0
    return sweep, study, out


def _datasets(f):
    names = []
    f.visit(names.append)
    return {n: f[n][()] for n in names if isinstance(f[n], h5py.Dataset)}


def test_the_study_reproduces_the_candidate_scene_bit_for_bit(knee):
    """`pipeline run knee.toml` stores what the sweep's design re-run as a
    scene (candidate_scene, solved in memory) gives: every dataset identical."""
    from pipeline.analysis.candidate import candidate_scene
    from pipeline.results.scene_file import scene_in_memory
    from pipeline.solve.scene_study import solve_scene
    sweep, study_file, out = knee
    study, _, number = candidate_scene(sweep, "knee")
    text = study_file.read_text()
    assert f"candidate #{number} of {sweep}" in text.splitlines()[1]     # where it came from
    with scene_in_memory(solve_scene(study)) as want, h5py.File(out, "r") as got:
        a, b = _datasets(want), _datasets(got)
        assert a.keys() == b.keys()
        for n in a:
            np.testing.assert_array_equal(a[n], b[n], err_msg=n)


def test_the_study_gives_the_sweeps_metrics_and_shows(knee):
    """The scene's dwell error, stroke, peak reaction, peak M_bal and
    singularity margin equal the sweep file's row of the knee (the lanes'
    agreement with the scene path, LANE_AGREEMENT_REL; the margin
    LANE_MARGIN_REL), its dwell start and peak angle exactly; and `pipeline
    show --candidate knee`'s re-run has the same positions and reactions bit
    for bit, its dwell error to rounding (its theta starts at zero)."""
    from pipeline.analysis.candidate import rerun_candidate, resolve_candidate
    from pipeline.results.storage import open_results
    sweep, _, out = knee
    with open_results(sweep, "sweep") as f:
        i = resolve_candidate(f, "knee")
        row = {k: float(f["metrics"][k][i]) for k in f["metrics"]}
    with h5py.File(out, "r") as g:
        scene = {"dwell_error": g["motion/dwell_error"][()], "stroke": g["motion/stroke"][()],
                 "peak_reaction": g["peaks/reaction_grid"][()].max(),
                 "peak_M_bal": g["peaks/M_bal_grid"][()],
                 "singularity_margin": g["dense/margin"][()].min()}
        dwell_start = float(g["motion/dwell_start"][()])
        pos = g["dense/position"][()]
        reactions = g["dense/reactions"][()]
        phi = g["dense/phi1"][()]
    for k, v in scene.items():
        rel = LANE_MARGIN_REL if k == "singularity_margin" else LANE_AGREEMENT_REL
        assert v == pytest.approx(row[k], rel=rel, abs=0), k
    assert dwell_start == row["dwell_start"]
    k = int(np.argmax(np.hypot(reactions[..., 0], reactions[..., 1]).max(axis=1)))
    assert phi[k] == pytest.approx(row["peak_phi"], abs=1e-9)
    run = rerun_candidate(sweep, "knee")             # what `pipeline show --candidate` draws
    np.testing.assert_array_equal(run.dense.pos[:, :pos.shape[1]], pos)
    np.testing.assert_array_equal(run.dense.forces.magnitude,
                                  np.hypot(reactions[..., 0], reactions[..., 1]))
    assert np.nanmax(run.dense.forces.magnitude) == scene["peak_reaction"]
    assert run.dwell_error == pytest.approx(scene["dwell_error"], rel=1e-12, abs=0)


def test_the_study_file_is_refused_where_it_would_replace_a_results_file(knee, tmp_path,
                                                                          capsys):
    sweep, _, out = knee
    for target in (sweep, out):
        before = target.read_bytes()
        assert main(["export", str(sweep), "--candidate", "knee", "--study", str(target)]) != 0
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and str(target) in err, err
        assert target.read_bytes() == before
    assert main(["export", str(out), "--study", str(tmp_path / "x.toml")]) != 0
    assert "scene result" in capsys.readouterr().err
    assert not (tmp_path / "x.toml").exists()


@pytest.mark.parametrize("name", ["ov7_synthesis.toml", "ov7_base.toml", "takeup_dynamics.toml",
                                  "ov7_robust_search.toml", "cam_rocker_input_sweep.toml"])
def test_the_toml_writer_round_trips_a_study(studies, name):
    """Every value read back as written: floats to the bit, strings with
    their quotes and backslashes, tables and arrays of tables."""
    data = tomllib.loads((studies / name).read_text())
    assert tomllib.loads(toml_text(data, ["a comment"])) == data


def test_the_toml_writer_keeps_awkward_values():
    data = {"s": {"text": 'a "quoted" \\ back\tslash\n\x7f', "odd key": 0.1 + 0.2,
                  "tiny": 5e-324, "big": 1.7976931348623157e308, "neg": -0.0, "inf": math.inf,
                  "list": [{"a": 1}, {"b": [1.5, "x"]}]},
            "t": [{"name": "body 1", "com": {"lS": 1 / 3}}]}
    back = tomllib.loads(toml_text(data))
    assert back == data
    assert math.copysign(1.0, back["s"]["neg"]) == -1.0


def test_degrees_exact_turns_back_into_the_same_radians():
    """An angle that a study's degrees give (math.radians of a float) is
    written back as degrees that give it exactly; any other within an ulp."""
    rng = np.random.default_rng(51)
    for deg in rng.uniform(-720.0, 720.0, 2000):
        rad = math.radians(float(deg))
        assert math.radians(degrees_exact(rad)) == rad
        other = math.nextafter(rad, math.inf)
        assert abs(math.radians(degrees_exact(other)) - other) <= 2 * math.ulp(other)
