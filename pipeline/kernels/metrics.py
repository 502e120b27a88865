"""Dwell and motion metrics over one revolution (DOMAIN.md section 9)."""

import math

from numba import njit

from .config import JIT


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
    for j in range(n + w):
        v = theta[j % n]
        while tmax > hmax and theta[qmax[tmax - 1] % n] <= v:
            tmax -= 1
        qmax[tmax] = j
        tmax += 1
        while tmin > hmin and theta[qmin[tmin - 1] % n] >= v:
            tmin -= 1
        qmin[tmin] = j
        tmin += 1
        start = j - w
        if start >= 0:
            while qmax[hmax] < start:
                hmax += 1
            while qmin[hmin] < start:
                hmin += 1
            r = theta[qmax[hmax] % n] - theta[qmin[hmin] % n]
            if r < best:
                best = r
                best_start = start
    return best / full, best_start, full


@njit(**JIT)
def relative_angle(x0, y0, x, y):
    """Angle from direction (x0, y0) to (x, y) in (-pi, pi]: a rocker's swing
    measured from its first position, free of the atan2 wrap."""
    return math.atan2(x0 * y - y0 * x, x0 * x + y0 * y)
