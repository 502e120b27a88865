"""A design as a DXF drawing (`pipeline export RESULTS [--candidate ID] --dxf
DIR`, issue 51), read back with ezdxf: the joints' circles at each drawn crank
angle are the results file's positions, the paths its dense positions, the
link-length dimensions the study's lengths; ezdxf's audit finds no error; the
SVG renders."""

import math
import xml.etree.ElementTree as ET

import ezdxf
import h5py
import numpy as np
import pytest

from pipeline.cli import main
from pipeline.study.reader import load_study
from support.sweep_helpers import copy_of

MM = 1e-9               # positions and lengths read back, mm
APPID = "PIPELINE"

# the study's link lengths (parameters) by the segment drawn between two points
LENGTHS = {
    "ov7_class3": {("P1", "P2"): "crank.length", ("P2", "P3"): "triad.L23",
                   ("P3", "P4"): "triad.L34", ("P4", "P5"): "triad.L45",
                   ("P5", "P3"): "triad.L35", ("P6", "P4"): "triad.L46",
                   ("P7", "P5"): "triad.L57", ("P7", "P8"): "output arm.length"},
    "ov7_base": {("P1", "P2"): "crank.length", ("P2", "P3"): "RRR[1].L_AB",
                 ("P4", "P3"): "RRR[1].L_CB", ("P3", "P5"): "RRR[2].L_AB",
                 ("P6", "P5"): "RRR[2].L_CB", ("P5", "P7"): "RRR[3].L_AB",
                 ("P8", "P7"): "RRR[3].L_CB", ("P8", "P9"): "output arm.length"},
}
LENGTHS["ov7_synthesis"] = LENGTHS["ov7_class3"]     # the sweep of mechanism B's dimensions


@pytest.fixture(scope="module")
def scenes(studies, tmp_path_factory):
    """Mechanism B's and mechanism A's scenes, run once."""
    folder = tmp_path_factory.mktemp("dxf_scenes")
    out = {}
    for name in ("ov7_class3", "ov7_base"):
        out[name] = folder / f"{name}.h5"
        assert main(["run", str(studies / f"{name}.toml"), "-o", str(out[name]),
                     "--no-pictures", "-q"]) == 0
    return out


def _xdata(e):
    try:
        return [t.value for t in e.get_xdata(APPID)]
    except ezdxf.DXFValueError:
        return []


def read_drawing(path):
    """{phi deg: {point: (centre, diameter, kind)}}, {point: path vertices},
    [(a, b, measurement)], the document."""
    doc = ezdxf.readfile(path)
    assert doc.header["$INSUNITS"] == 4
    positions = {}
    for ref in doc.modelspace().query("INSERT"):
        phi = _xdata(ref)[1]
        circles = {}
        for c in doc.blocks[ref.dxf.name].query("CIRCLE"):
            x = _xdata(c)
            circles[x[0]] = (np.array(c.dxf.center)[:2], 2 * c.dxf.radius, x[2])
            assert x[1] == phi
        positions[phi] = circles
    paths = {_xdata(p)[0]: np.array([v[:2] for v in p.get_points("xy")])
             for p in doc.modelspace().query("LWPOLYLINE[layer=='PATHS']")}
    dims = [(*_xdata(d)[1:3], d.get_measurement()) for d in doc.modelspace().query("DIMENSION")]
    return positions, paths, dims, doc


def _position_at(f, phi):
    for group in ("table", "dense"):
        k = np.flatnonzero(np.abs(f[f"{group}/phi1"][()] - phi) <= 1e-9)
        if k.size:
            return f[f"{group}/position"][k[0]]
    raise AssertionError(f"phi1 = {phi} is not a stored position")


def _extremes(f, rocker, names):
    """Crank angles of the output rocker's two extremes among the dense positions."""
    pos = f["dense/position"][()]
    a, b = (names.index(q) for q in rocker)
    v = pos[:, b] - pos[:, a]
    theta = np.unwrap(np.arctan2(v[:, 1], v[:, 0]))
    return {float(f["dense/phi1"][int(np.argmin(theta))]),
            float(f["dense/phi1"][int(np.argmax(theta))])}


def check_drawing(dxf, results, study, par):
    """The drawing of the design in ``results`` (a scene file) against it;
    ``par``: the study's parameters by name.  Returns the drawing's angles."""
    positions, paths, dims, doc = read_drawing(dxf)
    assert not doc.audit().has_errors
    with h5py.File(results, "r") as f:
        names = [str(n) for n in f["mechanism"].attrs["point_names"]]
        pins = {}
        if "pin_d_min" in f["peaks"]:
            plan = study.mechanism.compile()
            joint = dict(zip(plan.joint_names, plan.joint_point))
            for j, d in zip(f["joint"][()], f["peaks/pin_d_min"][()]):
                p = plan.point_names[int(joint[j.decode() if isinstance(j, bytes) else j])]
                pins[p] = max(d, pins.get(p, 0.0))
        for phi, circles in positions.items():
            want = _position_at(f, phi)
            assert sorted(circles) == sorted(names)
            for i, p in enumerate(names):
                centre, diameter, kind = circles[p]
                np.testing.assert_allclose(centre, want[i], rtol=0, atol=MM, err_msg=(phi, p))
                if p in pins:
                    assert kind == "pin d_min" and diameter == pytest.approx(pins[p], rel=1e-12)
                else:
                    assert kind == "nominal mark"
        dense = f["dense/position"][()]
        for p, vertices in paths.items():
            np.testing.assert_allclose(vertices, dense[:, names.index(p)], rtol=0, atol=MM,
                                       err_msg=p)
        angles = set(positions)
        default = {float(f["table/phi1"][0])} | _extremes(f, study.output.rocker, names)
        assert default <= angles
    lengths = LENGTHS[study.name.split("_candidate")[0]]
    got = {(a, b): m for a, b, m in dims}
    assert set(got) == set(lengths)
    for pair, name in lengths.items():
        assert got[pair] == pytest.approx(par[name], rel=0, abs=MM), pair
    return positions, paths, default


