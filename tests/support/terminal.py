"""Run a command on a pseudo-terminal (an 80x24 one, as a person's) and note
when each piece of its output arrives."""

import fcntl
import os
import select
import struct
import subprocess
import termios
import time


def run_on_terminal(argv, env=None, cwd=None, timeout=300.0):
    """(exit code, [seconds of each output], seconds to exit, the text)."""
    master, slave = os.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))
    t0 = time.perf_counter()
    p = subprocess.Popen(argv, stdin=slave, stdout=slave, stderr=slave, env=env, cwd=cwd,
                         close_fds=True)
    os.close(slave)
    times, chunks = [], []
    try:
        while time.perf_counter() - t0 < timeout:
            ready, _, _ = select.select([master], [], [], 0.05)
            if ready:
                try:
                    b = os.read(master, 4096)
                except OSError:         # the child closed the terminal
                    break
                if not b:
                    break
                times.append(time.perf_counter() - t0)
                chunks.append(b)
            elif p.poll() is not None:
                break
    finally:
        if p.poll() is None:
            p.kill()
        p.wait()
        os.close(master)
    return p.returncode, times, time.perf_counter() - t0, b"".join(chunks).decode(errors="replace")


def longest_silence(times, end):
    """The longest wait between two outputs, or after the last one (the start
    of the interpreter, before the first, left out)."""
    return max(b - a for a, b in zip(times, times[1:] + [end]))
