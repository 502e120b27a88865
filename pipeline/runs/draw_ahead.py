"""A local sweep's draws in a process of their own, forked as the run starts.

The sampler's first draw imports SciPy's statistics (``scipy.stats``: 0.6 s and
more), and the first chunk waited for it after the kernels' load (0.5 s), both
work of the interpreter, which one core does at a time.  A process forked first
(``prefork``: ``pipeline run`` of a sweep study, before the study is read)
imports it meanwhile, on another core, then draws each chunk the run asks for:
the run's first chunk starts sooner, and the draws leave the run's interpreter.
A run of 20,000 candidates of the main job, on a 2-core AMD EPYC, five runs each
alternated: 2.4 s before, 1.5 s so (medians, -j 2); 2.6 s and 1.9 s (-j 1).

The same bits: the child calls the draw the run would call
(``sampling.draw_checked``), which gives a chunk the same points whoever draws
it and in whatever order.  Only where forking is safe and cheap: on Linux, in a
process with no other thread yet (the command line's run; an interpreter with
threads at work, a test session's or a notebook's, draws as before, or forks
when its sweep starts where it has no thread: ``drawing_ahead``).  The child
keeps none of the run's files open (its lock on the results file is the run's
alone) and ends when the run closes its pipe, or dies.  A child that fails or
ends leaves the draws to the run's own process, the same again.
``PIPELINE_DRAW_AHEAD=0`` turns it off."""

from __future__ import annotations

import contextlib
import importlib
import logging
import os
import pickle
import signal
import struct
import sys
import threading
import time
import tomllib

from ..study.sampling import draw_checked

_HEAD = struct.Struct("<q")
log = logging.getLogger("pipeline")


class DrawAhead:
    """The run's side of a forked drawing process: ``begin(spec)``, then
    ``draw(chunk)`` as ``draw_checked(spec, chunk)``, asked of the child (one
    caller at a time: the run's drawing thread)."""

    def __init__(self, pid, ask, answers):
        self.pid, self._ask, self._answers = pid, ask, answers
        self.spec = None
        self.failed = False

    @classmethod
    def fork(cls) -> DrawAhead | None:
        """The child forked, importing the sampler at once, then waiting for its
        sweep (``begin``); None where it is not forked (see the module's doc)."""
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
                _serve(ask_r, ans_w)
            finally:
                os._exit(0)
        os.close(ask_r)
        os.close(ans_w)
        log.debug("the sampler's import and the draws in process %d, beside", pid)
        return cls(pid, os.fdopen(ask_w, "wb"), os.fdopen(ans_r, "rb"))

    def begin(self, spec):
        """The sweep ``spec`` the child draws for, from now on."""
        self.spec = spec
        body = pickle.dumps(spec, protocol=pickle.HIGHEST_PROTOCOL)
        try:
            self._ask.write(_HEAD.pack(-len(body)) + body)
            self._ask.flush()
        except OSError:     # (a child gone)
            self.failed = True

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

    def discard(self):
        """The child of a run that did not take it ended at once (it has done
        nothing but import and wait) and waited for."""
        with contextlib.suppress(ProcessLookupError):
            os.kill(self.pid, signal.SIGKILL)
        self.close()

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
    """Every file the child inherited closed but ``keep``, its standard streams
    on /dev/null: the run's lock on its results file is the run's alone (a run
    killed with -9 is resumed at once, and the lock must go with it), the pipe's
    other ends are the run's, and a caller that reads the run's output to its
    end never waits for the child (it writes nothing)."""
    null = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):
        os.dup2(null, fd)
    for name in os.listdir("/proc/self/fd"):
        fd = int(name)
        if fd > 2 and fd not in keep:
            with contextlib.suppress(OSError):      # (the listing's own, closed by now)
                os.close(fd)


def _serve(ask_r, ans_w):
    """The child: the sampler imported, then its sweep's spec read and each chunk
    asked for drawn, until the run closes its pipe.  A draw that raises (or comes
    before the spec) is answered None: the run draws it itself, and raises the
    same."""
    importlib.import_module("scipy.stats")     # (the import this process is for)
    spec = None
    with os.fdopen(ask_r, "rb") as ask, os.fdopen(ans_w, "wb") as answers:
        while True:
            head = ask.read(_HEAD.size)
            if len(head) < _HEAD.size:
                return
            n = _HEAD.unpack(head)[0]
            if n < 0:           # the sweep's spec, pickled
                spec = pickle.loads(ask.read(-n))
                continue
            try:
                drawn = None if spec is None else draw_checked(spec, n)
            except Exception:
                drawn = None
            body = pickle.dumps((n, drawn), protocol=pickle.HIGHEST_PROTOCOL)
            answers.write(_HEAD.pack(len(body)) + body)
            answers.flush()


_WAITING: list = []     # the child ``prefork`` forked, waiting for its sweep


def prefork(study_path) -> None:
    """Where ``pipeline run`` runs a sweep study (its file says kind = "sweep" and
    has no [search]), the drawing process forked now, before the study is read
    and the package's numerical part imported: the sampler's import then ends
    before the kernels' load does.  A run that does not take it (a refusal, a
    GPU's or a cluster's draws) lets it go (``drawing_ahead``, or this
    process's end)."""
    try:
        with open(study_path, "rb") as fh:
            data = tomllib.load(fh)
        sweep = data.get("study", {}).get("kind") == "sweep" and "search" not in data
    except Exception:       # (the reader says what is wrong with it)
        return
    if sweep and not _WAITING:
        ahead = DrawAhead.fork()
        if ahead is not None:
            _WAITING.append(ahead)


def let_go() -> None:
    """The child ``prefork`` forked, where no run took it (a refused or failed
    run), ended now rather than at this process's end."""
    while _WAITING:
        _WAITING.pop().discard()


@contextlib.contextmanager
def drawing_ahead(problem, local: bool):
    """Around a sweep's run: the draw its chunks take (``SweepProblem.draw_chunk``'s
    ``draw``), a forked process's where ``local`` and the host draws on the CPU
    (the one ``prefork`` forked, or one forked now), else None (the problem draws
    as it does)."""
    waiting = _WAITING.pop() if _WAITING else None
    ahead = None
    if local and problem.device == "cpu":
        ahead = waiting or DrawAhead.fork()
    elif waiting is not None:
        waiting.discard()
    if ahead is not None:
        ahead.begin(problem.spec)
    try:
        yield None if ahead is None else ahead.draw
    finally:
        if ahead is not None:
            ahead.close()
