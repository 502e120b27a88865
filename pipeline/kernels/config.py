"""The one place that defines how kernels are compiled, the status codes and
the layout of the tolerance vector passed to every solver.

Tolerances are passed as arguments (never read from globals) because numba's
on-disk cache freezes global values into the compiled code.
"""

import os

import numpy as np

# Floating-point flags, in one place.  Never 'nnan' or 'ninf': NaN is the
# failure signal.
# * JIT (every kernel but the lane walk): strict IEEE by default, so the careful
#   path gives the same bits as any other faithful evaluation of its formulas
#   (near-singular candidates magnify a last-bit difference into a different
#   status).
# * JIT_LANES (the sweep's lock-step walk): FMA contraction ("contract": a*b + c
#   in one rounding) to reach the FMA units; a lane near a singular position is
#   redone on the careful path anyway.
# PIPELINE_FASTMATH=strict turns contraction off in the lanes too; =fast selects
# the wider subset below everywhere (used by the speed/accuracy benchmark, which
# also points NUMBA_CACHE_DIR elsewhere because the cache key does not include
# these flags).
_FAST_FLAGS = {"nsz", "arcp", "contract", "afn", "reassoc"}
_MODE = os.environ.get("PIPELINE_FASTMATH", "default")
FASTMATH = _FAST_FLAGS if _MODE == "fast" else False
LANE_FASTMATH = {"strict": False, "fast": _FAST_FLAGS}.get(_MODE, {"contract"})

# error_model="numpy": a division by zero gives inf/nan instead of raising,
# so a kernel never raises on a worker thread.
# _nrt=False: a kernel allocates nothing and works on the arrays it is given,
# so numba's reference counting is left out (every array passed to or unpacked
# in a kernel was an atomic increment and decrement: 40 % of the careful walk's
# time, seen with perf at NRT_incref/NRT_decref).  numba refuses to compile an
# allocation in such a kernel, so the rule is checked, not trusted.
# JIT_ALLOC: the few entry points that allocate work arrays, once per call.
JIT = dict(cache=True, fastmath=FASTMATH, error_model="numpy", nogil=True, _nrt=False)
JIT_LANES = dict(JIT, fastmath=LANE_FASTMATH)
JIT_ALLOC = dict(JIT, _nrt=True)
# JIT_INNER: a generated kernel that only other kernels call (never Python):
# numba then builds no CPython or C wrapper for it, which it otherwise compiles
# and links for every function (measured: a fifth of a new scene's compile time).
# The machine code of the kernel itself is the same.
JIT_INNER = dict(JIT, no_cpython_wrapper=True, no_cfunc_wrapper=True)
JIT_ALLOC_INNER = dict(JIT_ALLOC, no_cpython_wrapper=True, no_cfunc_wrapper=True)   # allocating
# JIT_FIRST_CLASS: a generated kernel that other kernels also take as an argument
# (``advance`` and ``start``: pipeline.kernels.walk's revolution calls them through
# their address, numba's first-class functions, which is the C wrapper's).
JIT_FIRST_CLASS = dict(JIT, no_cpython_wrapper=True)


def compile_for(kernel, signature) -> None:
    """``kernel`` compiled (or loaded from numba's cache) for ``signature`` and
    for no other, its compiling disabled after: once per process, whichever
    thread asks first.  The question and the compile under numba's own compile
    lock (re-entrant): numba refuses a second thread that asked before the first
    one disabled compiling."""
    from numba.core.compiler_lock import global_compiler_lock
    if not getattr(kernel, "compile", None):
        return          # numba's JIT disabled (NUMBA_DISABLE_JIT): Python calls Python
    with global_compiler_lock:
        if not kernel.signatures:
            kernel.compile(signature)
            kernel.disable_compile()


# Candidates per block of the sweep's lock-step lane path: two AVX-512 vectors (four
# AVX2 ones).  The walk's lane loop is one long chain of dependent operations per
# position (Newton steps, the series of cos/sin); with two vectors per block the
# core works on a second chain while the first waits: mechanism B's sweep 8 % less
# CPU time per chunk than with 8 (every result bit-identical: each lane's
# operations do not depend on its neighbours); 32 gave less than 16.
LANE_WIDTH = 16

# ---- status codes (int8), ordered by how they are reported -----------------
OK = 0
NO_ASSEMBLY = 1       # cosine-law argument outside [-1, 1], block off its guide, ...
NEWTON_MAXITER = 2    # class III Newton did not converge
SINGULAR = 3          # toggle / dead position: the velocity analogs do not exist
BRANCH_JUMP = 4       # assembly branch switched, or the revolution does not close
BAD_GEOMETRY = 5      # impossible ternary triangle, non-positive length
NOT_EVALUATED = 6     # sweep: stage skipped because the candidate already failed
FRICTION_LOCK = 7     # friction: a self-locking joint, or the friction does not converge

