"""No silence over 2 s: on a terminal a command shows a live line while it
works (analyze, compile, report), elsewhere plain lines with no carriage
returns."""

import logging
import os
import sys
import time

import pytest

from pipeline.base import progress
from support.sweep_helpers import copy_of
from support.terminal import longest_silence, run_on_terminal

SILENCE_S = 2.0


def test_plain_lines_off_a_terminal(caplog, monkeypatch):
    monkeypatch.setattr(progress, "QUIET_S", 0.05)
    with caplog.at_level(logging.INFO, logger="pipeline"):
        with progress.ticking("stage") as t:
            t.set("part")
            time.sleep(0.2)
        bar = progress.bar(10, desc="sweep", unit="cand")
        for _ in range(10):
            bar.update(1)
            time.sleep(0.01)
        bar.close()
    text = caplog.text
    assert "stage ..." in text and "stage: part: still at work" in text
    assert "sweep: 10/10 cand" in text and "\r" not in text


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a pseudo-terminal")
def test_commands_on_a_terminal_never_fall_silent(synthesis_sweep, tmp_path, studies):
    """analyze, and compile of a study whose kernels the session compiled:
    the first output comes within 2 s of the interpreter's start (as long as
    `pipeline --help` takes to print), and none is more than 2 s after the
    one before."""
    path = copy_of(synthesis_sweep, tmp_path, "s.h5")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(studies.parent)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    cli = [sys.executable, "-m", "pipeline.cli"]
    code, times, _, _ = run_on_terminal(cli + ["--help"], env=env)
    start = times[0]
    for argv in (["analyze", str(path)], ["compile", str(studies / "ov7_synthesis.toml")]):
        code, times, end, text = run_on_terminal(cli + argv, env=env)
        assert code == 0, text
        assert times and times[0] <= start + SILENCE_S, (argv, start, times)
        assert longest_silence(times, end) <= SILENCE_S, (argv, times, end, text)
        assert f"{argv[0]}" in text and " s\r" in text, text      # the live line
