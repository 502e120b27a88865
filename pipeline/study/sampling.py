"""Drawing a sweep's candidates, chunk by chunk, in NumPy outside the kernels.

Chunk c of a study with seed s uses ``SeedSequence(s).spawn(n_chunks)[c]``
(uniform, Latin hypercube) or the points c*chunk .. (c+1)*chunk-1 of one
scrambled Sobol sequence seeded by s: a chunk is the same whatever the thread
count, the engine or the order in which chunks run.  Draws that break a
triangle inequality of the variables are redrawn (rejection sampling)."""

from __future__ import annotations

import threading
import warnings

import numpy as np

# the Sobol engine of the last chunk drawn, per (seed, dimension): the next chunk
# continues it (scrambling a new engine and fast-forwarding costs more than the
# draw); any other chunk starts a fresh engine, so the points are the same
_SOBOL: dict = {}
_SOBOL_LOCK = threading.Lock()


def draw_unit(spec, chunk: int) -> np.ndarray:
    """Chunk ``chunk``'s candidates as points of the unit cube (n, n_vars)."""
    from scipy.stats import qmc     # here, not at import: 1.3 s that every study's load paid
    lo, hi = spec.chunk_bounds(chunk)
    d = len(spec.variables)
    if spec.sampler == "sobol":
        with _SOBOL_LOCK:
            key = (spec.seed, d)
            s, at = _SOBOL.get(key, (None, -1))
            if at != lo:      # not the continuation of the last chunk: a fresh engine
                s = sobol_engine(spec)
                if lo:
                    s.fast_forward(lo)
            with warnings.catch_warnings():  # chunks of one sequence need not be powers of 2
                warnings.simplefilter("ignore", UserWarning)
                u = s.random(hi - lo)
            _SOBOL[key] = (s, hi)
            return u
    child = np.random.SeedSequence(spec.seed).spawn(spec.n_chunks)[chunk]
    rng = np.random.default_rng(child)
    if spec.sampler == "lhs":
        return qmc.LatinHypercube(d, seed=rng).random(hi - lo)
    return rng.random((hi - lo, d))


def sobol_engine(spec):
    """The scrambled Sobol sequence of a sweep with seed ``spec.seed``, at its
    first point: the host's draws step through it (``draw_unit``), the GPU's take
    its direction numbers and shift (``runs.gpu_draws``)."""
    from scipy.stats import qmc
    return qmc.Sobol(len(spec.variables), scramble=True, seed=np.random.default_rng(spec.seed))


# rejection rounds per chunk: with the acceptance >= 1 % that parse_sweep checks, a draw
# is still broken after 5,000 rounds with probability 0.99^5000 = 1.5e-22
REDRAW_ROUNDS = 5000


def draw_candidates(spec, chunk: int) -> np.ndarray:
    """Design variables of chunk ``chunk`` (n, n_vars) in their units."""
    return draw_checked(spec, chunk)[0]


def draw_checked(spec, chunk: int):
    """(x, rejected): chunk ``chunk``'s design variables, every row a buildable
    design (``spec.triangles``), and the number of draws rejected per triangle.

    Rows that break a triangle are redrawn uniformly in the bounds from a
    stream of their own, seeded by (seed, chunk): rejection sampling, so the
    accepted designs are distributed as the sampler's over the buildable part
    of the box, and the same on any number of threads or workers."""
    u = draw_unit(spec, chunk)
    low, span = bounds(spec)
    x = low + u * span
    rejected = np.zeros(len(spec.triangles), np.int64)
    if not spec.triangles:
        return x, rejected
    bad = broken_rows(spec, x, rejected)
    if bad.any():
        bad = np.flatnonzero(bad)
        x[bad] = redrawn(spec, chunk, bad, rejected)
    return x, rejected


def bounds(spec):
    """(low, high - low) of the design variables, as the draws map the unit cube."""
    low = np.array([v.low for v in spec.variables])
    high = np.array([v.high for v in spec.variables])
    return low, high - low


def broken_rows(spec, xs, rejected):
    """Which rows of ``xs`` break a triangle, each counted into ``rejected`` once,
    for the first triangle it breaks."""
    bad = np.zeros(xs.shape[0], bool)
    for k, t in enumerate(spec.triangles):
        b = t.broken(xs) & ~bad
        rejected[k] += int(b.sum())
        bad |= b
    return bad


def redrawn(spec, chunk, rows, rejected):
    """The rows ``rows`` (indices in row order) of chunk ``chunk``'s first draws
    broke a triangle: their values drawn again, uniformly in the bounds from the
    chunk's own stream (seeded by (seed, chunk)), round after round until each
    is buildable, every rejection counted into ``rejected``.  Only the rows just
    redrawn are looked at again (the others are buildable: a GPU's chunk of
    10^6 rows took 13 rounds over all of them, 0.26 s).  The GPU's draws
    (``runs.gpu_draws``) check the first round there and redraw here alike."""
    low, span = bounds(spec)
    rng = np.random.default_rng([spec.seed, chunk, 0x7EDA])
    out = np.empty((len(rows), len(low)))
    todo = np.arange(len(rows))
    for _ in range(REDRAW_ROUNDS):
        out[todo] = low + rng.random((len(todo), len(low))) * span
        bad = broken_rows(spec, out[todo], rejected)
        if not bad.any():
            return out
        todo = todo[bad]
    raise ValueError(f"chunk {chunk}: designs still break a triangle inequality after "
                     f"{REDRAW_ROUNDS} redraws; narrow the bounds of "
                     + ", ".join(n for t in spec.triangles for n in t.names))
