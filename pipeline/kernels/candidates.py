"""A sweep's candidates as the kernels' parameter rows, compiled: the
reference row with the design variables set, then the mass model (DOMAIN.md
section 9).  ``study.sweep_spec.parameter_rows`` calls it; the NumPy form it
replaces wrote each column over every row (1.1-1.4 s for a GPU's chunk of
10^6 candidates, on the thread that draws the next chunk while the device
evaluates one), this writes each row once (0.075 s) with the same IEEE
operations in the same order: the same bits (tested)."""

from numba import njit

from .config import JIT


@njit(**JIT)
def scaled_mass_data(m0, J0, lS0, ratio):
    """The mass model of DOMAIN.md section 9 for a body whose characteristic
    length changes by ``ratio`` = L/L0: (m, J_S, lS) = (m0 L/L0, J0 (L/L0)^3,
    lS0 L/L0).

    The one place both the sweep (``parameter_rows_into``) and the scene path
    (``study.sweep_spec.apply_design``, from Python) scale the mass data: plain
    IEEE multiplications (the cube as ``ratio * ratio * ratio``, never
    ``** 3``), the same bits either way."""
    cube = ratio * ratio * ratio
    return m0 * ratio, J0 * cube, lS0 * ratio


@njit(**JIT)
def parameter_row(base, x, var_cols, factors, mass_cols, out):
    """One candidate's row ``out``: the reference row ``base`` with design
    variable j (x[j] times factors[j]) in column var_cols[j], then each body of
    the mass model in turn (mass_cols[b]: the columns of its characteristic
    length, mass, J_S and centre-of-mass arm) scaled by its length's ratio to
    the reference.  (The GPU's draws call it too: ``runs.gpu_draws``.)"""
    for p in range(base.shape[0]):
        out[p] = base[p]
    for j in range(var_cols.shape[0]):
        out[var_cols[j]] = x[j] * factors[j]
    for b in range(mass_cols.shape[0]):
        k, m, inertia, arm = mass_cols[b, 0], mass_cols[b, 1], mass_cols[b, 2], mass_cols[b, 3]
        out[m], out[inertia], out[arm] = scaled_mass_data(base[m], base[inertia], base[arm],
                                                          out[k] / base[k])


@njit(**JIT)
def parameter_rows_into(base, x, var_cols, factors, mass_cols, out):
    """``parameter_row`` of every row of ``x`` into the rows of ``out``."""
    for i in range(x.shape[0]):
        parameter_row(base, x[i], var_cols, factors, mass_cols, out[i])
