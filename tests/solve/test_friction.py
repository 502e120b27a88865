"""Friction in the joints ([mechanism.friction], issue 52): the study section
and its refusals, the friction-inclusive kinetostatics against the virtual-power
balance (mechanism B, the take-up's two slides), a closed-form offset
slider-crank, an independent dense Newton solve of a four-bar (naive.py), a
self-locking slide located between positions, and one bearing's p, v, p*v by
hand from the stored reaction and link analogs."""

import math
import re

import h5py
import numpy as np
import pytest

from pipeline.base.errors import StudyError
from pipeline.cli import main
from pipeline.kernels import config as kc
from pipeline.solve.scene import run_scene
from pipeline.study.reader import load_study, parse_study
from support.friction_sections import TAKEUP_FRICTION_EDGES

ENERGY_REL = 1e-9        # issue 52: the energy balance, relative
CLOSED_FORM_REL = 1e-10  # issue 52: the slider-crank's driving force, the four-bar's Newton
LOCK_RAD = 1e-8          # a locking angle against its closed form (bisection to 1e-10 rad)


def _with(text, section, drop=()):
    """A study's text with ``section`` added before [output] and the tables
    ``drop`` (with their sub-tables) taken out."""
    for name in drop:
        text = re.sub(rf"(?ms)^\[\[?{re.escape(name)}[\].].*?(?=^\[(?!{re.escape(name)}))", "",
                      text)
    return text.replace("[output]", section + "\n[output]", 1)


FRICTION_B = """[mechanism.friction]
revolute = 0.08
pin_diameter = 10.0
pins = { P1 = 14.0, R2 = 12.0 }
pin_length = 12.0
pin_lengths = { P5 = 8.0 }
p_max = 25.0
pv_max = 3.0
"""


@pytest.fixture(scope="module")
def mech_b(studies):
    """Mechanism B with and without friction (the shipped scene ov7_friction and
    ov7_class3)."""
    with_f = load_study(studies / "ov7_friction.toml")
    without = load_study(studies / "ov7_class3.toml")
    return run_scene(with_f), run_scene(without)


def _body_rates(plan, curves):
    """Each body's angle analog phi' (n, nb) from the kinematics: the analog of
    the angle of its turning vector a -> b, cross(r, r') / |r|^2 (0: no turn)."""
    w = np.zeros((curves.pos.shape[0], len(plan.body_names)))
    for i, (a, b) in enumerate(plan.body_turn):
        if a >= 0:
            r = curves.pos[:, b] - curves.pos[:, a]
            v = curves.d1[:, b] - curves.d1[:, a]
            w[:, i] = (r[:, 0] * v[:, 1] - r[:, 1] * v[:, 0]) / (r[:, 0] ** 2 + r[:, 1] ** 2)
    return w


def _relative_rates(plan, curves):
    w = _body_rates(plan, curves)
    out = np.zeros((w.shape[0], len(plan.joint_names)))
    for j, (p, q) in enumerate(plan.joint_bodies):
        out[:, j] = w[:, q] - (w[:, p] if p >= 0 else 0.0)
    return out


def _energy_gap(with_f, without, plan, curves, sliding=None):
    """|M_bal with - M_bal without + sum(friction load x relative analog)| over the
    largest of |M_bal with - without| and the terms, per position."""
    fr = with_f.friction
    terms = fr.moment * _relative_rates(plan, curves)
    if sliding is not None:
        terms = np.concatenate([terms, fr.force * sliding * 1e-3], axis=1)
    delta = with_f.M_bal - without.M_bal
    scale = np.maximum(np.abs(delta), np.abs(terms).max(axis=1))
    return np.abs(delta + terms.sum(axis=1)) / scale


# ------------------------------------------------------------------ the study section
def test_the_section_is_read_per_joint(studies):
    text = _with((studies / "ov7_class3.toml").read_text(), FRICTION_B)
    fr = parse_study(text, "b.toml").mechanism.friction
    assert fr.revolute == 0.08 and fr.slide == 0.0 and fr.p_max == 25.0 and fr.pv_max == 3.0
    assert fr.pins == (("R1", 14.0, 12.0), ("R2", 12.0, 12.0), ("R3", 10.0, 12.0),
                       ("R4", 10.0, 12.0), ("R5", 10.0, 8.0), ("R6", 10.0, 12.0),
                       ("R7", 10.0, 12.0))
    assert parse_study((studies / "ov7_class3.toml").read_text(), "b.toml") \
        .mechanism.friction is None


