"""Two steps of pymoo's NSGA-II, compiled, with pymoo's results to the bit.

The search's NSGA-II on arrays (``pipeline.runs.nsga2``) spends most of a
generation's own time in two numpy-heavy steps of pymoo; these kernels do
them in one pass each, with the same numbers:

* :func:`crowding_distance`: pymoo's ``calc_crowding_distance`` (the 'cd'
  crowding of its rank-and-crowding survival): per objective, a stable sort,
  the gaps to the neighbours over the objective's range (0 where the range
  is 0 or a gap is NaN; inf at the ends); their sum over the objectives is
  numpy's own (``np.sum`` over a row: pairwise from 8 objectives on), divided
  by their number; inf for every point of a front of at most 2.  The same
  floating-point operations in the same order.
* :func:`unique_rows`: pymoo's ``DefaultDuplicateElimination`` (epsilon
  1e-16): a row is dropped where its Euclidean distance to an earlier row of
  its own array, or to a row of each further array, is at most epsilon.  The
  distance is the square root of the sum of the squared differences, summed
  in the variables' order (scipy's ``cdist`` may sum in another order: the
  two agree on every decision except a sum within rounding of 1e-32, which
  needs two designs apart by less than about 1e-16 in a variable, below the
  spacing of doubles for any variable of magnitude 0.5 or more).

``tests/runs/test_search_nsga2.py`` holds both against pymoo's own functions.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_JIT = dict(cache=True, nogil=True, error_model="numpy")

EPSILON = 1e-16           # pymoo's DefaultDuplicateElimination


def crowding_distance(F):
    """pymoo's FunctionalDiversity(calc_crowding_distance) of the rows of F
    (n points, m objectives)."""
    F = np.ascontiguousarray(F, dtype=np.double)
    n, m = F.shape
    if n <= 2:
        return np.full(n, np.inf)
    return np.sum(_crowding_gaps(F), axis=1) / m


@njit(**_JIT)
def _crowding_gaps(F):
    """Per point and objective, the gaps to its neighbours in that objective
    over the objective's range (calc_crowding_distance's dist_to_last +
    dist_to_next, in the points' own order)."""
    n, m = F.shape
    total = np.zeros((n, m))
    for j in range(m):
        order = np.argsort(F[:, j], kind="mergesort")
        v = F[order, j]
        norm = np.max(v) - np.min(v)
        if norm == 0.0:
            norm = np.nan
        for i in range(n):
            lo = v[i] - v[i - 1] if i > 0 else np.inf         # v[i] - (-inf)
            hi = v[i + 1] - v[i] if i + 1 < n else np.inf     # inf - v[i]
            dl = lo / norm
            dn = hi / norm
            if math.isnan(dl):
                dl = 0.0
            if math.isnan(dn):
                dn = 0.0
            total[order[i], j] = dl + dn
    return total


@njit(**_JIT)
def _near(a, b, eps):
    s = 0.0
    for k in range(a.shape[0]):
        d = a[k] - b[k]
        s += d * d
    dist = math.sqrt(s)
    return dist <= eps          # NaN: not a duplicate (pymoo sets NaN to inf)


@njit(**_JIT)
def _keep_self(X, eps):
    keep = np.ones(X.shape[0], np.bool_)
    for i in range(X.shape[0]):
        for j in range(i):
            if _near(X[i], X[j], eps):
                keep[i] = False
                break
    return keep


@njit(**_JIT)
def _keep_apart(X, other, eps):
    keep = np.ones(X.shape[0], np.bool_)
    for i in range(X.shape[0]):
        for j in range(other.shape[0]):
            if _near(X[i], other[j], eps):
                keep[i] = False
                break
    return keep


def unique_rows(X, *others, eps=EPSILON):
    """The rows of X that pymoo's DefaultDuplicateElimination keeps
    (``do(X, *others)``): none within eps of an earlier row of X, nor of any
    row of ``others``."""
    X = np.ascontiguousarray(X, float)
    if len(X) == 0:
        return X
    X = X[_keep_self(X, eps)]
    for other in others:
        if len(other) > 0:
            if len(X) == 0:
                break
            X = X[_keep_apart(X, np.ascontiguousarray(other, float), eps)]
    return X


