"""The crank's driving moment and the external loads as the dynamics kernels take
them (``Drive``): each of M1 and the load components a constant, a periodic
spline of phi1 (PHI_INTERVALS intervals per revolution) or a spline of t (a
node every T_NODE_STEPS steps); anything else is refused when the study is
read, naming the field (``model.drive``).  The equation of
motion and its integration are ``crank_motion``'s."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.drive import classify_drive

PHI_INTERVALS = 4096        # periodic spline intervals per revolution (phi tables)
T_NODE_STEPS = 2            # time tables: one node every T_NODE_STEPS integration steps
T_MAX_INTERVALS = 400_000


@dataclass(frozen=True)
class Drive:
    """Drive channels as the kernels take them (see kernels/dynamics.py)."""
    const: np.ndarray          # (n_channels,)
    tab_phi: np.ndarray        # (n_channels, n_intervals or 0, 4)
    h_phi: float
    tab_t: np.ndarray
    h_t: float

    def args(self):
        return (self.const, self.tab_phi, self.h_phi, self.tab_t, self.h_t)


def build_drive(mechanism, M1, t_end=1.0, dt=1e-3, file="<study>") -> Drive:
    """Sample M1 and the mechanism's loads into drive channels."""
    exprs = [M1] + [e for ld in mechanism.loads for e in (ld.fx, ld.fy, ld.moment)]
    kinds = [classify_drive(e, t_end, file) for e in exprs]
    n = len(exprs)
    const = np.zeros(n)
    h_phi = 2.0 * math.pi / PHI_INTERVALS
    n_t = int(min(T_MAX_INTERVALS, max(16, math.ceil(t_end / (T_NODE_STEPS * dt)))))
    h_t = t_end / n_t
    tab_phi = np.zeros((n, PHI_INTERVALS if "phi" in kinds else 0, 4))
    tab_t = np.zeros((n, n_t if "t" in kinds else 0, 4))
    for c, (e, kind) in enumerate(zip(exprs, kinds)):
        if kind == "const":
            const[c] = float(e.evaluate(0.0, 0.0))
        elif kind == "phi":
            x = np.arange(PHI_INTERVALS + 1) * h_phi
            y = e.evaluate(x, 0.0)
            y[-1] = y[0]
            tab_phi[c] = _spline()(x, y, bc_type="periodic").c.T
        else:
            x = np.arange(n_t + 1) * h_t
            tab_t[c] = _spline()(x, e.evaluate(0.0, x)).c.T
    return Drive(const, tab_phi, h_phi, tab_t, h_t)


def _spline():
    """scipy's CubicSpline, imported only for a channel that is not a constant
    (scipy.interpolate takes a tenth of a second to import)."""
    from scipy.interpolate import CubicSpline
    return CubicSpline