@pytest.mark.parametrize("section, field, reason", [
    ("revolute = -0.1\npin_diameter = 10.0\npin_length = 10.0", "mechanism.friction.revolute",
     "out of range"),
    ("revolute = 0.1\npin_length = 10.0", "mechanism.friction.pin_diameter",
     "required field is missing"),
    ("revolute = 0.1\npin_diameter = 10.0\npin_length = 10.0\npins = { P9 = 8.0 }",
     "mechanism.friction.pins.P9", "no revolute joint at 'P9'"),
    ("revolute = 0.1\npin_diameter = 10.0\npin_length = 10.0\npins = { P2 = 8.0, R2 = 9.0 }",
     "mechanism.friction.pins.", "given twice"),
    ("revolute = 0.1\npin_diameter = 10.0\npin_length = 10.0\npv_max = 0.0",
     "mechanism.friction.pv_max", "out of range"),
    ("revolute = 0.1\npin_diameter = 10.0\npin_length = 10.0\nslip = 1",
     "mechanism.friction.slip", "unknown key"),
    ("revolute = 0.1\npin_diameter = '10'\npin_length = 10.0",
     "mechanism.friction.pin_diameter", "expected a number"),
])
def test_bad_input_is_one_line_naming_file_field_reason(studies, section, field, reason):
    text = _with((studies / "ov7_class3.toml").read_text(), "[mechanism.friction]\n" + section)
    with pytest.raises(StudyError) as e:
        parse_study(text, "bad.toml")
    msg = str(e.value)
    assert "\n" not in msg and "bad.toml" in msg and field in msg and reason in msg, msg


def test_friction_needs_the_forces(studies):
    text = _with((studies / "ov7_class3.toml").read_text(), FRICTION_B)
    text = text.replace('analysis = "forces"', 'analysis = "accelerations"')
    with pytest.raises(StudyError, match="output.analysis"):
        parse_study(text, "b.toml")


# ------------------------------------------------------------------ energy balance
def test_energy_balance_of_mechanism_b_at_every_position(mech_b):
    """M_bal with - without = -sum over joints of the friction moment times the
    relative angular velocity analog (from the kinematics), and every friction
    moment is f (d/2) |R| against the relative rotation."""
    res, free = mech_b
    for c, c0 in ((res.dense, free.dense), (res.table, free.table)):
        fr = c.forces.friction
        assert (fr.status == kc.OK).all() and res.status == kc.OK
        assert _energy_gap(c.forces, c0.forces, res.plan, c).max() <= ENERGY_REL
        np.testing.assert_array_equal(fr.M_bal_frictionless, c0.forces.M_bal)
        d = np.array([14.0, 12.0, 10.0, 10.0, 10.0, 10.0, 10.0])
        rel = _relative_rates(res.plan, c)
        mag = np.hypot(c.forces.R[..., 0], c.forces.R[..., 1])
        np.testing.assert_allclose(np.abs(fr.moment), 0.08 * d / 2000.0 * mag, rtol=1e-15)
        assert (np.sign(fr.moment) == -np.sign(rel * res.study.mechanism.crank.omega1)).all()
        assert (fr.loss >= 0.0).all() and c.forces.residual.max() <= ENERGY_REL
    # friction makes the drive work: mean power = mean loss (the inertia's averages to 0)
    fr = res.dense.forces.friction
    mean_power = np.mean(res.dense.forces.M_bal * res.study.mechanism.crank.omega1)
    assert mean_power == pytest.approx(fr.mean_loss(), rel=1e-9)


def _sliding_analogs(plan, curves):
    """The take-up's slides' sliding analogs from the kinematics: the needle bar's
    S along the vertical, the block's S along P5->P4 against the coulisse's
    point at S (turning about the fixed P5)."""
    nb_s, blk_s = (plan.body_com[plan.body_names.index(b)] for b in ("needle bar", "block"))
    p4, p5 = plan.point("P4"), plan.point("P5")
    out = np.zeros((curves.pos.shape[0], 2))
    out[:, 0] = curves.d1[:, nb_s, 1]
    r = curves.pos[:, p4] - curves.pos[:, p5]
    u = r / np.hypot(r[:, 0], r[:, 1])[:, None]
    w = (r[:, 0] * curves.d1[:, p4, 1] - r[:, 1] * curves.d1[:, p4, 0]) / (r ** 2).sum(axis=1)
    s = curves.pos[:, blk_s] - curves.pos[:, p5]
    guide = np.stack([-w * s[:, 1], w * s[:, 0]], axis=1)   # P5 fixed: omega x (S - P5)
    out[:, 1] = ((curves.d1[:, blk_s] - guide) * u).sum(axis=1)
    return out


