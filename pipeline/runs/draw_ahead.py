"""A local sweep's draws in a process of their own, forked as the run starts.

The sampler's first draw imports SciPy's statistics (``scipy.stats``: 0.6 s and
more), and the first chunk waited for it after the kernels' load (0.5 s), both
work of the interpreter, which one core does at a time.  A process forked before
the kernels' load imports it meanwhile, on another core, then draws each chunk
the run asks for: the run's first chunk starts sooner (a run of 20,000
candidates on 2 cores of a 2-core AMD EPYC: 2.1 s before, 1.7 s so, five runs
each, alternated), and the draws leave the run's interpreter afterwards.

The same bits: the child calls the draw the run would call
(``sampling.draw_checked``), which gives a chunk the same points whoever draws
it and in whatever order.  Only where forking is safe and cheap: on Linux, in a
process with no other thread yet (the command line's run; an interpreter with
threads at work, a test session's or a notebook's, draws as before).  The child
keeps none of the run's files open (its lock on the results file is the run's
alone) and ends when the run closes its pipe, or dies.  A child that fails or
ends leaves the draws to the run's own process, the same again.
``PIPELINE_DRAW_AHEAD=0`` turns it off."""

from __future__ import annotations

import contextlib
import logging
import os
import pickle
import signal
import struct
import sys
import threading
import time

from ..study.sampling import draw_checked

_HEAD = struct.Struct("<q")
log = logging.getLogger("pipeline")


class DrawAhead:
    """The run's side of a forked drawing process: ``draw(chunk)`` as
    ``draw_checked(spec, chunk)``, asked of the child (one caller at a time: the
    run's drawing thread)."""

    def __init__(self, spec, pid, ask, answers):
        self.spec, self.pid, self._ask, self._answers = spec, pid, ask, answers
        self.failed = False

    @classmethod
    def start(cls, spec) -> DrawAhead | None:
        """The child forked, already importing the sampler; None where it is not
        forked (see the module's doc)."""
        if (not sys.platform.startswith("linux") or threading.active_count() != 1
                or os.environ.get("PIPELINE_DRAW_AHEAD", "1") == "0"):
            return None
        ask_r, ask_w = os.pipe()
        ans_r, ans_w = os.pipe()
        pid = os.fork()
        if pid == 0:                # the child: never back into the run's code
            try:
                _close_all_but(ask_r, ans_w)
                signal.signal(signal.SIGINT, signal.SIG_IGN)   # the run decides; EOF ends it
                _serve(spec, ask_r, ans_w)
            finally:
                os._exit(0)
        os.close(ask_r)
        os.close(ans_w)
        log.debug("the sampler's import and the draws in process %d, beside", pid)
        return cls(spec, pid, os.fdopen(ask_w, "wb"), os.fdopen(ans_r, "rb"))

    def draw(self, chunk):
        """(x, rejected) of chunk ``chunk``: the child's, or this process's own
        where the child failed (its error, if any, is the draw's own again)."""
        if not self.failed:
            try:
                self._ask.write(_HEAD.pack(chunk))
                self._ask.flush()
                head = self._answers.read(_HEAD.size)
                body = self._answers.read(_HEAD.unpack(head)[0]) if len(head) == _HEAD.size \
                    else b""
                c, drawn = pickle.loads(body)
                if c == chunk and drawn is not None:
                    return drawn
            except Exception:   # (a child gone: a broken pipe, a short answer)
                pass
            self.failed = True
        return draw_checked(self.spec, chunk)

    def close(self):
        """The child told to end (its pipe closed) and waited for; killed if it
        is still there after a second."""
        for f in (self._ask, self._answers):
            with contextlib.suppress(OSError):
                f.close()
        deadline = time.monotonic() + 1.0
        with contextlib.suppress(ChildProcessError):      # (already waited for)
            while not os.waitpid(self.pid, os.WNOHANG)[0]:
                if time.monotonic() > deadline:
                    with contextlib.suppress(ProcessLookupError):
                        os.kill(self.pid, signal.SIGKILL)
                    os.waitpid(self.pid, 0)
                    return
                time.sleep(0.005)


def _close_all_but(*keep):
    """Every file the child inherited closed but its standard streams and ``keep``:
    the run's lock on its results file is the run's alone (a run killed with -9
    is resumed at once, and the lock must go with it), and the pipe's other ends
    are the run's."""
    for name in os.listdir("/proc/self/fd"):
        fd = int(name)
        if fd > 2 and fd not in keep:
            with contextlib.suppress(OSError):      # (the listing's own, closed by now)
                os.close(fd)


def _serve(spec, ask_r, ans_w):
    """The child: the sampler imported, then each chunk asked for drawn, until
    the run closes its pipe.  A draw that raises is answered None (the run
    draws it itself, and raises the same)."""
    from scipy import stats  # noqa: F401  (the import this process is for)
    with os.fdopen(ask_r, "rb") as ask, os.fdopen(ans_w, "wb") as answers:
        while True:
            head = ask.read(_HEAD.size)
            if len(head) < _HEAD.size:
                return
            chunk = _HEAD.unpack(head)[0]
            try:
                drawn = draw_checked(spec, chunk)
            except Exception:
                drawn = None
            body = pickle.dumps((chunk, drawn), protocol=pickle.HIGHEST_PROTOCOL)
            answers.write(_HEAD.pack(len(body)) + body)
            answers.flush()


@contextlib.contextmanager
def drawing_ahead(problem, local: bool):
    """Around a sweep's run: the draw its chunks take (``SweepProblem.draw_chunk``'s
    ``draw``), a forked process's where ``local`` and the host draws on the CPU,
    else None (the problem draws as it does)."""
    ahead = (DrawAhead.start(problem.spec)
             if local and problem.device == "cpu" else None)
    try:
        yield None if ahead is None else ahead.draw
    finally:
        if ahead is not None:
            ahead.close()
