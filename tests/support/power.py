"""The virtual-power identity of a scene's kinetostatics (DOMAIN.md section 6),
summed from a scene's curves and its force result: shared by the force tests
of every group type."""

import numpy as np

from pipeline.kernels.geometry import angle_analogs


def virtual_power(study, plan, curves, fr):
    """M_bal*omega1 + sum over links (F . v_S + M omega) per position, and the
    largest single term (the scale of the identity)."""
    crank = study.mechanism.crank
    w1, e1 = crank.omega1, crank.eps1
    total = fr.M_bal * w1
    scale = np.abs(total)
    for i in range(len(plan.body_names)):
        s = plan.body_com[i]
        vS = curves.d1[:, s] * w1 / 1000.0
        a, b = plan.body_turn[i]
        if a >= 0:
            om = np.array([angle_analogs(*(curves.pos[k, b] - curves.pos[k, a]),
                                         *(curves.d1[k, b] - curves.d1[k, a]),
                                         *(curves.d2[k, b] - curves.d2[k, a]))[1]
                           for k in range(len(curves.phi))]) * w1
        else:
            om = np.zeros(len(curves.phi))
        F = fr.body_loads[:, i, :2]
        M = fr.body_loads[:, i, 2]
        pf = (F * vS).sum(axis=1)
        pm = M * om
        total = total + pf + pm
        scale = np.maximum(scale, np.maximum(np.abs(pf), np.abs(pm)))
    return total, scale
