"""Self-check of the naive reference oracle (tests/support/naive.py).

Checks the oracle against the reference tables and the numbers of DOMAIN.md,
and checks that its finite-difference analogs are self-consistent.  Does not
touch the ``pipeline`` package.
"""

import math

import numpy as np
import pandas as pd
import pytest

from support import naive as nv
from support.tolerances import REFERENCE_MM

DEG = math.pi / 180.0
GRID12 = [-k * 30.0 * DEG for k in range(12)]


def _ref(reference_dir, name):
    """A reference table of the checkout's ../shared/reference (conftest's
    reference_dir fails, never skips, when it is missing)."""
    return pd.read_csv(reference_dir / name)


@pytest.fixture(scope="module")
def b_rev720():
    theta, res = nv.mech_b_rocker_angles(720)
    return theta, res


@pytest.fixture(scope="module")
def b_guesses12():
    return [ab for _p, ab in nv.revolution(nv.mech_b_positions, GRID12)]


# ---------------------------------------------------------------- positions


def test_mech_a_reference_table(reference_dir):
    ref = _ref(reference_dir, "ov7_base_positions.csv")
    for _, row in ref.iterrows():
        p = nv.mech_a_positions(math.radians(row.phi1_deg))
        for k in ("P2", "P3", "P5", "P7", "P9"):
            np.testing.assert_allclose(p[k], [row[k + "_x"], row[k + "_y"]], rtol=0, atol=REFERENCE_MM,
                                       err_msg=f"{k} at {row.phi1_deg}")


def test_mech_a_constraints_and_branch():
    d = nv.A_DATA
    for phi in np.linspace(0, -2 * math.pi, 37):
        p = nv.mech_a_positions(phi)
        dist = lambda a, b: np.hypot(*(p[a] - p[b]))  # noqa: E731
        assert abs(dist("P2", "P3") - d["L23"]) < 1e-11
        assert abs(dist("P4", "P3") - d["L43"]) < 1e-11
        assert abs(dist("P3", "P5") - d["L35"]) < 1e-11
        assert abs(dist("P6", "P5") - d["L65"]) < 1e-11
        assert abs(dist("P5", "P7") - d["L57"]) < 1e-11
        assert abs(dist("P8", "P7") - d["L87"]) < 1e-11
        # W = -1  <=>  cross(A - C, B - C) > 0
        for A, B, C in (("P2", "P3", "P4"), ("P3", "P5", "P6"), ("P5", "P7", "P8")):
            assert nv.cross(p[A] - p[C], p[B] - p[C]) > 0


def test_mech_b_reference_table(reference_dir):
    ref = _ref(reference_dir, "ov7_class3_positions.csv")
    res = nv.revolution(nv.mech_b_positions, np.radians(ref.phi1_deg.values))
    for (p, _ab), (_, row) in zip(res, ref.iterrows()):
        for k in ("P2", "P3", "P4", "P5", "P8"):
            np.testing.assert_allclose(p[k], [row[k + "_x"], row[k + "_y"]], rtol=0, atol=REFERENCE_MM,
                                       err_msg=f"{k} at {row.phi1_deg}")
    a0, b0 = res[0][1]
    assert round(math.degrees(a0), 3) == 44.006
    assert round(math.degrees(b0), 3) == 128.709
    # the revolution closes on its start
    np.testing.assert_allclose(res[-1][1], res[0][1], atol=1e-10)


def test_mech_b_constraints():
    d = nv.B_DATA
    for p, _ab in nv.revolution(nv.mech_b_positions, np.linspace(0, -2 * math.pi, 25)):
        dist = lambda a, b: np.hypot(*(p[a] - p[b]))  # noqa: E731
        for (a, b, L) in (("P1", "P2", d["L12"]), ("P2", "P3", d["L23"]), ("P3", "P4", d["L34"]),
                          ("P4", "P5", d["L45"]), ("P3", "P5", d["L35"]), ("P4", "P6", d["L46"]),
                          ("P5", "P7", d["L57"]), ("P7", "P8", d["L78"])):
            assert abs(dist(a, b) - L) < 1e-10, (a, b)
        # U435 positive: P5 is counter-clockwise of P4 as seen from P3
        assert nv.cross(p["P4"] - p["P3"], p["P5"] - p["P3"]) > 0