# ----------------------------------------------------------------- SBX and PM
# pymoo's simulated binary crossover (``cross_sbx``) and polynomial mutation
# (``mut_pm``) in compiled steps between their random draws and their powers:
# the caller draws from the generator in pymoo's order and takes every power
# with numpy's own ``np.power`` (whose results may come from a vector library
# other than the C library's pow that compiled code calls), so that the
# offspring are pymoo's to the bit.
@njit(**_JIT)
def sbx_entries(X, R, prob_var, prob_bin, eta, xl, xu, eps):
    """cross_sbx up to its second draw.  X (2, n_matings, n_var) parents, R
    (n_matings, n_var) its first draw, prob_var, prob_bin, eta (n_matings, 1).
    Returns the crossed entries' mask and, entry by entry in row-major order,
    (y1, y2, delta, beta at the lower and at the upper bound, -(eta + 1),
    1 / (eta + 1), prob_bin)."""
    _, nm, nv = X.shape
    cross = np.zeros((nm, nv), np.bool_)
    count = 0
    for m in range(nm):
        for v in range(nv):
            c = R[m, v] < prob_var[m, 0]
            if abs(X[0, m, v] - X[1, m, v]) <= eps or xl[v] == xu[v]:
                c = False
            cross[m, v] = c
            count += c
    E = np.empty((8, count))
    i = 0
    for m in range(nm):
        for v in range(nv):
            if not cross[m, v]:
                continue
            p1 = X[0, m, v]
            p2 = X[1, m, v]
            sm = p1 < p2
            y1 = p1 if sm else p2
            y2 = p2 if sm else p1
            delta = y2 - y1
            e = eta[m, 0] + 1.0
            E[0, i] = y1
            E[1, i] = y2
            E[2, i] = delta
            E[3, i] = 1.0 + (2.0 * (y1 - xl[v]) / delta)
            E[4, i] = 1.0 + (2.0 * (xu[v] - y2) / delta)
            E[5, i] = -e
            E[6, i] = 1.0 / e
            E[7, i] = prob_bin[m, 0]
            i += 1
    return cross, E


@njit(**_JIT)
def sbx_bases(rand, pw):
    """calc_betaq's two bases of the powers (rand * alpha, 1 / (2 - rand *
    alpha)) and its test (rand <= 1 / alpha, and > ), alpha = 2 - pw."""
    n = rand.shape[0]
    out = np.empty((2, n))
    side = np.zeros(n, np.int8)         # 1: the first power, -1: the second, 0: neither
    for i in range(n):
        alpha = 2.0 - pw[i]
        out[0, i] = rand[i] * alpha
        out[1, i] = 1.0 / (2.0 - rand[i] * alpha)
        if rand[i] <= (1.0 / alpha):
            side[i] = 1
        elif rand[i] > (1.0 / alpha):
            side[i] = -1
    return out, side


@njit(**_JIT)
def sbx_children(X, cross, E, side1, q1, side2, q2, r_bin, xl, xu):
    """cross_sbx from its betaq on: the children, exchanged where the draw
    ``r_bin`` says so, put in place of the parents and clamped to the bounds."""
    Q = X.copy()
    _, nm, nv = X.shape
    i = 0
    for m in range(nm):
        for v in range(nv):
            if not cross[m, v]:
                continue
            y1, y2, delta = E[0, i], E[1, i], E[2, i]
            bq1 = q1[0, i] if side1[i] == 1 else (q1[1, i] if side1[i] == -1 else 0.0)
            bq2 = q2[0, i] if side2[i] == 1 else (q2[1, i] if side2[i] == -1 else 0.0)
            c1 = 0.5 * ((y1 + y2) - bq1 * delta)
            c2 = 0.5 * ((y1 + y2) + bq2 * delta)
            sm = X[0, m, v] < X[1, m, v]
            ch1 = c1 if sm else c2
            ch2 = c2 if sm else c1
            if (r_bin[i] < E[7, i]) != (X[0, m, v] > X[1, m, v]):
                ch1, ch2 = ch2, ch1
            Q[0, m, v] = ch1
            Q[1, m, v] = ch2
            i += 1
    _clamp(Q[0], xl, xu)
    _clamp(Q[1], xl, xu)
    return Q


@njit(**_JIT)
def _clamp(X, xl, xu):
    """pymoo's repair_clamp and set_to_bounds_if_outside on the rows of X: a
    value below its lower bound takes it, then one above its upper bound."""
    for r in range(X.shape[0]):
        for v in range(X.shape[1]):
            if X[r, v] < xl[v]:
                X[r, v] = xl[v]
            if X[r, v] > xu[v]:
                X[r, v] = xu[v]


