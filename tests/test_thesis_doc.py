"""docs/guide/thesis.md quotes our numbers beside the thesis's: recompute every one
from the shipped studies, so the page never drifts from the product."""

import re
from pathlib import Path

import numpy as np
import pytest

import pipeline
from pipeline.solve.scene import real_motion

DOC = Path(__file__).resolve().parent.parent / "docs" / "guide" / "thesis.md"


def _ours(label):
    """The 'ours' cell of the row whose first cell is ``label``."""
    for line in DOC.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells and cells[0] == label:
            return cells[2]
    raise AssertionError(f"no row {label!r} in {DOC.name}")


@pytest.fixture(scope="module")
def mech_b(studies):
    return pipeline.solve_scene(studies / "ov7_class3.toml")


def _printed(value, text):
    """``value`` as the page prints it (as many decimals as the page shows)."""
    decimals = len(text.split(".")[1]) if "." in text else 0
    return f"{value:.{decimals}f}" == text


def test_velocities(mech_b):
    t, crank = mech_b.table, mech_b.study.mechanism.crank
    v, *_ = real_motion(t, crank.omega1, crank.eps1)
    names = list(mech_b.plan.point_names)
    for label, point, deg in (("V2X at phi1 = -270 deg (m/s)", "P2", -270.0),
                              ("V4X at phi1 = -360 deg (m/s)", "P4", -360.0)):
        k = int(np.argmin(np.abs(np.degrees(t.phi) - deg)))
        text = _ours(label)
        assert _printed(v[k, names.index(point), 0], text), (label, text)


def test_reactions_and_balancing_moment(mech_b):
    f = mech_b.dense.forces
    mag = f.magnitude
    for j, name in enumerate(f.joint_names):
        text = _ours(f"{name} peak (N)")
        assert _printed(float(np.max(mag[:, j])), text), (name, text)
    k = int(np.argmin(np.abs(mech_b.dense.phi)))
    text = _ours("M_bal at phi1 = 0 (N*m)")
    assert _printed(float(f.M_bal[k]), text)
    assert re.search(r"R1 .* 232\.7", DOC.read_text())     # the thesis's own value is quoted
