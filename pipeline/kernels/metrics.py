"""Dwell and motion metrics over one revolution (DOMAIN.md section 9)."""

import math

from numba import njit

from .config import JIT


@njit(**JIT)
def finite_range(theta):
    """(smallest, largest) of theta; (NaN, NaN) if any sample is not finite."""
    lo = math.inf
    hi = -math.inf
    for k in range(theta.shape[0]):
        v = theta[k]
        if not math.isfinite(v):
            return math.nan, math.nan
        lo = min(lo, v)
        hi = max(hi, v)
    return lo, hi


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
    lo, hi = finite_range(theta)
    if not math.isfinite(lo):
        return math.nan, -1, math.nan
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
    the same results.  W5: work array of at least (5, n + w, lanes), n + w >= 4.
    Writes err (NaN where ``dwell_error`` gives NaN), start (-1 there) and full.

    Give ``lanes`` as a run-time value (an array's shape): a constant count has
    LLVM unroll the lane loops, which then stay scalar.  No value is written back
    where the same loop read it (a select of a row's own value, which LLVM writes
    with masked stores, microcoded on AMD's AVX2 cores), and each lane loop
    touches few arrays (LLVM checks every pair for overlap before it vectorizes)."""
    b = w + 1
    m = n + w
    pmax = W5[0]
    smax = W5[1]
    pmin = W5[2]
    smin = W5[3]
    # counters instead of j % n and j % b: an integer division per row costs
    # more than the row's work
    q = 0                         # j % b
    for j in range(m):
        k = j if j < n else j - n
        if q == 0:
            for l in range(lanes):
                pmax[j, l] = theta[k, l]
            for l in range(lanes):
                pmin[j, l] = theta[k, l]
        else:
            for l in range(lanes):
                pmax[j, l] = max(pmax[j - 1, l], theta[k, l])
            for l in range(lanes):
                pmin[j, l] = min(pmin[j - 1, l], theta[k, l])
        q = 0 if q == b - 1 else q + 1
    q = (m - 1) % b
    for j in range(m - 1, -1, -1):
        k = j if j < n else j - n
        if q == b - 1 or j == m - 1:
            for l in range(lanes):
                smax[j, l] = theta[k, l]
            for l in range(lanes):
                smin[j, l] = theta[k, l]
        else:
            for l in range(lanes):
                smax[j, l] = max(smax[j + 1, l], theta[k, l])
            for l in range(lanes):
                smin[j, l] = min(smin[j + 1, l], theta[k, l])
        q = b - 1 if q == 0 else q - 1
    # the revolution's extremes: its blocks' (the suffix extrema at their first rows)
    hi = W5[4, 0]
    lo = W5[4, 1]
    nan = W5[4, 2]
    first = W5[4, 3]
    for l in range(lanes):
        h = smax[0, l]
        o = smin[0, l]
        for j in range(b, m, b):
            h = max(h, smax[j, l])
            o = min(o, smin[j, l])
        hi[l] = h
        lo[l] = o
        nan[l] = 0.0
        first[l] = 0.0
    for k in range(n):
        for l in range(lanes):
            nan[l] += theta[k, l] - theta[k, l]     # stays 0.0 unless a NaN or inf
    # window s..s+w: the suffix of s's block and the prefix of (s+w)'s; its range
    # overwrites smax[s] (read there for the last time)
    rng = smax
    for s in range(n):
        for l in range(lanes):
            rng[s, l] = max(smax[s, l], pmax[s + w, l]) - min(smin[s, l], pmin[s + w, l])
    # the least range's first window: the running least range (into pmin) falls to
    # it there, so its start counts the windows before where it is still above
    least = pmin
    for l in range(lanes):
        least[0, l] = rng[0, l]
    for s in range(1, n):
        for l in range(lanes):
            least[s, l] = min(least[s - 1, l], rng[s, l])
    for s in range(n):
        for l in range(lanes):
            first[l] += 1.0 if least[s, l] > least[n - 1, l] else 0.0
    for l in range(lanes):
        f = hi[l] - lo[l]
        full[l] = f
        err[l] = least[n - 1, l]
        start[l] = int(first[l])
        if nan[l] != 0.0:
            err[l] = math.nan
            start[l] = -1
            full[l] = math.nan
        elif not (f > 0.0) or w < 1 or w >= n:
            err[l] = math.nan
            start[l] = -1
        else:
            err[l] = err[l] / f


@njit(**JIT)
def law_error(theta, law, off, best, corr):
    """Deviation of the output rocker from a required motion law.

    theta: the rocker's angles at the n positions of a revolution (any
    origin); law[off + j], j = 0 .. 2n - 1: the law's normalised displacement
    (0 at the dwell, 1 at the full swing) at position j mod n (two turns, so
    a shifted law reads law[off + k + s] without a modulo).  The rocker is
    normalised the same way, u = (theta - min) / (max - min) or 1 - that:
    the orientation that fits the law better (which end of the swing the
    rocker dwells at is the design's choice of sign, not a timing error).
    With ``best`` every cyclic shift s of the law is tried and the best kept
    (the crank's mounting phase that fits the law best; ``corr``: work array
    of at least n), else s = 0.  Returns (RMS of u - law, largest |u - law|,
    s); NaN (and s = -1) if theta has NaN or does not move.
    """
    n = theta.shape[0]
    lo, hi = finite_range(theta)
    if not math.isfinite(lo):
        return math.nan, math.nan, -1
    full = hi - lo
    if not (full > 0.0):
        return math.nan, math.nan, -1
    inv = 1.0 / full
    shift = 0
    flip = False
    if best:
        # sum_k (u_k - L_k+s)^2 = S(u^2) + S(L^2) - 2 c(s), and for 1 - u:
        # S((1-u)^2) + S(L^2) - 2 S(L) + 2 c(s), with c(s) = sum_k u_k L_k+s:
        # the best s has the largest c (u) or the smallest (1 - u).  c for
        # every s at once, s innermost and element-wise (no reduction, so strict
        # IEEE still vectorizes it), four k per pass over corr: n^2 multiply-adds
        su2 = 0.0
        sd2 = 0.0
        sl = 0.0
        for k in range(n):
            u = (theta[k] - lo) * inv
            su2 += u * u
            sd2 += (1.0 - u) * (1.0 - u)
            sl += law[off + k]
        for s in range(n):
            corr[s] = 0.0
        n4 = n - n % 4
        for k in range(0, n4, 4):
            u0 = (theta[k] - lo) * inv
            u1 = (theta[k + 1] - lo) * inv
            u2 = (theta[k + 2] - lo) * inv
            u3 = (theta[k + 3] - lo) * inv
            # views (no copy): law from k, k + 1, k + 2, k + 3 on
            b0 = law[off + k:off + k + n]
            b1 = law[off + k + 1:off + k + 1 + n]
            b2 = law[off + k + 2:off + k + 2 + n]
            b3 = law[off + k + 3:off + k + 3 + n]
            for s in range(n):
                corr[s] += (u0 * b0[s] + u1 * b1[s]) + (u2 * b2[s] + u3 * b3[s])
        for k in range(n4, n):
            u0 = (theta[k] - lo) * inv
            b0 = law[off + k:off + k + n]
            for s in range(n):
                corr[s] += u0 * b0[s]
        cmax = -math.inf
        cmin = math.inf
        smax = 0
        smin = 0
        for s in range(n):          # the first s on ties
            if corr[s] > cmax:
                cmax = corr[s]
                smax = s
            if corr[s] < cmin:
                cmin = corr[s]
                smin = s
        if su2 - 2.0 * cmax <= sd2 - 2.0 * sl + 2.0 * cmin:
            shift = smax
        else:
            shift = smin
            flip = True
    else:
        up = 0.0
        dn = 0.0
        for k in range(n):
            u = (theta[k] - lo) * inv
            a = u - law[off + k]
            b = 1.0 - u - law[off + k]
            up += a * a
            dn += b * b
        flip = dn < up
    # the chosen fit again, directly (no cancellation: ~0 for a rocker on the law)
    sq = 0.0
    top = 0.0
    for k in range(n):
        u = (theta[k] - lo) * inv
        if flip:
            u = 1.0 - u
        e = u - law[off + k + shift]
        sq += e * e
        top = max(top, abs(e))
    return math.sqrt(sq / n), top, shift


# above this share of the cos/sin cross test an angle is certainly above the smallest so far
_ABOVE = 1.0 + 1e-9


@njit(**JIT)
def fold_angle(ux, uy, wx, wy, best_cos=math.nan, best_sin=math.nan):
    """The angle between the lines of directions u and w, in [0, pi/2].  With
    the cos and sin of the smallest angle found so far (a running minimum):
    inf where this angle is certainly larger, without the atan2 (a library
    call): |u x w| cos(best) > |u . w| sin(best) (1 + 1e-9) says
    atan2(|u x w|, |u . w|) > best, whatever the rounding of either side, so
    the minimum is the same to the bit; NaN (no minimum yet) never skips."""
    return fold_cd(abs(ux * wy - uy * wx), abs(ux * wx + uy * wy), best_cos, best_sin)


@njit(**JIT)
def fold_cd(c, d, best_cos=math.nan, best_sin=math.nan):
    """``fold_angle`` from c = |u x w| and d = |u . w| (the force lanes keep
    these per position and take the minimum afterwards)."""
    if c * best_cos > d * best_sin * _ABOVE:
        return math.inf
    return math.atan2(c, d)


@njit(**JIT)
def dyad_transmission(pos, ia, ib, ic, best_cos=math.nan, best_sin=math.nan):
    """Transmission angle of a two-link dyad A-B-C at its middle joint B: the
    angle between B->A and B->C, folded into [0, pi/2] (``pipeline.solve.peaks``;
    best_cos, best_sin: ``fold_angle``'s running minimum)."""
    return fold_angle(pos[ia, 0] - pos[ib, 0], pos[ia, 1] - pos[ib, 1],
                      pos[ic, 0] - pos[ib, 0], pos[ic, 1] - pos[ib, 1], best_cos, best_sin)


@njit(**JIT)
def lead_transmission(pos, ij, ip, ia, ib, ic, idd, best_cos=math.nan, best_sin=math.nan):
    """Transmission angle of a class III lead J-P (J on the ternary link, P
    its pivot): the angle at J between the lead and the line from J through
    Q, where the lines A-B and C-D of the other two leads meet (with axial
    forces in those leads the ternary link, in equilibrium under three
    forces, passes its force to this lead along J-Q).  Folded into
    [0, pi/2]; 0 when the three leads' lines meet in one point (the group's
    singular position).  Homogeneous coordinates about J: parallel leads
    (Q at infinity) need no special case."""
    jx = pos[ij, 0]
    jy = pos[ij, 1]
    ax = pos[ia, 0] - jx
    ay = pos[ia, 1] - jy
    bx = pos[ib, 0] - jx
    by = pos[ib, 1] - jy
    cx = pos[ic, 0] - jx
    cy = pos[ic, 1] - jy
    dx = pos[idd, 0] - jx
    dy = pos[idd, 1] - jy
    # the lines (a, 1) x (b, 1) and (c, 1) x (d, 1), and their meet Q = (X, Y, W)
    l1x = ay - by
    l1y = bx - ax
    l1w = ax * by - ay * bx
    l2x = cy - dy
    l2y = dx - cx
    l2w = cx * dy - cy * dx
    qx = l1y * l2w - l1w * l2y
    qy = l1w * l2x - l1x * l2w
    # J is the origin: the direction J -> Q is (X, Y) (times W, whose sign folds away)
    return fold_angle(pos[ip, 0] - jx, pos[ip, 1] - jy, qx, qy, best_cos, best_sin)


@njit(**JIT)
def _line(pos, ia, ib, alpha):
    """Direction of the link a->b turned by ``alpha`` (the absolute direction
    ``alpha`` where ia < 0); not normalised."""
    c = math.cos(alpha)
    s = math.sin(alpha)
    if ia < 0:
        return c, s
    dx = pos[ib, 0] - pos[ia, 0]
    dy = pos[ib, 1] - pos[ia, 1]
    return c * dx - s * dy, s * dx + c * dy


@njit(**JIT)
def lines_transmission(pos, ia, ib, alpha, ic, idd, beta, best_cos=math.nan, best_sin=math.nan):
    """Transmission angle of a group with a sliding pair: the angle between
    line 1 (the link a->b turned by ``alpha``, or the absolute ``alpha`` where
    ia < 0) and line 2 (c->d turned by ``beta``), folded into [0, pi/2].  Each
    group's emitter picks the two lines so that this is 90 deg minus the
    angle between the line of the force the group transmits and the velocity
    of the member it drives (``pipeline.solve.peaks.transmission_items``)."""
    ux, uy = _line(pos, ia, ib, alpha)
    wx, wy = _line(pos, ic, idd, beta)
    return fold_angle(ux, uy, wx, wy, best_cos, best_sin)
