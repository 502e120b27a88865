"""Dwell and motion metrics over one revolution (DOMAIN.md section 9)."""

import math

from numba import njit

from .config import JIT


@njit(**JIT)
def _sample(j, n):
    """Sample of index j (0 <= j < 2n) of a cyclic revolution of n samples."""
    return j if j < n else j - n


@njit(**JIT)
def dwell_error(theta, w, qmax, qmin):
    """Best dwell window of ``theta`` (n samples of one revolution, cyclic).

    A window spans w intervals (w + 1 consecutive samples taken cyclically);
    every start k = 0..n-1 is tried.  Returns (error, best start, full range):
    error = smallest (max - min within a window) / (max - min over the
    revolution).  O(n) with monotonic deques; qmax/qmin are int work arrays
    of length >= n + w.  Ties go to the first start.  NaN if theta has NaN or
    does not move.
    """
    n = theta.shape[0]
    lo = math.inf
    hi = -math.inf
    for k in range(n):
        v = theta[k]
        if not math.isfinite(v):
            return math.nan, -1, math.nan
        lo = min(lo, v)
        hi = max(hi, v)
    full = hi - lo
    if not (full > 0.0) or w < 1 or w >= n:
        return math.nan, -1, full
    # deques over the doubled index j = 0..n+w-1 (sample j % n)
    hmax = 0
    tmax = 0
    hmin = 0
    tmin = 0
    best = math.inf
    best_start = -1
    # (j < n + w < 2n: the sample of j is j or j - n; no integer division in the
    # loop, whose latency dominated the careful path)
    for j in range(n + w):
        v = theta[j if j < n else j - n]
        while tmax > hmax and theta[_sample(qmax[tmax - 1], n)] <= v:
            tmax -= 1
        qmax[tmax] = j
        tmax += 1
        while tmin > hmin and theta[_sample(qmin[tmin - 1], n)] >= v:
            tmin -= 1
        qmin[tmin] = j
        tmin += 1
        start = j - w
        if start >= 0:
            while qmax[hmax] < start:
                hmax += 1
            while qmin[hmin] < start:
                hmin += 1
            r = theta[_sample(qmax[hmax], n)] - theta[_sample(qmin[hmin], n)]
            if r < best:
                best = r
                best_start = start
    return best / full, best_start, full


@njit(**JIT)
def relative_angle(x0, y0, x, y):
    """Angle from direction (x0, y0) to (x, y) in (-pi, pi]: a rocker's swing
    measured from its first position, free of the atan2 wrap."""
    return math.atan2(x0 * y - y0 * x, x0 * x + y0 * y)




@njit(**JIT)
def dwell_lanes(theta, n, w, lanes, W5, err, start, full):
    """``dwell_error`` of ``lanes`` revolutions at once: theta[k, l] is sample k
    of lane l (k = 0..n-1).  Branch-free, so the lane loops vectorize: van Herk
    / Gil-Werman, prefix and suffix extrema in blocks of the window's w + 1
    samples over the revolution extended by w; the same windows, the same exact
    extrema and the same tie rule (the first start) as ``dwell_error``, hence
    the same results.  W5: work array of at least (5, n + w, lanes).  Writes
    err (NaN where ``dwell_error`` gives NaN), start (-1 there) and full."""
    b = w + 1
    m = n + w
    pmax = W5[0]
    smax = W5[1]
    pmin = W5[2]
    smin = W5[3]
    hi = W5[4, 0]
    lo = W5[4, 1]
    bad = W5[4, 2]
    # counters instead of j % n and j % b: an integer division per row costs
    # more than the row's work
    q = 0                         # j % b
    for j in range(m):
        k = j if j < n else j - n
        if q == 0:
            for l in range(lanes):
                pmax[j, l] = theta[k, l]
                pmin[j, l] = theta[k, l]
        else:
            for l in range(lanes):
                pmax[j, l] = max(pmax[j - 1, l], theta[k, l])
                pmin[j, l] = min(pmin[j - 1, l], theta[k, l])
        q = 0 if q == b - 1 else q + 1
    q = (m - 1) % b
    for j in range(m - 1, -1, -1):
        k = j if j < n else j - n
        if q == b - 1 or j == m - 1:
            for l in range(lanes):
                smax[j, l] = theta[k, l]
                smin[j, l] = theta[k, l]
        else:
            for l in range(lanes):
                smax[j, l] = max(smax[j + 1, l], theta[k, l])
                smin[j, l] = min(smin[j + 1, l], theta[k, l])
        q = b - 1 if q == 0 else q - 1
    for l in range(lanes):
        hi[l] = theta[0, l]
        lo[l] = theta[0, l]
        bad[l] = 0.0
        err[l] = math.inf
        start[l] = -1
    for k in range(n):
        for l in range(lanes):
            v = theta[k, l]
            hi[l] = max(hi[l], v)
            lo[l] = min(lo[l], v)
            bad[l] = max(bad[l], 0.0 if v - v == 0.0 else 1.0)    # NaN or inf
    for s in range(n):      # window s..s+w: suffix of s's block, prefix of (s+w)'s
        for l in range(lanes):
            r = max(smax[s, l], pmax[s + w, l]) - min(smin[s, l], pmin[s + w, l])
            if r < err[l]:
                err[l] = r
                start[l] = s
    for l in range(lanes):
        f = hi[l] - lo[l]
        full[l] = f
        if bad[l] != 0.0:
            err[l] = math.nan
            start[l] = -1
            full[l] = math.nan
        elif not (f > 0.0) or w < 1 or w >= n:
            err[l] = math.nan
            start[l] = -1
        else:
            err[l] = err[l] / f
