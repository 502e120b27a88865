"""The notice around a run's first evaluation, which compiles a new
mechanism's kernels (a sweep's, a search's, a tolerance analysis's, a
scene's): what it does, the seconds it has taken, and an estimate from the
last compile measured on this machine."""

from __future__ import annotations

import contextlib
import logging
import math
import time

log = logging.getLogger("pipeline")

COMPILE_RECORD = "last_compile_s.txt"     # in the compile cache folder: the last compile's seconds


def compile_record():
    """The file that keeps how long the last new mechanism's kernels took to
    compile on this machine (beside the generated modules it compiled)."""
    from . import cache_dir
    return cache_dir() / COMPILE_RECORD


def last_compile_s():
    """Seconds the last compile took here (``compile_record``), or None."""
    try:
        s = float(compile_record().read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return None
    return s if math.isfinite(s) and s > 0 else None


# what compiles: a new mechanism's generated module, or (a scene on the plan path,
# ``pipeline.compiler.plan_path``) the kernels every mechanism's scenes share, once
MECHANISM = "the kernels of this mechanism (first run only"
INSTALLATION = "this installation's kernels (once for all mechanisms"


@contextlib.contextmanager
def compile_notice(what=MECHANISM):
    """Around the first evaluation of a run (the reference design), which compiles
    a new mechanism's kernels (``what``: MECHANISM, or INSTALLATION for a scene on
    the plan path): a notice if it takes more than a second, and how
    long it took (the list it yields holds the seconds afterwards).  The notice's
    estimate is the last compile measured on this machine (a constant would be
    wrong on every machine but one); the time it took is kept for the next, only
    where numba did compile (its "numba:compile" event: a slow first load from
    numba's cache, a second or more under load, is no compile to estimate from).
    The live line and its seconds fit an 80-column terminal."""
    from numba.core import event

    from ..base.progress import ticking
    last = last_compile_s()
    guess = f"; last time {last:.0f} s" if last is not None else ""
    t = time.perf_counter()
    took = [0.0]
    # after a second: what it does and for how long (live on a terminal)
    with event.install_recorder("numba:compile") as compiled, \
            ticking(f"compiling {what}{guess})", after=1.0, say_done=False):
        yield took
    took[0] = time.perf_counter() - t
    if took[0] > 1.0:
        log.info("kernels ready after %.1f s", took[0])
    if took[0] > 1.0 and compiled.buffer:
        try:
            from ..base.files import write_text
            write_text(compile_record(), f"{took[0]:.1f}\n")
        except OSError:     # a read-only cache: the next notice has no estimate
            pass
