"""Pareto ranking of the candidates of a Monte-Carlo mechanism-design sweep.

All objectives are MINIMISED.  Candidate ``a`` dominates ``b`` iff
``all(a <= b) and any(a < b)``; identical points therefore never dominate each
other and always share a front.

* :func:`nondominated_rank` -- front number of every candidate (1 = Pareto
  optimal among the feasible candidates, 2 = optimal once front 1 is removed,
  ...; 0 = infeasible or containing NaN).  Ranks are a pure function of the
  objective values: permuting the input permutes the output.
* :func:`crowding_distance` -- NSGA-II crowding distance within each front.
* :func:`knee_point` -- index of the knee of front 1.
* :func:`dominates` -- the dominance relation for two objective vectors.

Algorithms
----------
Rows are first sorted lexicographically.  If ``q`` dominates ``p`` then ``q``
precedes ``p`` lexicographically, so the sorted order is a topological order of
the dominance relation and one pass assigns final ranks
(rank(p) = 1 + max rank of the points that dominate p).

* ``m == 2`` (and ``m < 2``, padded with zero columns): O(n log n).  Rows are
  sorted by (f1, f2).  For every front only its last member (the one with the
  smallest f2) matters: an already placed point ``q`` has ``q.f1 <= p.f1``, so
  front k dominates ``p`` iff its last member ``(a1, a2)`` satisfies
  ``(a2, a1) < (p.f2, p.f1)`` lexicographically.  These keys are strictly
  increasing over the fronts, so the first non-dominating front is found by
  binary search, and ``p`` becomes that front's new last member.  Ties in f1
  and exact duplicates are handled exactly by the lexicographic key.
* ``m >= 3``: O(m n^2) worst case, O(n) memory.  Each point in sorted order
  scans the points before it, skipping those whose rank cannot raise the
  current maximum, and tests dominance with early exit.

Both inner loops are numba-compiled (``cache=True``).  Strict IEEE semantics
(no fast-math) are used: these are pure comparisons.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["nondominated_rank", "crowding_distance", "knee_point", "dominates"]

_JIT = dict(cache=True, nogil=True, error_model="numpy")


# ---------------------------------------------------------------------------
# compiled kernels
# ---------------------------------------------------------------------------
@njit(**_JIT)
def _rank_sorted_2d(f1, f2, out):
    """Ranks of points already sorted lexicographically by (f1, f2)."""
    n = f1.shape[0]
    last1 = np.empty(n, np.float64)   # f1 of the last member of each front
    last2 = np.empty(n, np.float64)   # f2 of the last member (= front's min f2)
    nfronts = 0
    for i in range(n):
        a1 = f1[i]
        a2 = f2[i]
        # first front k whose key (last2[k], last1[k]) is NOT < (a2, a1)
        lo = 0
        hi = nfronts
        while lo < hi:
            mid = (lo + hi) >> 1
            b2 = last2[mid]
            if b2 < a2 or (b2 == a2 and last1[mid] < a1):
                lo = mid + 1       # front `mid` dominates the point
            else:
                hi = mid
        last1[lo] = a1
        last2[lo] = a2
        if lo == nfronts:
            nfronts += 1
        out[i] = lo + 1


@njit(**_JIT)
def _rank_sorted_general(F, out):
    """Ranks of rows of F already sorted lexicographically (any m)."""
    n, m = F.shape
    for i in range(n):
        best = 0
        for j in range(i):
            rj = out[j]
            if rj <= best:
                continue
            dom = True
            strict = False
            for k in range(m):
                a = F[j, k]
                b = F[i, k]
                if a > b:
                    dom = False
                    break
                if a < b:
                    strict = True
            if dom and strict:
                best = rj
        out[i] = best + 1


# ---------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------
def _as_objectives(F) -> np.ndarray:
    F = np.asarray(F, dtype=np.float64)
    if F.ndim != 2:
        raise ValueError(f"F must be a 2-D (n, m) array, got shape {F.shape}")
    return F


def _valid_mask(F: np.ndarray, feasible) -> np.ndarray:
    n = F.shape[0]
    valid = ~np.isnan(F).any(axis=1) if F.shape[1] else np.ones(n, dtype=bool)
    if feasible is not None:
        feasible = np.asarray(feasible)
        if feasible.shape != (n,):
            raise ValueError(f"feasible must have shape ({n},), got {feasible.shape}")
        valid &= feasible.astype(bool)
    return valid


def _rank_valid(X: np.ndarray, general: bool = False) -> np.ndarray:
    """Ranks (int32, >= 1) of the rows of X (no NaN)."""
    n, m = X.shape
    out = np.zeros(n, dtype=np.int32)
    if n == 0:
        return out
    if m < 2:  # zero columns do not change the dominance relation
        X = np.hstack([X, np.zeros((n, 2 - m))])
        m = 2
    order = np.lexsort(X.T[::-1])  # primary key: column 0
    ranks_sorted = np.empty(n, dtype=np.int32)
    if m == 2 and not general:
        f1 = np.ascontiguousarray(X[order, 0])
        f2 = np.ascontiguousarray(X[order, 1])
        _rank_sorted_2d(f1, f2, ranks_sorted)
    else:
        _rank_sorted_general(np.ascontiguousarray(X[order]), ranks_sorted)
    out[order] = ranks_sorted
    return out


# ---------------------------------------------------------------------------
# public API
# ---------------------------------------------------------------------------
def dominates(a, b) -> bool:
    """True iff ``a`` dominates ``b`` (minimisation): a <= b everywhere and a < b somewhere.

    Any NaN makes the answer False.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.shape != b.shape:
        raise ValueError(f"shape mismatch: {a.shape} vs {b.shape}")
    return bool(np.all(a <= b) and np.any(a < b))