def test_mech_b_default_guess_continues_from_zero():
    p_direct, ab_direct = nv.mech_b_positions(-200 * DEG)
    res = nv.revolution(nv.mech_b_positions, [0.0, -200 * DEG])
    np.testing.assert_allclose(ab_direct, res[-1][1], atol=1e-11)


def test_mech_d_assembly():
    d = nv.D_DATA
    p90 = nv.mech_d_positions(90 * DEG)
    assert p90["P3"][1] > 0  # C above AD with the crank at 90 deg
    for phi in np.linspace(0, 2 * math.pi, 73):
        p = nv.mech_d_positions(phi)
        assert abs(np.hypot(*(p["P2"] - p["P1"])) - d["LAB"]) < 1e-12
        assert abs(np.hypot(*(p["P3"] - p["P2"])) - d["LBC"]) < 1e-11
        assert abs(np.hypot(*(p["P3"] - p["P4"])) - d["LDC"]) < 1e-11
        assert abs(np.hypot(*(p["P5"] - p["P4"])) - d["LDE"]) < 1e-11
        assert np.sign(nv.cross(p["P2"] - p["P4"], p["P3"] - p["P4"])) == nv.D_BRANCH


def test_mech_c_geometry():
    d = nv.C_DATA
    for phi in np.linspace(0, 2 * math.pi, 37):
        p, phi5 = nv.mech_c_positions(phi)
        assert abs(np.hypot(*(p["P3"] - p["P2"])) - d["l2"]) < 1e-12
        assert abs(p["P3"][0]) < 1e-15 and p["P3"][1] < 0
        np.testing.assert_allclose(p["P2"], d["l1"] * np.array([math.cos(phi), math.sin(phi)]))
        assert abs(np.hypot(*(p["P4"] - p["P2"])) - 10.0) < 1e-12
        assert abs(np.dot(p["P4"] - p["P2"], p["P3"] - p["P2"])) < 1e-10
        assert abs(np.hypot(*(p["P7"] - p["P5"])) - 55.0) < 1e-12
        assert abs(nv._wrap(phi5 - nv.angle_of(p["P5"], p["P7"]))) < 1e-13


# ------------------------------------------------------------------- analogs


def _fd_disagreement(calls_h1, calls_h2):
    """max |a - b| / scale per quantity, scale = max |.| over the whole sample."""
    worst = {}
    for key in ("d1", "d2", "ang_d1", "ang_d2"):
        scale = 0.0
        diff = 0.0
        for r1, r2 in zip(calls_h1, calls_h2):
            for name in r1[key]:
                scale = max(scale, float(np.max(np.abs(r1[key][name]))))
                diff = max(diff, float(np.max(np.abs(np.asarray(r1[key][name])
                                                     - np.asarray(r2[key][name])))))
        worst[key] = diff / scale
    return worst


@pytest.mark.parametrize("mech", ["A", "B", "C", "D"])
def test_fd_analogs_two_steps_agree(mech, b_guesses12):
    h1, h2 = 0.02, 0.03
    if mech == "A":
        f = lambda phi, h, i: nv.mech_a_analogs(phi, h)  # noqa: E731
    elif mech == "B":
        f = lambda phi, h, i: nv.mech_b_analogs(phi, guess=b_guesses12[i], h=h,  # noqa: E731
                                                with_S=True)
    elif mech == "C":
        f = lambda phi, h, i: nv.mech_c_analogs(phi, h)  # noqa: E731
    else:
        f = lambda phi, h, i: nv.mech_d_analogs(phi, h)  # noqa: E731
    r1 = [f(phi, h1, i) for i, phi in enumerate(GRID12)]
    r2 = [f(phi, h2, i) for i, phi in enumerate(GRID12)]
    worst = _fd_disagreement(r1, r2)
    assert max(worst.values()) < 1e-9, worst


def test_fd_crank_analogs_exact():
    """The crank point has a trivial exact derivative: checks the FD weights."""
    for phi in GRID12:
        an = nv.mech_a_analogs(phi)
        th = phi + nv.A_DATA["phiM0"]
        L = nv.A_DATA["L12"]
        np.testing.assert_allclose(an["d1"]["P2"], L * np.array([-math.sin(th), math.cos(th)]),
                                   atol=1e-11 * L)
        np.testing.assert_allclose(an["d2"]["P2"], -L * np.array([math.cos(th), math.sin(th)]),
                                   atol=1e-9 * L)
        assert abs(an["ang_d1"]["1_2"] - 1.0) < 1e-11
        assert abs(an["ang_d2"]["1_2"]) < 1e-9