def test_energy_balance_of_the_takeup_with_both_slides(studies):
    """The take-up (a slide on the frame and a block in the turning coulisse,
    with block lengths: edge loads) balances too, the sliding analogs taken from
    the kinematics; its slides' friction is f max(|N|, 2000 |C| / l)."""
    base = (studies / "takeup_dynamics.toml").read_text()
    base = base[:base.index("[dynamics]")]
    res = run_scene(parse_study(_with(base, TAKEUP_FRICTION_EDGES), "takeup.toml"))
    free = run_scene(parse_study(base, "takeup.toml"))
    c = res.dense
    sl = _sliding_analogs(res.plan, c)
    fr = c.forces.friction
    nj = len(res.plan.joint_names)
    np.testing.assert_allclose(fr.speed_analog[:, nj:], sl, rtol=0, atol=1e-12 * np.abs(sl).max())
    assert _energy_gap(c.forces, free.dense.forces, res.plan, c, sl).max() <= ENERGY_REL
    N, C = c.forces.slide[..., 0], c.forces.slide[..., 1]
    edge = np.maximum(np.abs(N), 2000.0 * np.abs(C) / np.array([30.0, 12.0]))
    np.testing.assert_allclose(np.abs(fr.force), 0.12 * edge, rtol=1e-15)
    assert (np.abs(C) * 2000.0 / 12.0 > np.abs(N)).any()     # the block is wedged somewhere


# ------------------------------------------------------------------ offset slider-crank
SLIDER = """[study]
kind = "scene"
name = "offset_slider"

[mechanism]
gravity = 0.0

[mechanism.fixed]
P1 = [0.0, 0.0]
G = [0.0, {neg_e}]

[mechanism.crank]
pivot = "P1"
tip = "P2"
length = {r}
omega1 = 100.0
rot = 1

[[mechanism.groups]]
type = "RRP"
name = "slider"
A = "P2"
B = "P3"
guide_point = "G"
guide_angle = 0.0
L_AB = {l}
W = {W}

[[mechanism.bodies]]
name = "crank"
joints = ["P1", "P2"]
mass = 1e-12
com = {{ base = "P1", along = ["P1", "P2"], lS = 10.0 }}

[[mechanism.bodies]]
name = "rod"
joints = ["P2", "P3"]
mass = 1e-12
com = {{ base = "P2", along = ["P2", "P3"], lS = 20.0 }}

[[mechanism.bodies]]
name = "block"
joints = ["P3"]
mass = 1e-12
com = {{ base = "P3" }}

[[mechanism.slides]]
slider = "block"
angle = 0.0

[[mechanism.loads]]
body = "block"
point = "P3"
fx = "{P}"

[mechanism.friction]
revolute = 0.0
slide = {f}
pin_diameter = 10.0
pin_length = 10.0

[output]
analysis = "forces"
dense_positions = {n}
"""


def _slider(r=30.0, l=90.0, e=10.0, f=0.15, P=-500.0, n=360, W=1):
    return parse_study(SLIDER.format(r=r, l=l, neg_e=-e, f=f, P=P, n=n, W=W), "slider.toml")


def _slider_closed_form(phi, r, l, e, f, P):
    """(x_B, T, ratio): the slider on y = -e right of the crank, the rod's tension T
    (pulling the slider towards P2) from the slider's balance along the guide
    P + T u_x - s f |T u_y| = 0 (s: the sense of the slider's motion at
    omega1 > 0) on the branch of the frictionless tension T0 = -P / u_x (the
    sign of T that of T0): T = -P / D, D = u_x - s f sgn(T0) |u_y|, and the
    lock ratio D / u_x.  Where it is not positive that branch has no solution
    (T would change its sign): the slide locks, and the drive would have to
    push without bound as the ratio falls to 0."""
    ax, ay = r * math.cos(phi), r * math.sin(phi)
    xb = ax + math.sqrt(l * l - (ay + e) ** 2)
    dxb = -r * math.sin(phi) - (ay + e) * r * math.cos(phi) / math.sqrt(l * l - (ay + e) ** 2)
    ux, uy = (ax - xb) / l, (ay + e) / l
    s = math.copysign(1.0, dxb)
    d = ux - s * f * math.copysign(1.0, -P / ux) * abs(uy)
    return xb, -P / d, d / ux