@njit(**_JIT)
def pm_entries(X, R, prob, eta, xl, xu):
    """mut_pm up to its second draw: the mask of mutated entries (R < prob)
    and, entry by entry in row-major order, (x, lower, upper, 1 - delta1,
    1 - delta2, eta + 1, 1 / (eta + 1))."""
    n, nv = X.shape
    mut = np.zeros((n, nv), np.bool_)
    count = 0
    for r in range(n):
        for v in range(nv):
            c = R[r, v] < prob[r] and xl[v] != xu[v]
            mut[r, v] = c
            count += c
    E = np.empty((7, count))
    i = 0
    for r in range(n):
        for v in range(nv):
            if not mut[r, v]:
                continue
            x, lo, hi = X[r, v], xl[v], xu[v]
            E[0, i] = x
            E[1, i] = lo
            E[2, i] = hi
            E[3, i] = 1.0 - (x - lo) / (hi - lo)
            E[4, i] = 1.0 - (hi - x) / (hi - lo)
            E[5, i] = eta[r] + 1.0
            E[6, i] = 1.0 / (eta[r] + 1.0)
            i += 1
    return mut, E


@njit(**_JIT)
def pm_bases(rand, pw1, pw2):
    """mut_pm's two bases of the final powers, below and above rand = 0.5."""
    n = rand.shape[0]
    out = np.empty((2, n))
    for i in range(n):
        out[0, i] = 2.0 * rand[i] + (1.0 - 2.0 * rand[i]) * pw1[i]
        out[1, i] = 2.0 * (1.0 - rand[i]) + 2.0 * (rand[i] - 0.5) * pw2[i]
    return out


@njit(**_JIT)
def pm_mutants(X, mut, E, rand, q, xl, xu):
    """mut_pm from its deltaq on: the mutated entries, clamped to their
    bounds, in place of the originals, then the whole clamped again."""
    Xp = X.copy()
    n, nv = X.shape
    i = 0
    for r in range(n):
        for v in range(nv):
            if not mut[r, v]:
                continue
            dq = (q[0, i] - 1.0) if rand[i] <= 0.5 else (1.0 - q[1, i])
            lo, hi = E[1, i], E[2, i]
            y = E[0, i] + dq * (hi - lo)
            if y < lo:
                y = lo
            if y > hi:
                y = hi
            Xp[r, v] = y
            i += 1
    _clamp(Xp, xl, xu)
    return Xp


def sbx(X, xl, xu, eta, prob_var, prob_exch, prob_bin, rs, eps=1.0e-14):
    """pymoo's ``SimulatedBinaryCrossover._do`` (two offspring) on parents X
    (2, n_matings, n_var) with parameters of shape (n_matings, 1), drawing from
    the generator ``rs`` as it does."""
    prob_bin = np.array(prob_bin, float)
    rand = rs.random((len(prob_bin), 1))
    prob_bin[rand > prob_exch] = 0.0
    X = np.ascontiguousarray(X, float)
    R = rs.random((X.shape[1], X.shape[2]))
    cross, E = sbx_entries(X, R, np.asarray(prob_var, float), prob_bin,
                           np.asarray(eta, float), xl, xu, eps)
    r_beta = rs.random(E.shape[1])
    r_bin = rs.random(E.shape[1])
    with np.errstate(all="ignore"):
        b1, side1 = sbx_bases(r_beta, np.power(E[3], E[5]))
        b2, side2 = sbx_bases(r_beta, np.power(E[4], E[5]))
        q1 = np.power(b1, E[6])
        q2 = np.power(b2, E[6])
    return sbx_children(X, cross, E, side1, q1, side2, q2, r_bin, xl, xu)


def pm(X, xl, xu, eta, prob, rs):
    """pymoo's ``mut_pm`` (not at least once) on the rows of X, drawing from
    the generator ``rs`` as it does."""
    X = np.ascontiguousarray(X, float)
    prob = np.ones(len(X)) * prob
    R = rs.random(X.shape)
    mut, E = pm_entries(X, R, prob, np.asarray(eta, float), xl, xu)
    rand = rs.random(E.shape[1])
    with np.errstate(all="ignore"):
        base = pm_bases(rand, np.power(E[3], E[5]), np.power(E[4], E[5]))
        q = np.power(base, E[6])
    return pm_mutants(X, mut, E, rand, q, xl, xu)
