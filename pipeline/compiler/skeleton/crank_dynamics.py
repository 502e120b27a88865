"""Crank dynamics of a generated module (``begin`` .. ``terms_curve``): the
motion of the crank under its driving moment, integrated along the mechanism's
exact reduced inertia (pipeline.kernels.dynamics: compiled once for every
mechanism; these pass it the module's first-class ``advance`` and ``start``,
its sizes and its mass model and loads).

The text below the marker line is pasted into the generated module
(``pipeline.compiler.generate``, after ``careful``); the imports above it
declare, for linters and readers, the names the generated module gives it."""


from .header import math, np, njit, JIT, OK, dynamics
from ._mechanism import (N_POINTS, N_GROUPS, N_TRIADS, GRAVITY, BODY_COM, BODY_TURN, BODY_MASS_OFF,
                         LOAD_BODY, LOAD_POINT)
from .careful import advance_first_class, start_first_class

# ---- the skeleton: from here on, pasted into the generated module ----
SIZES = (N_POINTS, N_GROUPS, N_TRIADS)
MASSES = (float(GRAVITY), BODY_COM, BODY_TURN, BODY_MASS_OFF, LOAD_BODY, LOAD_POINT)


def begin(K, phi, state, last):
    """Start a dynamics continuation towards ``phi`` (last[0]: where the
    first evaluation walks from).  K: the constants as an array (constants_array)."""
    dynamics.compile_integrator()
    dynamics.begin(start_first_class, K, phi, state, last)


@njit(**JIT)
def acceleration(par, K, tols, const, tab_phi, h_phi, tab_t, h_t, damping, t, phi, omega,
                 state, last, pos, d1, d2, margins, loads_k):
    """(status, eps1) at (t, phi, omega), walking the continuation from last[0]
    to phi (pipeline.kernels.dynamics.acceleration's numbers).  The reference
    integrator (scipy's DOP853) calls it from Python at every stage: a kernel
    of the module's own, so numba's dispatch takes 3 us, not the 45 us of the
    library's with a function for argument; compiled only where it is used."""
    st = advance_first_class(K, last[0], phi, np.int64(2), tols, state, pos, d1, d2, margins,
                             np.bool_(True))
    last[0] = phi
    if st != OK:
        return st, math.nan
    return dynamics.eps_at(GRAVITY, BODY_COM, BODY_TURN, BODY_MASS_OFF, LOAD_BODY, LOAD_POINT,
                           par, const, tab_phi, h_phi, tab_t, h_t, damping, t, phi, omega, pos,
                           d1, d2, loads_k)


def rk4(par, K, tols, *args):
    """RK4 of the crank's motion (pipeline.kernels.dynamics.rk4: its arguments
    after tols; its status and the step where |omega1| passed the limit, or -1)."""
    dynamics.compile_integrator()
    return dynamics.rk4(advance_first_class, start_first_class, K, SIZES, MASSES, par, tols,
                        *args)


def terms_curve(par, K, tols, *args):
    """J, (1/2) J', Q, M1 and V along crank angles (pipeline.kernels.dynamics.
    terms_curve: its arguments after tols; the worst status)."""
    dynamics.compile_integrator()
    return dynamics.terms_curve(advance_first_class, start_first_class, K, SIZES, MASSES, par,
                                tols, *args)