def test_offset_slider_crank_against_its_closed_form():
    """M_bal = T (P2 - P1) x u: the rod's tension from the slider's balance with
    the friction f |N| against its motion (massless links, no gravity)."""
    r, l, e, f, P = 30.0, 90.0, 10.0, 0.15, -500.0
    study = _slider(r, l, e, f, P)
    res = run_scene(study)
    c = res.dense
    assert res.status == kc.OK and (c.forces.friction.status == kc.OK).all()
    p3 = res.plan.point("P3")
    for k, phi in enumerate(c.phi):
        xb, T, _ = _slider_closed_form(phi, r, l, e, f, P)
        assert c.pos[k, p3, 0] == pytest.approx(xb, rel=1e-12)
        ax, ay = r * math.cos(phi), r * math.sin(phi)
        u = np.array([ax - xb, ay + e]) / l
        m_bal = T * (ax * u[1] - ay * u[0]) * 1e-3
        assert abs(c.forces.M_bal[k] - m_bal) <= CLOSED_FORM_REL * abs(T) * r * 1e-3
        assert abs(abs(c.forces.friction.force[k, 0]) - f * abs(T * u[1])) \
            <= CLOSED_FORM_REL * abs(T)


def test_a_wedging_slide_locks_at_the_right_angle_never_ok():
    """A short rod at a steep pressure angle with f = 0.8: where the closed form's
    lock ratio falls to 0 the status is FRICTION_LOCK (its forces NaN), located
    between positions at the closed form's first angle; elsewhere OK."""
    from scipy.optimize import brentq
    r, l, e, f, P = 30.0, 40.0, 4.0, 0.8, 500.0
    res = run_scene(_slider(r, l, e, f, P, n=360))
    c = res.dense
    fr = c.forces.friction
    ratio = np.array([_slider_closed_form(phi, r, l, e, f, P)[2] for phi in c.phi])
    locked = fr.status == kc.FRICTION_LOCK
    assert locked.any() and (locked == ~(ratio > 0)).all()
    assert np.isnan(c.forces.M_bal[locked]).all() and np.isfinite(c.forces.M_bal[~locked]).all()
    k = int(np.flatnonzero(locked)[0])
    exact = brentq(lambda p: _slider_closed_form(p, r, l, e, f, P)[2], c.phi[k - 1], c.phi[k],
                   xtol=1e-14)
    assert res.status == kc.FRICTION_LOCK
    fail = res.failure
    assert fail["status"] == "FRICTION_LOCK" and fail["group"] == "slide[block]"
    assert abs(math.radians(fail["phi_deg"]) - exact) <= LOCK_RAD


# ------------------------------------------------------------------ four-bar vs dense Newton
FOURBAR_FRICTION = """[mechanism.friction]
revolute = 0.2
pin_diameter = 12.0
pins = { P1 = 20.0, P4 = 16.0 }
pin_length = 10.0
"""


def test_four_bar_with_friction_at_every_joint_against_a_dense_newton(studies):
    """Mechanism D with f = 0.2 at all four joints: the reactions and M_bal equal
    naive.py's Newton on the whole nonlinear system (fed the same kinematics)."""
    from support.naive import naive_friction_newton
    study = parse_study(_with((studies / "warp_feed_fourbar.toml").read_text(),
                              FOURBAR_FRICTION), "d.toml")
    res = run_scene(study)
    plan, c = res.plan, res.table
    mech = study.mechanism
    w = _body_rates(plan, c)
    om = mech.crank.omega1
    radius = [d / 2000.0 for d in mech.friction.diameters()]
    for k, phi in enumerate(c.phi):
        bodies = []
        for i, b in enumerate(mech.bodies):
            s = plan.body_com[i]
            a_, b_ = plan.body_turn[i]
            r = c.pos[k, b_] - c.pos[k, a_]
            r1 = c.d1[k, b_] - c.d1[k, a_]
            r2 = c.d2[k, b_] - c.d2[k, a_]
            cr1, rr = r[0] * r1[1] - r[1] * r1[0], r @ r
            w2 = ((r[0] * r2[1] - r[1] * r2[0]) * rr - 2.0 * cr1 * (r @ r1)) / rr ** 2
            ext = []
            for ld in mech.loads:
                if ld.body == b.name:
                    fe = np.array([ld.fx.evaluate(phi, 0.0), ld.fy.evaluate(phi, 0.0)], float)
                    ext.append((c.pos[k, plan.point(ld.point)] / 1000.0, fe))
            bodies.append(dict(name=b.name, m=b.mass, J=b.J_S, crank=(i == plan.crank_body),
                               S=c.pos[k, s] / 1000.0, vS=c.d1[k, s] / 1000.0 * om,
                               aS=c.d2[k, s] / 1000.0 * om ** 2, omega=w[k, i] * om,
                               eps=w2 * om ** 2, ext=ext))
        joints = [(name, None if p < 0 else mech.bodies[p].name, mech.bodies[q].name,
                   c.pos[k, plan.joint_point[j]] / 1000.0)
                  for j, (name, (p, q)) in enumerate(zip(plan.joint_names, plan.joint_bodies))]
        ref = naive_friction_newton(bodies, joints, 0.2, radius, om)
        scale = max(abs(ref["M_bal"]), 1e-300)
        assert abs(c.forces.M_bal[k] - ref["M_bal"]) <= CLOSED_FORM_REL * scale
        rmax = max(np.abs(ref[n]).max() for n in plan.joint_names)
        for j, name in enumerate(plan.joint_names):
            np.testing.assert_allclose(c.forces.R[k, j], ref[name], rtol=0,
                                       atol=CLOSED_FORM_REL * rmax)
            assert abs(c.forces.friction.moment[k, j] - ref[name + " friction"]) \
                <= CLOSED_FORM_REL * rmax * radius[j] * 0.2


