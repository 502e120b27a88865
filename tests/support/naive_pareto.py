"""Brute-force references for tests/kernels/test_pareto.py (NOT used by the product).

Written independently of pipeline.pareto, straight from the definitions:

* ranks: peel fronts; a front is the set of remaining points that no remaining
  point dominates, found with explicit pairwise loops (O(n^2) per front);
* crowding distance: per front and objective, sort with sorted() and apply the
  NSGA-II formula literally.
"""

from __future__ import annotations

import math

import numpy as np


def _peel(F, valid, rank):
    """Explicit-loop peeling.  Plain Python; also compiled verbatim by numba."""
    n = F.shape[0]
    m = F.shape[1]
    remaining = np.empty(n, np.int64)
    r = 0
    for i in range(n):
        if valid[i]:
            remaining[r] = i
            r += 1
    front = 0
    while r > 0:
        front += 1
        keep = np.empty(r, np.int64)
        nk = 0
        for a in range(r):
            i = remaining[a]
            dominated = False
            for b in range(r):
                j = remaining[b]
                # does j dominate i?
                all_le = True
                any_lt = False
                for k in range(m):
                    if F[j, k] > F[i, k]:
                        all_le = False
                        break
                    if F[j, k] < F[i, k]:
                        any_lt = True
                if all_le and any_lt:
                    dominated = True
                    break
            if dominated:
                keep[nk] = i
                nk += 1
            else:
                rank[i] = front
        remaining = keep
        r = nk


_peel_jit = None


def brute_force_rank(F, feasible=None, *, jit: bool = False) -> np.ndarray:
    """Reference non-dominated sorting.  jit=True runs the same loops compiled by numba."""
    global _peel_jit
    F = np.asarray(F, dtype=np.float64)
    n = F.shape[0]
    valid = np.ones(n, dtype=np.bool_)
    for i in range(n):
        for k in range(F.shape[1]):
            if math.isnan(F[i, k]):
                valid[i] = False
        if feasible is not None and not feasible[i]:
            valid[i] = False
    rank = np.zeros(n, dtype=np.int32)
    if jit:
        if _peel_jit is None:
            import numba

            _peel_jit = numba.njit(_peel)
        _peel_jit(np.ascontiguousarray(F), valid, rank)
    else:
        _peel(F, valid, rank)
    return rank


def dominates_ref(a, b) -> bool:
    le = all(x <= y for x, y in zip(a, b))
    lt = any(x < y for x, y in zip(a, b))
    return le and lt


def crowding_ref(F, rank) -> np.ndarray:
    """NSGA-II crowding distance, literal loops.

    Same conventions as the product: ties sorted by index; an objective with zero
    range in a front contributes nothing; fronts of <= 2 points get inf; rank 0 -> 0.
    """
    F = np.asarray(F, dtype=np.float64)
    n, m = F.shape
    out = [0.0] * n
    fronts = {}
    for i in range(n):
        if rank[i] > 0:
            fronts.setdefault(int(rank[i]), []).append(i)
    for members in fronts.values():
        if len(members) <= 2:
            for i in members:
                out[i] = math.inf
            continue
        for k in range(m):
            srt = sorted(members, key=lambda i: (F[i, k], i))
            lo = F[srt[0], k]
            hi = F[srt[-1], k]
            span = hi - lo
            if not span > 0:
                continue
            out[srt[0]] = math.inf
            out[srt[-1]] = math.inf
            for p in range(1, len(srt) - 1):
                i = srt[p]
                out[i] = out[i] + (F[srt[p + 1], k] - F[srt[p - 1], k]) / span
    return np.array(out)


def hypervolume_2d_ref(F, reference):
    """Hypervolume of 2-objective points (minimised) against the point
    (reference, reference), from the definition: the area of the union of the
    boxes [f1, ref] x [f2, ref] of the points that dominate the reference,
    summed as vertical slabs between consecutive distinct f1 (plain loops)."""
    pts = [(float(a), float(b)) for a, b in np.asarray(F, float)
           if a < reference and b < reference]
    xs = sorted({a for a, _ in pts})
    area = 0.0
    for i, x in enumerate(xs):
        right = xs[i + 1] if i + 1 < len(xs) else reference
        low = min(b for a, b in pts if a <= x)       # the lowest f2 reached left of the slab
        area += (right - x) * (reference - low)
    return area