@pytest.mark.parametrize("name", ["ov7_class3", "ov7_base"])
def test_a_scene_drawing_reads_back(scenes, studies, tmp_path, name):
    out = tmp_path / "cad"
    assert main(["export", str(scenes[name]), "--dxf", str(out), "--paths", "--svg", "-q"]) == 0
    study = load_study(studies / f"{name}.toml")
    plan = study.mechanism.compile()
    positions, paths, default = check_drawing(out / f"{name}.dxf", scenes[name], study,
                                              dict(zip(plan.par_names, plan.par)))
    assert set(positions) == default          # no --phi: the defaults only
    moving = [p for p in plan.point_names[:plan.n_visible] if p not in study.mechanism.fixed]
    assert sorted(paths) == sorted(moving)
    root = ET.fromstring((out / f"{name}.svg").read_bytes())
    assert root.tag.endswith("svg")
    assert sum(1 for e in root.iter() if e.tag.endswith("path")) > 20


def test_a_drawing_at_chosen_angles(scenes, studies, tmp_path):
    """--phi: a stored position is the file's; an angle between the stored
    ones is solved there (every link keeps its length, the eyelet lies between
    its neighbouring dense positions); without --paths, the working point's
    path alone."""
    out = tmp_path / "cad"
    assert main(["export", str(scenes["ov7_class3"]), "--dxf", str(out), "--phi", "-60",
                 "-45.5", "-q"]) == 0
    positions, paths, dims, _ = read_drawing(out / "ov7_class3.dxf")
    stored, between = sorted(positions)          # the stored angle as the file has it
    assert [stored, between] == pytest.approx([-60.0, -45.5], abs=1e-9)
    assert list(paths) == ["P8"]
    study = load_study(studies / "ov7_class3.toml")
    plan = study.mechanism.compile()
    par = dict(zip(plan.par_names, plan.par))
    at = {p: c[0] for p, c in positions[between].items()}
    for (a, b), name in LENGTHS["ov7_class3"].items():
        assert math.dist(at[a], at[b]) == pytest.approx(par[name], abs=MM)
    with h5py.File(scenes["ov7_class3"], "r") as f:
        names = [str(n) for n in f["mechanism"].attrs["point_names"]]
        np.testing.assert_allclose([positions[stored][p][0] for p in names],
                                   _position_at(f, stored), rtol=0, atol=MM)
        near = f["dense/position"][[45, 46], names.index("P8")]
    step = math.dist(*near)
    assert math.dist(at["P8"], near[0]) < step and math.dist(at["P8"], near[1]) < step


def test_the_knees_drawing_reads_back(synthesis_sweep, tmp_path):
    """A sweep's knee: the drawing against `pipeline run` of the knee's
    exported study (the same design as a scene), its lengths the knee's."""
    sweep = copy_of(synthesis_sweep, tmp_path)
    assert main(["analyze", str(sweep), "-q"]) == 0
    out = tmp_path / "cad"
    assert main(["export", str(sweep), "--candidate", "knee", "--dxf", str(out), "--svg",
                 "-q"]) == 0
    assert main(["export", str(sweep), "--candidate", "knee", "--study",
                 str(tmp_path / "knee.toml"), "-q"]) == 0
    assert main(["run", str(tmp_path / "knee.toml"), "-o", str(tmp_path / "knee.h5"),
                 "--no-pictures", "-q"]) == 0
    study = load_study(tmp_path / "knee.toml")
    plan = study.mechanism.compile()
    [dxf] = list(out.glob("ov7_synthesis_candidate*.dxf"))
    number = dxf.stem.rsplit("candidate", 1)[1]
    assert study.name == f"ov7_synthesis_candidate{number}"
    check_drawing(dxf, tmp_path / "knee.h5", study, dict(zip(plan.par_names, plan.par)))
    assert dxf.with_suffix(".svg").stat().st_size > 0


def test_refusals_are_one_line(scenes, tmp_path, capsys):
    scene = scenes["ov7_base"]
    cases = [(["--dxf", str(tmp_path), "--candidate", "knee"], "scene result"),
             (["--dxf", str(scene)], "is a file"),
             (["--csv", str(tmp_path), "--svg"], "--dxf or --study"),
             (["--dxf", str(tmp_path), "--csv", str(tmp_path)], "give one output")]
    for args, words in cases:
        assert main(["export", str(scene), *args]) != 0
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and words in err, err
    assert not list(tmp_path.iterdir())


def test_a_file_written_before_the_go_on_entry_draws_with_its_tolerances():
    """A scene file's stored tolerance vector from before T_GO_ON (14 entries) is
    completed with the defaults, not read past its end by the kernels."""
    from pipeline.kernels import config as kc
    old = kc.default_tolerances(newton_tol=1e-11)[:kc.T_GO_ON]
    t = kc.stored_tolerances(old)
    assert len(t) == kc.N_TOLS and np.array_equal(t[:kc.T_GO_ON], old)
    assert t[kc.T_GO_ON] == kc.default_tolerances()[kc.T_GO_ON] == 1.0
