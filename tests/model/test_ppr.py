"""PPR, a group type of its own (pipeline.groups.ppr): a slider on a sliding
guide, the RPP chain read from its other end.  Its study fields are a PPR's
(pin, guide, B, slot); it is solved by the RPP's plan row and emitter, so the
PPR study gives bit for bit the numbers of the same mechanism declared as an
RPP (A = the slider's pin).  Also: the one registration table (every type's
emitter is the one its plan code picks) and a sweep over a PPR dimension."""

import math

import h5py
import numpy as np
import pytest

from pipeline import compile as pc
from pipeline.compiler.emit import emitter_classes
from pipeline.model.groups import GROUP_TYPES
from pipeline.group_types.rpp.model import PPR, RPP
from pipeline.solve.scene_study import solve_scene
from pipeline.kernels import sweep as ks
from pipeline.runs.sweep import build_problem
from pipeline.study.reader import load_study, parse_study
from pipeline.base.errors import StudyError
from pipeline.study.sweep_spec import parameter_rows
from pipeline.study.sampling import draw_candidates
from support.lanes import assert_force_lanes_round, assert_lanes_agree, widened_draws

SCENE = "ppr_cross_slide"
SWEEP = "ppr_cross_slide_sweep"


def _as_rpp(text):
    """The same mechanism declared as today's RPP read backwards."""
    for old, new in (('type = "PPR"', 'type = "RPP"'), ('pin = "P7"', 'A = "P7"')):
        assert text.count(old) == 1
        text = text.replace(old, new)
    return text


def _curves(c):
    return {k: getattr(c, k) for k in ("phi", "pos", "d1", "d2", "links")
            if isinstance(getattr(c, k, None), np.ndarray)}


def test_the_ppr_is_declared_with_its_own_fields(studies):
    g = load_study(studies / f"{SCENE}.toml").mechanism.groups[2]
    assert isinstance(g, PPR) and not isinstance(g, RPP)
    assert g == PPR("P7", "P6", "P5", 0.0, math.radians(60.0), 0.0, 0.0, None, "carriage")
    assert GROUP_TYPES["PPR"] is PPR


def test_ppr_gives_bit_for_bit_the_rpp_read_backwards(studies):
    text = (studies / f"{SCENE}.toml").read_text()
    ppr = parse_study(text, "ppr.toml")
    rpp = parse_study(_as_rpp(text), "rpp.toml")
    assert isinstance(rpp.mechanism.groups[2], RPP)
    a, b = ppr.mechanism.compile(), rpp.mechanism.compile()
    for k in ("codes", "gidx", "goff", "par"):
        assert np.array_equal(getattr(a, k), getattr(b, k)), k
    assert a.par_names == b.par_names and a.point_names == b.point_names
    assert pc.source(ppr) == pc.source(rpp)       # the same kernels
    ra, rb = solve_scene(ppr), solve_scene(rpp)
    assert ra.status == rb.status == 0
    for which in ("table", "dense"):
        ca, cb = _curves(getattr(ra, which)), _curves(getattr(rb, which))
        assert ca.keys() == cb.keys() and {"pos", "d1", "d2"} <= ca.keys()
        for k in ca:
            assert np.array_equal(ca[k], cb[k]), (which, k)
        fa, fb = getattr(ra, which).forces, getattr(rb, which).forces
        assert (fa is None) == (fb is None) and fa is not None
        for k, v in vars(fa).items():
            if isinstance(v, np.ndarray):
                assert np.array_equal(v, getattr(fb, k)), (which, "forces", k)
    # the same transmission angle (the slot against the guide: 60 deg), its own label
    pa = {(p.quantity, p.item): p.value for p in ra.peaks}
    assert pa[("min_transmission_angle", "carriage")] == pytest.approx(60.0, abs=1e-9)


def test_the_unnamed_ppr_is_labelled_as_a_ppr(studies):
    text = (studies / f"{SCENE}.toml").read_text().replace('name = "carriage"\n', "", 1)
    m = parse_study(text, "x.toml").mechanism
    assert m.compile().group_names[3] == "PPR[3]"
    from pipeline.model.mechanism import transmission_items
    assert transmission_items(m)[-1][0] == "PPR P7-P6"


PPR_ERRORS = [
    (("slot_angle = 60.0", "slot_angle = 0.0"), "slot_angle",
     "the slot runs along the guide (0 deg from it): the slider cannot move the sliding guide"),
    (('pin = "P7"', 'pin = "P9"'), "pin", "unknown point 'P9'"),
    (('pin = "P7"', 'pin = "P6"'), "pin", "point 'P6' is solved later"),
    (('pin = "P7"', '# pin = "P7"'), "pin", "required field is missing"),
    (('pin = "P7"', 'pin = "P7"\nA = "P7"'), "A", "unknown key 'A'"),
    (("slot_offset = 0.0", "slot_offset = 1e300"), "slot_offset", "is -10,000 to 10,000 mm"),
    (('B = "P6"', 'B = "P3"'), "B", "defined twice"),
]


