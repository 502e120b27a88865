"""The sweep metrics ``peak_shaking_force`` and ``peak_shaking_moment``
(pipeline.model.metric_catalogue): the largest |shaking force| and |shaking
moment| about the crank's pivot over the grid's positions, from the force stage.

Asked for by name in a copy of the synthesis study, they are stored with the
catalogue's units and description (not default metrics), NaN where the force
stage did not run, and equal to the scene path's largest value over the same
positions (the reference design and candidates re-run as scenes)."""

import json
import re
import tomllib

import h5py
import numpy as np
import pytest

from pipeline.base.units import unit_text

from pipeline.analysis.candidate import rerun_candidate
from pipeline.kernels import config as kc
from pipeline.model.metric_catalogue import BY_NAME, DEFAULT_METRICS
from pipeline.runs.sweep import run_sweep
from pipeline.study.reader import load_study
from support.tolerances import SWEEP_VS_SCENE_REL

NAMES = ("peak_shaking_force", "peak_shaking_moment")
CANDIDATES = 300


@pytest.fixture(scope="module")
def swept(studies, tmp_path_factory):
    folder = tmp_path_factory.mktemp("shaking")
    src = studies / "ov7_synthesis.toml"
    text = src.read_text()
    names = tomllib.loads(text)["sweep"].get("metrics", list(DEFAULT_METRICS))
    text = re.sub(r"^metrics = \[[^\]]*\]\n", "", text, flags=re.M)
    assert text.count("\n[sweep]\n") == 1
    text = text.replace("\n[sweep]\n", "\n[sweep]\nmetrics = "
                        f"{json.dumps(list(names) + list(NAMES))}\n")
    (folder / src.name).write_text(text)
    study = load_study(folder / src.name)
    out = folder / "sweep.h5"
    run_sweep(study, out, candidates=CANDIDATES, progress=False)
    return out


def _scene_peaks(run):
    fr = run.dense.forces
    return {"peak_shaking_force": fr.shaking_magnitude.max(),
            "peak_shaking_moment": np.abs(fr.shaking[:, 2]).max()}


def test_stored_with_the_catalogues_units_nan_without_forces(swept):
    with h5py.File(swept, "r") as f:
        ran = (f["candidates/status"][()] == kc.OK) & f["candidates/forces_evaluated"][()]
        assert ran.sum() >= 10
        for name in NAMES:
            d = f[f"metrics/{name}"]
            assert d.attrs["units"] == unit_text(BY_NAME[name].units)   # the files' style
            assert d.attrs["long_name"] == BY_NAME[name].long_name
            assert name not in DEFAULT_METRICS
            v = d[()]
            assert (v[ran] > 0).all() and np.isnan(v[~ran]).all()
    assert BY_NAME["peak_shaking_force"].units == "N"
    assert BY_NAME["peak_shaking_moment"].units == "N*m"


def test_they_agree_with_the_scene_path(swept):
    """The reference design (mechanism B at the operating speed) and three
    candidates whose forces ran, re-run as scenes over the sweep's grid."""
    with h5py.File(swept, "r") as f:
        m = {n: f[f"metrics/{n}"][()] for n in NAMES}
        ref = {n: f[f"reference/{n}"][()][0] for n in NAMES}
        ran = (f["candidates/status"][()] == kc.OK) & f["candidates/forces_evaluated"][()]
    run = rerun_candidate(swept, "reference")
    assert run.study.mechanism.crank.omega1 == -97.2
    assert len(run.dense.phi) == run.study.sweep.positions == 360
    want = _scene_peaks(run)
    print("\nreference design: " + ", ".join(f"{n} {ref[n]:.10g} (scene {want[n]:.10g})"
                                            for n in NAMES))
    for n in NAMES:
        assert ref[n] == pytest.approx(want[n], rel=SWEEP_VS_SCENE_REL), n
    for i in np.flatnonzero(ran)[:3]:
        want = _scene_peaks(rerun_candidate(swept, int(i)))
        for n in NAMES:
            assert m[n][i] == pytest.approx(want[n], rel=SWEEP_VS_SCENE_REL), (i, n)
