"""Progress that never leaves a person waiting in silence.

On a terminal a command shows a live line (a tqdm bar, or for work of unknown
length the seconds it has taken, redrawn twice a second), and the log lines it
writes meanwhile go above it.  Elsewhere (a pipe, a log file, CI) it writes
plain lines: one when a stage starts, one every ``QUIET_S`` seconds while it
runs, and one with its time when it ends; no carriage returns.  Both follow
logging: ``-q`` (WARNING) silences them.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import threading
import time

log = logging.getLogger("pipeline")

QUIET_S = 10.0      # a plain line at least this often while a stage runs off a terminal
REDRAW_S = 0.5      # a terminal's live line is redrawn this often

_said_at = [time.perf_counter()]    # when the command last said something


def said_now():
    """Note that the command has just said something (a log line, a live line's
    redraw): a stage's ``after`` counts from there (``ticking``)."""
    _said_at[0] = time.perf_counter()


def _note_said(record) -> bool:
    said_now()          # a line the "pipeline" logger lets through: said now
    return True


log.addFilter(_note_said)


def on_terminal() -> bool:
    """Progress goes to stderr: is that a terminal a person watches?"""
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def shown() -> bool:
    return log.isEnabledFor(logging.INFO)


class _PlainBar:
    """tqdm's update/set_postfix_str/close as plain log lines, at most one per
    ``QUIET_S`` seconds (and one at the end)."""

    def __init__(self, total, initial=0, desc="", unit="it"):
        self.total, self.n, self.desc, self.unit = total, initial, desc, unit
        self.t0 = self.last = time.perf_counter()
        self.postfix = ""
        self.closed = False

    def _line(self):
        el = time.perf_counter() - self.t0
        of = f"/{self.total:,}" if self.total else ""
        post = f", {self.postfix}" if self.postfix else ""
        log.info("%s: %s%s %s, %.0f s%s", self.desc, f"{self.n:,}", of, self.unit, el, post)

    def update(self, k=1):
        self.n += k
        now = time.perf_counter()
        if now - self.last >= QUIET_S:
            self.last = now
            self._line()

    def set_postfix_str(self, text, refresh=True):
        self.postfix = text

    def close(self):
        if not self.closed:
            self.closed = True
            self._line()


def bar(total=None, *, initial=0, desc="", unit="it", enabled=True, **tqdm_kw):
    """A progress bar: tqdm on a terminal (redrawn every REDRAW_S while it
    waits for an update), plain log lines elsewhere (shown where logging shows
    INFO), nothing when not ``enabled``."""
    from tqdm import tqdm
    if not enabled:
        return tqdm(total=total, disable=True)
    if not on_terminal():
        return _PlainBar(total, initial, desc, unit)
    b = tqdm(total=total, initial=initial, desc=desc, unit=unit, dynamic_ncols=True, **tqdm_kw)
    # tqdm redraws only when told of progress: between updates (a long chunk, a
    # module imported on the way) its time and rate are redrawn every REDRAW_S
    stop = threading.Event()

    def redraw():
        while not stop.wait(REDRAW_S):
            b.refresh()         # under the bar's own lock, as update() draws
            said_now()

    th = threading.Thread(target=redraw, daemon=True, name="pipeline-progress-bar")
    th.start()
    close = b.close

    def closing():
        stop.set()
        if th is not threading.current_thread():
            th.join()
        close()
        said_now()

    b.close = closing
    return b


def terminal_width() -> int:
    """Columns of the terminal that progress goes to (80 where it does not say)."""
    try:
        return os.get_terminal_size(sys.stderr.fileno()).columns or 80
    except (AttributeError, ValueError, OSError):
        return 80


def live_line(what: str, seconds: float, width: int) -> str:
    """'WHAT: N s' in fewer than ``width`` columns (the last one left free: a
    terminal wraps a full line): a long WHAT is cut, never the seconds, which
    show that the stage is alive."""
    tail = f": {seconds:.0f} s"
    room = max(width - 1 - len(tail), 8)
    if len(what) > room:
        what = what[:room - 3].rstrip() + "..."
    return what + tail


class _Ticker:
    def __init__(self, what):
        self.what = self.name = what

    def set(self, detail):
        """Say what the stage does now: 'NAME: DETAIL'."""
        self.what = f"{self.name}: {detail}"


@contextlib.contextmanager
def ticking(what: str, *, after: float = 0.0, say_done: bool = True):
    """A stage of unknown length: ``what`` and the seconds it has taken, live on
    a terminal (redrawn every REDRAW_S), a plain line every QUIET_S elsewhere,
    and (``say_done``) a line with its time at the end.  ``after``: nothing at
    all unless the stage takes that long (a cache that may be warm), counted from
    the last thing the command said (within QUIET_S): stages that each stay under
    it, one after another, never leave a person in silence for longer (two of a
    search's did).
    Yields an object whose ``set(text)`` changes what the line says.  The live
    line fits the terminal's width, its seconds always in it (``live_line``)."""
    t = _Ticker(what)
    if not shown():
        yield t
        return
    t0 = time.perf_counter()
    stop, started = threading.Event(), threading.Event()
    term = on_terminal()
    line = []

    def elapsed():
        return time.perf_counter() - t0

    def begin():
        if term:
            from tqdm import tqdm
            bar_ = tqdm(total=None, bar_format="{desc}", leave=False, dynamic_ncols=True)
            bar_.set_description_str(live_line(t.what, elapsed(), terminal_width()))
            line.append(bar_)
            said_now()
        else:
            log.info("%s ...", t.what)
        started.set()

    # the silence left before ``after`` is reached, counted from the last thing said
    # (said more than QUIET_S ago: no one is waiting on it, ``after`` from now)
    since = t0 - _said_at[0]
    quiet_s = max(0.0, after - since) if 0.0 <= since < QUIET_S else after

    def tick():
        if after and stop.wait(quiet_s):
            return
        if not started.is_set():
            begin()
        while not stop.wait(REDRAW_S if term else QUIET_S):
            if term:
                line[0].set_description_str(live_line(t.what, elapsed(), terminal_width()))
                said_now()
            else:
                log.info("%s: still at work, %.0f s", t.what, elapsed())

    if term:
        from tqdm.contrib.logging import logging_redirect_tqdm
        ctx = logging_redirect_tqdm(loggers=[logging.getLogger()])
    else:
        ctx = contextlib.nullcontext()
    ok = False
    with ctx:
        if not after:
            begin()
        th = threading.Thread(target=tick, daemon=True, name="pipeline-progress")
        th.start()
        try:
            yield t
            ok = True
        finally:
            stop.set()
            th.join()
            for b in line:
                b.close()
                said_now()      # the live line wiped
    if ok and say_done and started.is_set():
        log.info("%s: %.1f s", what, elapsed())