def test_link_seen_from_both_ends():
    an = nv.mech_b_analogs(0.0, links=["3_4", "4_3"])
    assert abs(abs(nv._wrap(an["ang"]["3_4"] - an["ang"]["4_3"])) - math.pi) < 1e-13
    assert abs(an["ang_d1"]["3_4"] - an["ang_d1"]["4_3"]) < 1e-12
    assert abs(an["ang_d2"]["3_4"] - an["ang_d2"]["4_3"]) < 1e-10


def test_mech_c_lagrange_terms_consistent():
    # (1/2) dJ/dphi from analogs equals half the FD derivative of J(phi)
    for phi in (0.3, 1.9, 4.0, 269.18 * DEG):
        J, half_dJ, _Q = nv.naive_c_lagrange_terms(phi)
        h = 1e-3
        Jp = nv.naive_c_lagrange_terms(phi + h)[0]
        Jm = nv.naive_c_lagrange_terms(phi - h)[0]
        assert J > 0
        assert abs(0.5 * (Jp - Jm) / (2 * h) - half_dJ) < 1e-6 * max(abs(half_dJ), J)


# -------------------------------------------------------------- kinetostatics


def _check_virtual_power(res):
    total, scale = nv.virtual_power_residual(res)
    assert abs(total) < 1e-9 * scale, (total, scale)


def test_virtual_power_b(b_guesses12):
    for i, phi in enumerate(GRID12[::3]):
        _check_virtual_power(nv.naive_forces_b(phi, guess=b_guesses12[3 * i]))
        _check_virtual_power(nv.naive_forces_b(phi, omega1=-94.4, eps1=250.0,
                                               guess=b_guesses12[3 * i]))


def test_virtual_power_d():
    for phi in np.radians([0, 45, 90, 170, 260, 330]):
        _check_virtual_power(nv.naive_forces_d(phi))
        _check_virtual_power(nv.naive_forces_d(phi, omega1=60.0, eps1=-400.0))


def test_static_d_equilibrium_against_direct_moment_balance():
    """omega1 = 0: gravity + load only; M_bal from the principle of virtual work."""
    phi = 0.7
    res = nv.naive_forces_d(phi, omega1=0.0, eps1=0.0)
    an = nv.fd_analogs(nv._d_points_with_S, phi, nv.D_LINKS)
    work = 0.0
    for name, (_b, _t, _lS, m, _J) in nv.D_MASS.items():
        work += np.array([0.0, -m * nv.G]) @ (an["d1"]["S_" + name] / 1000.0)
    work += np.array([0.0, -150 * (1 + 0.2 * math.sin(2 * phi))]) @ (an["d1"]["P5"] / 1000.0)
    assert abs(res["M_bal"] + work) < 1e-10


def test_peak_reaction_b_12():
    value, joint, phi_deg = nv.naive_mech_b_peak(12, omega1=-94.4)
    assert round(value, 1) == 1011.6
    assert joint == "R1"
    assert round(phi_deg) == -120


# -------------------------------------------------------- dwell and margin


def test_dwell_brute_force_small():
    theta = [0, 1, 2, 2, 2, 1]  # n = 6
    assert nv.naive_dwell_error(theta, 120.0) == (0.0, 2)   # w = 2: samples 2,3,4
    err, k = nv.naive_dwell_error(theta, 180.0)             # w = 3
    assert (err, k) == (0.5, 1)


def test_dwell_mech_b(b_rev720):
    theta, _res = b_rev720
    assert round(nv.naive_dwell_error(theta, 120.0)[0], 4) == 0.0193
    assert round(nv.naive_dwell_error(theta, 150.0)[0], 4) == 0.0712
    assert 11 <= nv.B_DATA["L78"] * (max(theta) - min(theta)) <= 15


def test_dwell_mech_a():
    theta = nv.mech_a_rocker_angles(720)
    assert round(nv.naive_dwell_error(theta, 120.0)[0], 4) == 0.0212
    assert round(nv.naive_dwell_error(theta, 150.0)[0], 4) == 0.0212


def test_margin_mech_b():
    margin, _phi = nv.naive_mech_b_margin(360)
    assert round(margin, 2) == 0.93


def test_peak_reaction_b_360():
    value, joint, phi_deg = nv.naive_mech_b_peak(360, omega1=-94.4)
    assert round(value, 1) == 1011.6
    assert joint == "R1"
    assert round(phi_deg) == -120
