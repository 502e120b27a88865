"""The plain bearings' peaks with friction (issue 52): each pin's peak pressure
p, sliding speed v and p*v of mechanism B with friction
(studies/ov7_friction.toml) is refined between the dense positions like every
other peak of a scene (``solve.peaks``): at least the largest dense sample,
and within 1e-9 of a reference that evaluates the exact kernels (the
kinematics by continuation, then the reactions with friction) at 100,000
positions and zooms twice, 1001 times each, round the largest samples (no
maximiser).  The results file stores them in /friction with their crank
angles, and the summary prints them against p_max and pv_max.  Before, they
were the largest of the 360 dense positions (p*v up to 2e-4 low)."""

import json
import math

import h5py
import numpy as np
import pytest

from pipeline.cli import main
from pipeline.kernels import config as kc
from pipeline.solve.friction import scene_forces_with_friction
from pipeline.solve.scene import revolution_angles, run_scene, solve_curves
from pipeline.study.reader import load_study

FINE = 100_000          # the reference's revolution: 0.0036 deg steps
ZOOMS = 2               # then twice SUB samples across the best sample's neighbours
SUB = 1001
RIVALS = 4              # the reference's local maxima zoomed into, within 0.1 % of the top
REL = 1e-9              # the refined peak against the reference
STORED = {"bearing_pressure": "peak_pressure", "sliding_speed": "peak_sliding_speed",
          "bearing_pv": "peak_pv"}          # the /friction dataset of each peak
DENSE = {"bearing_pressure": "bearing_pressure", "sliding_speed": "sliding_speed",
         "bearing_pv": "pv"}                # the /dense dataset it is the peak of


def _bearings(res, phis):
    """{(quantity, joint): array over ``phis``} of the exact kernels, walked
    from phis[0]."""
    mech, plan = res.study.mechanism, res.plan

    def kinematics(path):
        return solve_curves(plan, path, kc.ACCELERATIONS, res.tolerances)
    c = kinematics(phis)
    assert (c.status == kc.OK).all()
    fr = scene_forces_with_friction(mech, plan, c, kinematics).friction
    assert (fr.status == kc.OK).all()
    out = {}
    for j, (name, _, _) in enumerate(fr.spec.pins):
        out[("bearing_pressure", name)] = fr.pressure[:, j]
        out[("sliding_speed", name)] = fr.sliding_speed[:, j]
        out[("bearing_pv", name)] = fr.pv[:, j]
    return out


def _reference(res):
    """{(quantity, joint): the largest value} from FINE positions, zoomed ZOOMS
    times round each of the largest local maxima."""
    crank = res.study.mechanism.crank
    phis = revolution_angles(crank, FINE)
    h = crank.rot * 2.0 * math.pi / FINE
    fine = _bearings(res, phis)
    zoomed = {}

    def zoom(k, mid, w):        # (walked from the fine position before: the revolution's branch)
        key = (k, float(mid), float(w))
        if key not in zoomed:
            sub = mid + w * np.linspace(-1.0, 1.0, SUB)
            got = _bearings(res, np.concatenate([[phis[k] - 2.0 * h], sub]))
            zoomed[key] = sub, {q: v[1:] for q, v in got.items()}
        return zoomed[key]

    out = {}
    for key, v in fine.items():
        local = (v >= np.roll(v, 1)) & (v >= np.roll(v, -1)) & (v >= (1 - 1e-3) * v.max())
        idx = np.flatnonzero(local)
        best = float(v.max())
        for k in idx[np.argsort(-v[idx])][:RIVALS]:
            mid, w = phis[k], h
            for _ in range(ZOOMS):
                sub, got = zoom(k, mid, w)
                j = int(np.argmax(got[key]))
                best = max(best, float(got[key][j]))
                mid, w = sub[j], 2.0 * w / (SUB - 1)
        out[key] = best
    return out


@pytest.fixture(scope="module")
def run(studies, tmp_path_factory):
    """The shipped study run by the CLI: (its results file, its summary)."""
    import contextlib
    import io
    out = tmp_path_factory.mktemp("friction_peaks") / "f.h5"
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        assert main(["run", str(studies / "ov7_friction.toml"), "-o", str(out),
                     "--no-pictures", "--format", "json"]) == 0
    return out, json.loads(text.getvalue())


def test_bearing_peaks_are_refined_to_a_dense_reference(studies, run):
    path, _ = run
    res = run_scene(load_study(studies / "ov7_friction.toml"))
    ref = _reference(res)
    bad = []
    with h5py.File(path, "r") as f:
        joints = list(f["joint"].asstr()[()])
        g, dense = f["friction"], f["dense"]
        assert len(ref) == 3 * len(joints) == 21 and f.attrs["status"] == "OK"
        for (q, name), want in ref.items():
            j = joints.index(name)
            got = float(g[STORED[q]][j])
            grid = float(np.max(dense[DENSE[q]][:, j]))
            assert got >= grid, (q, name)
            if not abs(got - want) <= REL * abs(want):
                bad.append(f"{q} {name}: {got!r} against {want!r} ({(got - want) / want:.2e})")
    assert not bad, "\n".join(bad)


def test_the_refined_peaks_are_stored_and_printed_with_their_crank_angles(studies, run):
    """The stored peaks are the refined ones (the kernels at their stored crank
    angle give them back), no smaller than the dense revolution's, and the
    summary's bearing lines print them against the limits."""
    path, summary = run
    res = run_scene(load_study(studies / "ov7_friction.toml"))
    phis = res.dense.phi
    with h5py.File(path, "r") as f:
        joints = list(f["joint"].asstr()[()])
        g, dense = f["friction"], f["dense"]
        rows = {q: (g[d][()], g[f"{d}_phi1"][()]) for q, d in STORED.items()}
        grids = {q: dense[d][()] for q, d in DENSE.items()}
    between = 0
    for q, (value, at) in rows.items():
        for j, name in enumerate(joints):
            assert value[j] >= grids[q][:, j].max(), (q, name)
            # the kernels at the stored angle, walked along the revolution up to it
            phi = math.radians(at[j])
            m = int(np.searchsorted(res.study.mechanism.crank.rot * (phis - phis[0]),
                                    res.study.mechanism.crank.rot * (phi - phis[0])))
            again = _bearings(res, np.append(phis[:m], phi))[(q, name)][-1]
            assert again == pytest.approx(value[j], rel=1e-10, abs=0.0), (q, name)
            between += not np.isclose(phis, phi, rtol=0.0, atol=1e-12).any()
    assert between >= 12        # most peaks lie between the dense positions
    p, pv = rows["bearing_pressure"], rows["bearing_pv"]
    for j, name in enumerate(joints):
        line = summary[f"bearing {name}"]
        assert line.startswith(f"p {p[0][j]:.3g} MPa at {p[1][j]:g} deg (within the limit 25)")
        assert f"p*v {pv[0][j]:.3g} MPa·m/s at {pv[1][j]:g} deg" in line
