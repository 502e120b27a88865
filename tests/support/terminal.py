"""Run a command on a pseudo-terminal (an 80x24 one, as a person's) and note
when each piece of its output arrives, on the command's own pace.

The command's own pace: the seconds since its start less the time it waited
for a processor (on a machine loaded beyond its cores a command waits its turn,
and a silence that a quiet machine would not have is the machine's, not the
command's).  Linux counts each thread's wait on the run queue
(/proc/PID/task/TID/schedstat, its second field, in ns); over each short
interval the wait of the command's most delayed thread (of it and of any
process it started) is taken off its clock, and the wait of this reader before
it saw an output is taken off that output's time.  Where Linux gives no such
counts, the pace is the wall clock's."""

import fcntl
import os
import re
import select
import struct
import subprocess
import termios
import time

POLL_S = 0.05       # the reader's look at the command and at its waits
# the longest a command on a terminal may stay silent (a live line redrawn each second
# counts as output), on its own pace
SILENCE_S = 2.0


def run_on_terminal(argv, env=None, cwd=None, timeout=300.0, pieces=None):
    """(exit code, [seconds of each output], seconds to exit, the text): the
    seconds on the command's own pace (the module's doc); ``timeout`` is a hang
    guard in wall seconds; ``pieces``, a list, gets each output's (seconds, text)."""
    master, slave = os.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))
    t0 = time.perf_counter()
    p = subprocess.Popen(argv, stdin=slave, stdout=slave, stderr=slave, env=env, cwd=cwd,
                         close_fds=True)
    os.close(slave)
    pace = Pace(p.pid, t0)
    times, chunks, late = [], [], 0.0
    try:
        while time.perf_counter() - t0 < timeout:
            mine = own_wait()
            ready, _, _ = select.select([master], [], [], POLL_S)
            pace.look()
            late = own_wait() - mine            # this reader's wait for a processor
            if ready:
                try:
                    b = os.read(master, 4096)
                except OSError:         # the child closed the terminal
                    break
                if not b:
                    break
                times.append(pace.now(late, after=times[-1] if times else 0.0))
                chunks.append(b)
                if pieces is not None:
                    pieces.append((times[-1], b.decode(errors="replace")))
            elif p.poll() is not None:
                break
        end = pace.now(late, after=times[-1] if times else 0.0)
    finally:
        if p.poll() is None:
            p.kill()
        p.wait()
        os.close(master)
    return p.returncode, times, end, b"".join(chunks).decode(errors="replace")


def longest_silence(times, end):
    """The longest wait between two outputs, or after the last one (the start
    of the interpreter, before the first, left out)."""
    return max(b - a for a, b in zip(times, times[1:] + [end]))


def run_queue_wait(path) -> float:
    """Seconds the thread of /proc/.../schedstat ``path`` has waited for a
    processor (0 where Linux does not say)."""
    try:
        with open(path) as f:
            return int(f.read().split()[1]) * 1e-9
    except (OSError, IndexError, ValueError):
        return 0.0


def own_wait() -> float:
    return run_queue_wait("/proc/thread-self/schedstat")


def thread_waits(pid) -> dict:
    """{(pid, tid): seconds waited} of every thread of ``pid`` and of the
    processes it started, theirs too ({} once it is gone)."""
    waits = {}
    todo = [pid]
    while todo:
        proc = todo.pop()
        try:
            tids = os.listdir(f"/proc/{proc}/task")
        except OSError:
            continue
        for tid in tids:
            waits[proc, tid] = run_queue_wait(f"/proc/{proc}/task/{tid}/schedstat")
            try:
                with open(f"/proc/{proc}/task/{tid}/children") as f:
                    todo += [int(c) for c in f.read().split()]
            except (OSError, ValueError):
                pass
    return waits


class Pace:
    """The command's clock: wall seconds since ``t0`` less, for each interval
    between two looks, the largest wait for a processor that one of its threads
    was given in it (Linux adds a wait when the thread gets its turn: one wait may
    span many looks, and is counted whole at the look after it)."""

    def __init__(self, pid, t0):
        self.pid, self.t0 = pid, t0
        self.waits = {}             # (pid, tid) -> its wait at the last look
        self.waited = 0.0

    def look(self):
        waits = thread_waits(self.pid)
        grew = max((w - self.waits.get(k, 0.0) for k, w in waits.items()), default=0.0)
        self.waited += max(grew, 0.0)
        self.waits.update(waits)

    def now(self, late=0.0, after=0.0) -> float:
        """Seconds on the command's clock now, less ``late`` (the reader's own
        wait before it saw what it notes), never before ``after``."""
        wall = time.perf_counter() - self.t0
        return max(wall - min(self.waited + max(late, 0.0), wall), after)


_ESCAPE = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")
LIVE = re.compile(r": (\d+) s$")


def live_lines(text):
    """The live lines the terminal showed ('WHAT: N s', each drawn between two
    carriage returns or line ends), their padding dropped: a line cut before its
    seconds is none."""
    parts = (p.rstrip() for p in re.split(r"[\r\n]", _ESCAPE.sub("", text)))
    return [p for p in parts if LIVE.search(p)]


def said_live(text, start):
    """The live lines that begin with ``start`` fit 80 columns, and there are some."""
    lines = [p for p in live_lines(text) if p.startswith(start)]
    assert lines, (start, text)
    assert all(len(p) < 80 for p in lines), lines
    return lines