# ------------------------------------------------------------------ a bearing by hand
def test_one_bearing_of_mechanism_b_by_hand_from_the_results_file(studies, tmp_path):
    """R5 (ternary / rocker at P5, d = 10 mm, l = 12 mm): p = |R| / (d l), v =
    |omega_rocker - omega_ternary| d / 2 from the stored link omegas (links 3_4 and
    7_5 are the ternary's and the rocker's), p*v, their peaks (no smaller than the
    positions' largest: refined between them) and the mean p*v."""
    out = tmp_path / "f.h5"
    assert main(["run", str(studies / "ov7_friction.toml"), "-o", str(out), "-q",
                 "--no-pictures"]) == 0
    with h5py.File(out, "r") as f:
        g = f["dense"]
        j = list(f["joint"].asstr()[()]).index("R5")
        links = list(f["link"].asstr()[()])
        R = g["reactions"][:, j]
        om = g["link_omega"][()]
        p = np.hypot(R[:, 0], R[:, 1]) / (10.0 * 12.0)
        v = np.abs(om[:, links.index("7_5")] - om[:, links.index("3_4")]) * 10.0 / 2000.0
        np.testing.assert_allclose(g["bearing_pressure"][:, j], p, rtol=1e-14)
        np.testing.assert_allclose(g["sliding_speed"][:, j], v, rtol=1e-12)
        np.testing.assert_allclose(g["pv"][:, j], p * v, rtol=1e-12)
        s = f["friction"]
        # the peaks, refined between the positions (tests/solve/test_friction_peaks.py):
        # no smaller than the positions' largest, on the same hump (within a step)
        step = abs(g["phi1"][1] - g["phi1"][0])
        for key, by_hand in (("peak_pressure", p), ("peak_sliding_speed", v),
                             ("peak_pv", p * v)):
            k = int(np.argmax(by_hand))
            assert s[key][j] >= by_hand[k]
            assert abs(s[f"{key}_phi1"][j] - g["phi1"][k]) <= step
        assert s["mean_pv"][j] == pytest.approx(np.mean(p * v), rel=1e-12)
        assert g["pv"].attrs["units"] == "MPa·m/s" and g["friction_loss"].attrs["units"] == "W"
        assert f.attrs["status"] == "OK"


# ------------------------------------------------------------------ the study writer
def test_a_sweeps_exported_design_keeps_the_friction(studies):
    """`pipeline export --candidate ... --study` writes the sweep's text back with
    the design's values: [mechanism.friction] comes along, read back the same."""
    from pipeline.study.writer import design_study_text
    study = parse_study(_with((studies / "ov7_synthesis.toml").read_text(), FRICTION_B),
                        studies / "s.toml")
    x = np.array([(v.low + v.high) / 2.0 for v in study.sweep.variables])
    text = design_study_text(study, x, label="the middle", origin="a test", name="mid")
    back = parse_study(text, studies / "mid.toml")
    assert back.kind == "scene" and back.mechanism.friction == study.mechanism.friction