STATUS_NAMES = {
    OK: "OK",
    NO_ASSEMBLY: "NO_ASSEMBLY",
    NEWTON_MAXITER: "NEWTON_MAXITER",
    SINGULAR: "SINGULAR",
    BRANCH_JUMP: "BRANCH_JUMP",
    BAD_GEOMETRY: "BAD_GEOMETRY",
    NOT_EVALUATED: "NOT_EVALUATED",
    FRICTION_LOCK: "FRICTION_LOCK",
}

# ---- what to compute --------------------------------------------------------
POSITIONS = 0
VELOCITIES = 1      # positions + first analogs
ACCELERATIONS = 2   # positions + first and second analogs

# ---- tolerance vector ---------------------------------------------------------
T_NEWTON_TOL = 0      # closure residual accepted by Newton, relative to the lead lengths
T_NEWTON_MAXITER = 1  # iteration cap
T_NEWTON_STEP = 2     # largest Newton step in (a, b), rad (damping)
T_SINGULAR = 3        # |normalised determinant| below this is a toggle
T_JUMP = 4            # largest Newton correction of a predicted class III step, rad
T_SUBSTEP = 5         # largest crank step of the continuation, rad
T_CLOSE = 6           # revolution must close on its start to this, rad
T_ASSEMBLY_SLACK = 7  # cosine-law argument in [1, 1+slack] is clamped to a toggle
T_STEP_CHANGE = 8     # continuation steps change a class III angle by at most this, rad
T_MIN_STEP = 9        # a rejected step is halved down to this fraction of T_SUBSTEP
T_FIRST_STEP = 10     # first step of a walk (no slope known yet), fraction of T_SUBSTEP:
                      # by default the smallest step (T_MIN_STEP): a class III fold may lie
                      # just ahead of the start, and its margin's slope is not known yet
                      # (continuation.step_limit)
T_WATCH = 11          # between-sample watch: a margin^2 that may dip this low between two
                      # positions (by the quadratic through three, allowing for the cubic
                      # term) is looked at closely (pipeline.kernels.watch)
T_TOUCH = 12          # margin^2 at or below this at a located minimum: a toggle the crank
                      # passes between positions (the branch there is ambiguous): SINGULAR
T_LOCATE = 13         # a failure between positions is located to this, rad
T_GO_ON = 14          # 1: after a failure at the smallest step a walk solves its target
                      # straight from its last solution (a scene shows what can be shown);
                      # 0: it reports the failure at once (a sweep's careful path, and a
                      # failure's location, look no further than the failure)
N_TOLS = 15

# state columns of a class III group, either kind (per candidate, per group)
S_A = 0
S_B = 1
S_DET_SIGN = 2
S_MARGIN = 3
S_ITERS = 4
S_SLOPE_A = 5     # secant slopes da/dphi, db/dphi of the last accepted step
S_SLOPE_B = 6
S_HAS_SLOPE = 7
S_A_OLD = 8       # the state before the step being tried
S_B_OLD = 9
S_SIGN_OLD = 10
S_HANDED = 11     # 1.0: the solution at this position is handed over as unit vectors
S_CA = 12         # e(a) = (cos a, sin a) and e(b) handed over (the lane path's solution:
S_SA = 13         # the class III kernel confirms it by its residual, without a cos or sin)
S_CB = 14
S_SB = 15
S_MAY_STOP = 16  # 1.0: this solve's Newton may stop where it does not contract (a
                 # failure is retried at half the step: ``continuation.may_stop``)
S_MARGIN_OLD = 17  # the margin before the step being tried
S_D_RATE = 18    # d(margin^2)/d(phi1) over the last accepted step (NaN: not known yet)
N_STATE = 19


def default_tolerances(newton_tol=1e-12, newton_maxiter=50, newton_step=0.5,
                       singular=1e-9, jump=0.1, substep_deg=2.0, close=1e-7,
                       assembly_slack=1e-12, step_change=0.05, min_step=1e-5,
                       first_step=1e-5, watch=1e-6, touch=1e-12, locate=1e-10, go_on=True):
    """The tolerance vector the kernels take, with the product's defaults."""
    t = np.empty(N_TOLS)
    t[T_NEWTON_TOL] = newton_tol
    t[T_NEWTON_MAXITER] = newton_maxiter
    t[T_NEWTON_STEP] = newton_step
    t[T_SINGULAR] = singular
    t[T_JUMP] = jump
    t[T_SUBSTEP] = np.deg2rad(substep_deg)
    t[T_CLOSE] = close
    t[T_ASSEMBLY_SLACK] = assembly_slack
    t[T_STEP_CHANGE] = step_change
    t[T_MIN_STEP] = min_step
    t[T_FIRST_STEP] = first_step
    t[T_WATCH] = watch
    t[T_TOUCH] = touch
    t[T_LOCATE] = locate
    t[T_GO_ON] = 1.0 if go_on else 0.0
    return t


def stored_tolerances(stored):
    """A tolerance vector read from a results file, completed with the defaults
    of the entries added since it was written (T_GO_ON, 2026-12-06)."""
    t = default_tolerances()
    stored = np.asarray(stored, dtype=np.float64)
    t[:len(stored)] = stored[:N_TOLS]
    return t
