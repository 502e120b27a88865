"""All cores for the generated kernels: ranges of candidates on threads.

The kernels are compiled with ``nogil=True``, so Python threads run them in
parallel.  A batch kernel takes a row range ``lo, hi``; what a candidate gets
never depends on the range, the thread, the chunking or the engine (every
lane of the lock-step path runs the same instructions; tested).  One compiled
function serves one thread, all cores and a Dask worker (no parallel twin, no
parfor compile).
"""

from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor, wait

from ..kernels.config import LANE_WIDTH

TASK_ROWS = 256          # candidates per task: small enough that threads rarely idle at
                         # the end of a chunk (the force stage falls unevenly)
_POOLS: dict[int, ThreadPoolExecutor] = {}
_LOCK = threading.Lock()


def default_jobs() -> int:
    """The cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def _pool(jobs):
    with _LOCK:
        pool = _POOLS.get(jobs)
        if pool is None:
            pool = _POOLS[jobs] = ThreadPoolExecutor(jobs, thread_name_prefix="pipeline")
        return pool


def _ranges(n, task_rows, jobs):
    """Rows 0 .. n - 1 on ``jobs`` (> 1) threads in ranges of ``task_rows``, the last
    ones shorter (each at most a (2 jobs)-th of the rows left, in whole lane
    blocks), so that the threads end together instead of one waiting for the
    last long range of another (10 ms of a 100 ms chunk on 2 cores)."""
    ranges, lo = [], 0
    while lo < n:
        tail = -(-(n - lo) // (2 * jobs))
        size = min(task_rows, max(LANE_WIDTH, -(-tail // LANE_WIDTH) * LANE_WIDTH))
        ranges.append((lo, min(lo + size, n)))
        lo += size
    return ranges


def run_rows(kernel, pars, *args, n_jobs=None, task_rows=TASK_ROWS):
    """``kernel(pars, lo, hi, *args)`` over all rows of ``pars`` in ranges of
    ``task_rows``, on ``n_jobs`` threads (all cores by default; 1: this thread,
    every row in one call).
    A batch of fewer than ``task_rows`` rows per thread (a search's generation)
    is shared out evenly, in whole lane blocks, so that every thread has some."""
    n = pars.shape[0]
    jobs = default_jobs() if n_jobs is None else int(n_jobs)
    if jobs < 1:
        raise ValueError(f"n_jobs must be at least 1, got {n_jobs}")
    if jobs == 1:
        # one call: between two ranges the thread needs the GIL back, and while the
        # main thread writes a chunk that waited up to the interpreter's switch
        # interval (5 ms) each time (3-4 % of a 1-thread sweep)
        if n:
            kernel(pars, 0, n, *args)
        return
    if n < jobs * task_rows:
        share = -(-n // jobs)
        task_rows = max(LANE_WIDTH, -(-share // LANE_WIDTH) * LANE_WIDTH)
        ranges = [(lo, min(lo + task_rows, n)) for lo in range(0, n, task_rows)]
    else:
        ranges = _ranges(n, task_rows, jobs)
    if len(ranges) <= 1:
        for lo, hi in ranges:
            kernel(pars, lo, hi, *args)
        return
    # the calling thread works too, taking ranges in turn with the pool's threads:
    # one thread fewer to wake (a search's generation is a millisecond or two of
    # kernels, and waking a sleeping worker took as long again)
    todo = iter(ranges)
    lock = threading.Lock()
    stop = threading.Event()        # a range failed (or the caller was interrupted)

    def work():
        while not stop.is_set():
            with lock:
                r = next(todo, None)
            if r is None:
                return
            try:
                kernel(pars, r[0], r[1], *args)
            except BaseException:
                stop.set()
                raise

    pool = _pool(jobs - 1)
    futures = [pool.submit(work) for _ in range(min(jobs, len(ranges)) - 1)]
    try:
        work()
    except BaseException:
        stop.set()
        raise
    finally:
        # every thread done with the arrays before they go back to the caller; the
        # first failure of a pool thread is raised (the caller's own, if any, first)
        wait(futures)
    for f in futures:
        f.result()