def nondominated_rank(F: np.ndarray, feasible: np.ndarray | None = None) -> np.ndarray:
    """Non-dominated sorting (all objectives minimised).

    F: (n, m) float objectives. Returns int32 ranks: 1 = non-dominated among the
    feasible, 2 = next front, ...; 0 for infeasible rows (feasible False) and for
    rows with any NaN.  Rank-0 rows take no part in the sorting (they dominate
    nothing).  +-inf are ordinary values.

    m == 2: O(n log n) (10^6 candidates in well under a second after
    compilation); m >= 3: O(m n^2) worst case with O(n) memory.
    """
    F = _as_objectives(F)
    valid = _valid_mask(F, feasible)
    rank = np.zeros(F.shape[0], dtype=np.int32)
    idx = np.flatnonzero(valid)
    if idx.size:
        rank[idx] = _rank_valid(F[idx])
    return rank


def _check_rank(F: np.ndarray, rank) -> np.ndarray:
    rank = np.asarray(rank)
    if rank.shape != (F.shape[0],):
        raise ValueError(f"rank must have shape ({F.shape[0]},), got {rank.shape}")
    return rank.astype(np.int64)


def crowding_distance(F: np.ndarray, rank: np.ndarray) -> np.ndarray:
    """Crowding distance of each candidate within its own front (NSGA-II).

    For every front and objective the members are sorted by that objective
    (ties: lower index first); the first and last get +inf, each interior member
    adds ``(next - prev) / (max - min)`` of the front.  Conventions:

    * an objective whose range within the front is 0 (or not finite)
      contributes nothing, not even the boundary inf;
    * fronts of 1 or 2 points: inf for all members;
    * contributions that are NaN (from infinite objective values) count as 0;
    * rank 0 (infeasible / NaN): 0.

    Returns float64 of shape (n,).
    """
    F = _as_objectives(F)
    rank = _check_rank(F, rank)
    n, m = F.shape
    cd = np.zeros(n, dtype=np.float64)
    idx = np.flatnonzero(rank > 0)
    if idx.size == 0:
        return cd
    r = rank[idx]
    X = F[idx]
    dist = np.zeros(idx.size, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for k in range(m):
            # lexsort is stable and idx is ascending: ties -> lower index first
            order = np.lexsort((X[:, k], r))
            v = X[order, k]
            rr = r[order]
            start = np.empty(v.size, dtype=bool)
            start[0] = True
            start[1:] = rr[1:] != rr[:-1]
            end = np.empty(v.size, dtype=bool)
            end[-1] = True
            end[:-1] = start[1:]
            group = np.cumsum(start) - 1
            rng = (v[end] - v[start])[group]
            ok = np.isfinite(rng) & (rng > 0)
            contrib = np.zeros(v.size, dtype=np.float64)
            interior = ok & ~start & ~end
            ii = np.flatnonzero(interior)
            contrib[ii] = (v[ii + 1] - v[ii - 1]) / rng[ii]
            contrib[ok & (start | end)] = np.inf
            contrib[np.isnan(contrib)] = 0.0
            dist[order] += contrib
    sizes = np.bincount(r)
    dist[sizes[r] <= 2] = np.inf
    cd[idx] = dist
    return cd


def knee_point(F: np.ndarray, rank: np.ndarray) -> int:
    """Index of the knee of front 1 (-1 if front 1 is empty).

    Front-1 objectives are normalised to [0, 1] per objective (an objective with
    zero range maps to 0).  The hyperplane ``a . x = 1`` is fitted through the
    extreme points (extreme point of objective j: the front-1 member with the
    smallest normalised f_j, lowest index on ties); if that system is singular
    or yields a non-positive/non-finite ``a``, the plane ``sum(x) = 1`` through
    the unit corners is used (for 2 objectives the two coincide: the line
    through the two ends of the front).  The knee is the member with the largest
    signed distance ``(1 - a . x) / |a|`` below that plane; exact ties go to the
    lowest index.  Non-finite distances (from infinite objectives) are never
    preferred over finite ones.
    """
    F = _as_objectives(F)
    rank = _check_rank(F, rank)
    idx = np.flatnonzero(rank == 1)
    if idx.size == 0:
        return -1
    if idx.size == 1 or F.shape[1] == 0:
        return int(idx[0])
    X = F[idx]
    m = X.shape[1]
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        lo = X.min(axis=0)
        rng = X.max(axis=0) - lo
        good = np.isfinite(rng) & (rng > 0)
        Z = np.zeros_like(X)
        Z[:, good] = (X[:, good] - lo[good]) / rng[good]
        ext = np.argmin(Z, axis=0)  # first occurrence = lowest index
        E = Z[ext]
        a = None
        try:
            sol = np.linalg.solve(E, np.ones(m))
            if np.all(np.isfinite(sol)) and np.all(sol > 0):
                a = sol
        except np.linalg.LinAlgError:
            pass
        if a is None:
            a = np.ones(m)
        d = (1.0 - Z @ a) / np.linalg.norm(a)
    d = np.where(np.isfinite(d), d, -np.inf)
    return int(idx[int(np.argmax(d))])