@pytest.mark.parametrize("change,key,reason", PPR_ERRORS, ids=[e[1] for e in PPR_ERRORS])
def test_ppr_declaration_errors_name_the_field(studies, change, key, reason):
    text = (studies / f"{SCENE}.toml").read_text()
    assert change[0] in text
    with pytest.raises(StudyError) as e:
        parse_study(text.replace(change[0], change[1], 1), "bad.toml")
    msg = str(e.value)
    assert f"mechanism.groups[2].{key}" in msg and reason in msg, msg


def test_a_slide_across_the_ppr_slot_is_refused(studies):
    text = (studies / f"{SCENE}.toml").read_text()
    old = 'guide = "carriage"\nangle = 60.0'
    assert old in text
    with pytest.raises(StudyError) as e:
        parse_study(text.replace(old, 'guide = "carriage"\nangle = 75.0'), "bad.toml")
    msg = str(e.value)
    assert "the PPR group 'carriage' guides P7 along its slot, 60 deg from its guide" in msg, msg


# the emitter of each group class, where it is not the class's name + "Emitter"
EMITTER_OF = {"PPR": "RPPEmitter", "RotaryInput": "InputEmitter", "SliderInput": "InputEmitter"}


def test_every_types_plan_code_picks_an_emitter_of_its_own_folder(studies):
    """A group type's plan row picks, by its code, its own emitter, in the type's
    own folder (pipeline.group_types; the mechanism's own elements: compiler.emit),
    for every group of every shipped study."""
    seen = set()
    for path in sorted(studies.glob("*.toml")):
        m = load_study(path).mechanism
        plan = m.compile()
        for k, g in enumerate(m.groups, start=1):
            emitter = emitter_classes()[int(plan.codes[k])]
            home = type(g).__module__.rsplit(".", 1)[0]     # the type's folder
            assert (emitter.__module__.rsplit(".", 1)[0] == home
                    or (emitter.__module__, home) == ("pipeline.compiler.emit",
                                                      "pipeline.model.groups")), (path.name, g)
            assert emitter.__name__ == EMITTER_OF.get(type(g).__name__,
                                                      type(g).__name__ + "Emitter"), (path.name, g)
            seen.add(type(g).__name__)
    assert {"RRR", "RRP", "RPR", "PRP", "RPP", "PPR", "ClassIII", "ClassIIISlider", "Attach",
            "RotaryInput", "SliderInput"} <= seen


def test_a_sweep_over_a_ppr_dimension_runs(studies, tmp_path):
    from pipeline.runs.sweep import run_sweep
    study = load_study(studies / f"{SWEEP}.toml")
    assert [v.param for v in study.sweep.variables] == ["carriage.slot_angle",
                                                        "carriage.guide_offset"]
    # the slider's slide follows the swept slot (its forces turn with it)
    assert study.mechanism.slides[0].follows == ("carriage.guide_angle", "carriage.slot_angle")
    out = tmp_path / "ppr.h5"
    outcome = run_sweep(study, out, candidates=200, progress=False)
    assert outcome.summary["status OK"].startswith("200 ")
    with h5py.File(out, "r") as f:
        slot = f["candidates/params"][()][:, 0]        # the variables, deg and mm
        assert 45.0 <= slot.min() < 50.0 and 70.0 < slot.max() <= 75.0
        acc = f["metrics/peak_acceleration"][()]
        tr = f["metrics/min_transmission_angle"][()]
        assert np.all(np.isfinite(acc)) and np.ptp(acc) > 0
        # the PPR's transmission angle is its slot against its guide
        assert np.all(tr <= np.minimum(slot, 180.0 - slot) + 1e-9)


def test_the_force_lanes_of_the_cross_slide_agree_with_the_scalar_force_stage(studies):
    """The cross slide's sweep (an RRR and a PPR, solved as an RPP; the smallest
    transmission angle asked for: the RRR's angle at its joint and the slot's
    against the guide): to rounding."""
    study = load_study(studies / "ppr_cross_slide_sweep.toml")
    pb = build_problem(study, study.sweep)
    assert pb.settings()[ks.SET_WANT_TRANSMISSION] and pb.kernels.N_TRANS == 2
    pars = parameter_rows(pb.plan, pb.spec, draw_candidates(pb.spec, 0))
    assert_force_lanes_round(pb, np.ascontiguousarray(pars), 500)


def test_ppr_lanes_agree_with_the_careful_path(studies):
    """The cross slide's PPR (solved as an RPP: the guide's line and the slot's,
    turned from it by the hoisted slot angle) in the lanes, over slot angles from
    1 to 179 deg: the force stage's peaks hold the lanes' B and its analogs to
    the careful path's (the study's own module)."""
    pb, pars = widened_draws(studies, "ppr_cross_slide_sweep",
                             [("min = 45.0, max = 75.0", "min = 1.0, max = 179.0"),
                              ("min = -5.0, max = 5.0", "min = 5.0, max = 30.0")], 2000)
    assert_lanes_agree(pb, pars, class3=False)
