"""The comparison of a solved revolution with naive.py's multiprecision
references (``naive.mp_analogs``), shared by the tests of the group types and
the inputs."""

import numpy as np

from support import naive
from support.tolerances import MP_REFERENCE_REL


def against_mp_reference(plan, curves, chain, rename=None, planned_only=False, label=""):
    """Every point of the reference ``chain`` at every position of ``curves``:
    positions, first and second analogs within MP_REFERENCE_REL of each one's
    largest value over the cycle (exactly 0 where that largest value is 0).
    ``rename``: the plan's name of a reference point where it differs;
    ``planned_only``: skip the reference's points the plan does not have.
    Returns (the largest relative error seen, the reference points checked)."""
    rename = rename or {}
    refs = [naive.mp_analogs(chain, phi) for phi in curves.phi]
    names = [p for p in refs[0]["pos"]
             if not planned_only or rename.get(p, p) in plan.point_names]
    worst = 0.0
    for name in names:
        i = plan.point(rename.get(name, name))
        for key, mine in (("pos", curves.pos), ("d1", curves.d1), ("d2", curves.d2)):
            ref = np.array([r[key][name] for r in refs])
            scale = np.abs(ref).max()
            err = np.abs(mine[:, i] - ref).max()
            if scale == 0.0:
                assert err == 0.0, (label, name, key, err)
                continue
            worst = max(worst, err / scale)
            assert err <= MP_REFERENCE_REL * scale, \
                f"{label} {name} {key}: {err / scale:.2e} relative"
    return worst, names
