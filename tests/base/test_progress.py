"""No silence over 2 s: on a terminal every command shows a live line while it
works (a bar, or the seconds a stage has taken), elsewhere plain lines with no
carriage returns; a new mechanism's compile notice estimates from the last
compile measured here.  No fixed seconds on the wall clock: a command's silences
are measured on its own pace (support.terminal: less the time it waited for a
processor on a loaded machine), and a line that comes after a while is waited
for (a hang guard, not a timing)."""

import logging
import re
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pipeline.base import progress
from pipeline.cli import main
from pipeline.compiler import notice
from support.checkout import child_env
from support.sweep_helpers import copy_of
from support.terminal import (LIVE, SILENCE_S, live_lines, longest_silence,
                              run_on_terminal, said_live)

HANG_GUARD_S = 120.0
on_linux = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a pseudo-terminal")


def wait_for(what, holds):
    """Until ``holds()``: a thread's line comes when the machine gives it a turn."""
    guard = time.monotonic() + HANG_GUARD_S
    while not holds():
        assert time.monotonic() < guard, f"no {what} within {HANG_GUARD_S} s"
        time.sleep(0.01)


def test_plain_lines_off_a_terminal(caplog, monkeypatch):
    monkeypatch.setattr(progress, "QUIET_S", 0.05)
    with caplog.at_level(logging.INFO, logger="pipeline"):
        with progress.ticking("stage") as t:
            t.set("part")
            wait_for("line while the stage works", lambda: "still at work" in caplog.text)
        bar = progress.bar(10, desc="sweep", unit="cand")
        for _ in range(10):
            bar.update(1)
            time.sleep(0.01)
        bar.close()
    text = caplog.text
    assert "stage ..." in text and "stage: part: still at work" in text
    assert "sweep: 10/10 cand" in text and "\r" not in text


def test_a_stage_s_quiet_start_counts_from_the_last_thing_said(caplog, monkeypatch):
    """Two quiet stages in a row (a search's first draw, then its compile notice)
    left a person 2 s in silence: a stage's ``after`` counts from the last thing
    the command said.  Said a moment ago, a stage with a long ``after`` stays
    quiet; said ``after`` ago, the same stage is said at once."""
    long_s = 2 * HANG_GUARD_S
    with caplog.at_level(logging.INFO, logger="pipeline"):
        progress.log.info("header")
        assert time.perf_counter() - progress._said_at[0] < 1.0     # the header noted
        with progress.ticking("quiet stage", after=long_s, say_done=False):
            time.sleep(0.2)
        assert "quiet stage" not in caplog.text
        monkeypatch.setattr(progress, "_said_at", [time.perf_counter() - long_s + 0.1])
        monkeypatch.setattr(progress, "QUIET_S", 3 * HANG_GUARD_S)
        with progress.ticking("second stage", after=long_s, say_done=False):
            wait_for("the stage said at once", lambda: "second stage ..." in caplog.text)


def test_a_bar_on_a_terminal_moves_between_updates(monkeypatch):
    """A chunk that takes long still sees the bar's time redrawn (every
    REDRAW_S), and closing the bar ends its redrawing thread."""
    import io
    import threading
    monkeypatch.setattr(progress, "on_terminal", lambda: True)
    monkeypatch.setattr(progress, "REDRAW_S", 0.05)
    buf = io.StringIO()
    b = progress.bar(10, desc="sweep", unit="cand", file=buf)
    wait_for("redraws", lambda: buf.getvalue().count("\r") >= 4)     # no update meanwhile
    b.close()
    assert b.n == 0
    assert not [t for t in threading.enumerate() if t.name == "pipeline-progress-bar"]


def test_compile_estimate_is_the_last_compile_measured(caplog, monkeypatch, tmp_path):
    """No constant: the notice names the seconds the last compile took on this
    machine (none before the first), and keeps the time of this one where numba
    compiled (a slow load from its cache keeps the last compile's)."""
    record = tmp_path / "last_compile_s.txt"
    monkeypatch.setattr(notice, "compile_record", lambda: record)
    assert notice.last_compile_s() is None
    record.write_text("37.4\n")
    assert notice.last_compile_s() == 37.4
    with caplog.at_level(logging.INFO, logger="pipeline"):
        with notice.compile_notice() as slow_load:     # compiling nothing, until the notice
            wait_for("compile notice", lambda: "first run only" in caplog.text)
            time.sleep(1.05)        # (said within a second of the last line: past one)
    assert "compiling the kernels of this mechanism (first run only; last time 37 s)" \
        in caplog.text
    assert slow_load[0] >= 1.0 and notice.last_compile_s() == 37.4     # kept: no compile
    from numba import njit
    with notice.compile_notice() as took:
        assert njit(lambda x: x + 1)(1) == 2       # a compile (numba's own event)
        time.sleep(1.1)                            # past the notice's one second
    assert took[0] >= 1.1 and notice.last_compile_s() == pytest.approx(took[0], abs=0.05)
    record.write_text("not a number")
    assert notice.last_compile_s() is None


def test_a_live_line_fits_its_terminal_with_its_seconds():
    """A text too long for the terminal is cut, never the seconds that show the
    stage is alive (tqdm cuts the end of a line: on 80 columns the compile
    notice lost its counter and looked hung); the last column stays free."""
    long = "compiling the kernels of this mechanism (first run only; last time 137 s) " * 2
    for width in (80, 40, 20):
        line = progress.live_line(long, 1234.4, width)
        assert len(line) < width and line.endswith("...: 1234 s"), (width, line)
    assert progress.live_line("stage", 3.2, 80) == "stage: 3 s"


# -- every command on a pseudo-terminal ------------------------------------------------

CLI = [sys.executable, "-m", "pipeline.cli"]

# on processor 0 only: a busy loop, and a child that works BUSY_S of its own processor
# time (or sleeps as long) between two prints
_ON_CPU0 = "import os, sys, time\nos.sched_setaffinity(0, {0})\n"
_LOOP = _ON_CPU0 + "print('on', flush=True)\nwhile True:\n    pass\n"
_CHILD = _ON_CPU0 + """print("start", flush=True)
t = time.process_time()
while sys.argv[1] == "works" and time.process_time() - t < float(sys.argv[2]):
    pass
if sys.argv[1] == "sleeps":
    time.sleep(float(sys.argv[2]))
print("end", flush=True)
"""
BUSY_S = 0.6


@on_linux
def test_a_command_s_pace_leaves_out_only_its_waits_for_a_processor():
    """support.terminal's clock: a child that shares processor 0 with two busy
    loops waits about twice as long as it works; its silence while it works is
    its work's (not the waits), and its silence while it sleeps is the sleep's
    (nothing taken off)."""
    loops = [subprocess.Popen([sys.executable, "-c", _LOOP], stdout=subprocess.PIPE, text=True)
             for _ in range(2)]
    try:
        assert [loop.stdout.readline() for loop in loops] == ["on\n"] * 2
        gaps, walls = {}, {}
        for what in ("works", "sleeps"):
            t0 = time.perf_counter()
            code, times, end, text = run_on_terminal(
                [sys.executable, "-c", _CHILD, what, str(BUSY_S)])
            walls[what] = time.perf_counter() - t0
            assert code == 0 and text.split() == ["start", "end"], text
            gaps[what] = times[-1] - times[0]
    finally:
        for loop in loops:
            loop.kill()
            loop.wait()
    assert walls["works"] > 2 * BUSY_S      # it did wait: the loops took their turns
    for what, gap in gaps.items():
        assert BUSY_S * 0.9 <= gap <= BUSY_S + 0.4, (what, gaps, walls)


@pytest.fixture(scope="module")
def help_time():
    """When `pipeline --help` first prints: the interpreter's start and the CLI's
    imports, which every command pays before it can say anything."""
    code, times, _, _ = run_on_terminal(CLI + ["--help"], env=child_env())
    assert code == 0
    return times[0]


@pytest.fixture(scope="module")
def scenes(tmp_path_factory, studies):
    """Two scene results files (no pictures: the commands below draw their own)."""
    d = tmp_path_factory.mktemp("scenes")
    for name in ("ov7_class3", "ov7_base"):
        assert main(["run", str(studies / f"{name}.toml"), "-o", str(d / f"{name}.h5"),
                     "--no-pictures", "-q"]) == 0
    return d / "ov7_class3.h5", d / "ov7_base.h5"


# each command with the smallest input that takes its real code path; {tmp}: the
# case's own folder, {sweep}: the session's sweep (read only), {sweep_copy}: a copy of
# it in {tmp}, {scene}/{scene2}: the scene results files, {studies}: studies/
COMMANDS = {
    "run-scene": "run {studies}/ov7_class3.toml -o {tmp}/scene.h5",
    "run-sweep": "run {studies}/ov7_synthesis.toml -o {tmp}/sweep.h5 --candidates 300",
    "export-scene": "export {scene} --csv {tmp}/csv",
    "export-sweep": "export {sweep} --csv {tmp}/csv",
    "compile": "compile {studies}/ov7_synthesis.toml",
    "analyze": "analyze {sweep_copy}",
    "browse": "browse {sweep}",
    "show-animate": "show {scene} --animate --frames 4 -o {tmp}/a.gif",
    "show-candidate": "show {sweep} --candidate reference -o {tmp}/c.png",
    "report": "report {sweep_copy} --drawings 0 --top 5",
    "tolerance": "tolerance {scene} --samples 8 --no-pictures -o {tmp}/t.h5",
    "compare": "compare {scene} {scene2} -o {tmp}",
    "doctor": "doctor",
}
# `pipeline bench --quick` (20 s) is held to the same limit in tests/test_bench.py


def _argv(case, tmp, synthesis_sweep, scenes, studies):
    sweep_copy = copy_of(synthesis_sweep, tmp, "s.h5") if "{sweep_copy}" in COMMANDS[case] \
        else None
    return [part.format(tmp=tmp, sweep=synthesis_sweep, sweep_copy=sweep_copy,
                        scene=scenes[0], scene2=scenes[1], studies=studies)
            for part in COMMANDS[case].split()]


@on_linux
@pytest.mark.parametrize("case", list(COMMANDS))
def test_command_on_a_terminal_never_falls_silent(case, help_time, synthesis_sweep, scenes,
                                                  studies, tmp_path):
    """The first output comes within 2 s of when `pipeline --help` prints, none
    more than 2 s after the one before, nor the exit more than 2 s after the last:
    seconds of each command's own pace (support.terminal), --help's too."""
    argv = _argv(case, tmp_path, synthesis_sweep, scenes, studies)
    code, times, end, text = run_on_terminal(CLI + argv, env=child_env())
    assert code == 0, text
    assert times and times[0] <= help_time + SILENCE_S, (argv, help_time, times[:3], text)
    assert longest_silence(times, end) <= SILENCE_S, (argv, times, end, text)
    assert all(len(p) < 80 for p in live_lines(text)), text      # its seconds in view
    if case in ("analyze", "compile", "report"):
        assert f"{argv[0]}" in text and " s\r" in text, text      # the live line


@pytest.mark.parametrize("case", ["run-sweep", "compare"])
def test_no_carriage_returns_off_a_terminal(case, synthesis_sweep, scenes, studies, tmp_path):
    """Through a pipe: plain progress lines (the stage and its time), no bars."""
    argv = _argv(case, tmp_path, synthesis_sweep, scenes, studies)
    p = subprocess.run(CLI + argv, env=child_env(), capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stderr
    assert "\r" not in p.stdout + p.stderr, (p.stdout, p.stderr)
    said = {"run-sweep": "sweep: 300/300 cand", "compare": "compare: "}[case]
    assert said in p.stderr, p.stderr



# -- the waits of issue 55: each says what it waits for, counts its seconds, fits 80 columns

def counted(lines, start):
    """The seconds shown by the live lines that begin with ``start``."""
    return sorted({int(LIVE.search(p).group(1)) for p in lines if p.startswith(start)})


WAIT_S = 3       # PIPELINE_CONNECT_TIMEOUT: the test's own timeout, not a measurement


@on_linux
def test_an_unreachable_scheduler_says_where_it_connects_and_counts(studies, tmp_path):
    """A closed local port: the connection's live line names the scheduler and
    how long it waits at most (PIPELINE_CONNECT_TIMEOUT), counts its seconds,
    and the error ends it in one line (it was 20 s of silence)."""
    with socket.socket() as s:          # a port nothing listens on, once closed
        s.bind(("127.0.0.1", 0))
        address = f"tcp://127.0.0.1:{s.getsockname()[1]}"
    out = tmp_path / "s.h5"
    code, times, end, text = run_on_terminal(
        CLI + ["run", str(studies / "ov7_synthesis.toml"), "-o", str(out), "--candidates",
               "300", "--scheduler", address],
        env=child_env(PIPELINE_CONNECT_TIMEOUT=str(WAIT_S)))
    assert code == 2, text
    assert longest_silence(times, end) <= SILENCE_S, (times, end, text)
    start = f"connecting (at most {WAIT_S} s) to the Dask scheduler {address}"
    lines = said_live(text, start)
    assert len(counted(lines, start)) >= 2, lines        # the seconds go on
    assert f"error: cannot reach the Dask scheduler {address} within {WAIT_S} s" in text
    assert not out.exists()


@on_linux
def test_a_resumed_sweep_says_it_reads_its_journal(studies, synthesis_sweep, tmp_path):
    """--resume rebuilds the results file from the journal first: a live line says
    so (and counts the chunks), no silence meanwhile (2.9-5.4 s for a large
    sweep under load)."""
    from pipeline.runs.sweep import run_sweep
    from pipeline.study.reader import load_study
    study = studies / "ov7_synthesis.toml"
    out = tmp_path / "s.h5"
    with pytest.raises(KeyboardInterrupt):
        run_sweep(load_study(study), out, candidates=2000, chunk_size=250, progress=False,
                  stop_after_chunks=5)
    code, times, end, text = run_on_terminal(CLI + ["run", str(study), "-o", str(out),
                                                    "--resume"], env=child_env())
    assert code == 0, text
    assert longest_silence(times, end) <= SILENCE_S, (times, end, text)
    said_live(text, "reading the journal s.h5.parts")
    assert "chunks already done" in text and "reading the journal s.h5.parts: " in text


# the search's own kernels: the optimizer's steps, the front's sorting
SEARCH_KERNELS = ("nsga2_ops", "pareto")


def new_mechanism_cache(tmp_path):
    """The compile caches of a machine that has run other studies, not this one:
    no generated module (this mechanism's kernels all compile), and in numba's
    cache the installation's kernels (pipeline/kernels and the group types',
    copied from the suite's cache as far as it has them) but not the search's
    own (SEARCH_KERNELS), which compile too.  (An empty cache compiled the
    installation's kernels as well: 20-40 s more of this test; a scene on a new
    installation is tests/compiler/test_library.py's.)"""
    from pipeline import group_types, kernels
    from support.caches import copy_compiled
    folders = [Path(kernels.__file__).parent] + [
        d for d in Path(group_types.__file__).parent.iterdir() if (d / "kernels.py").exists()]
    numba_cache = copy_compiled(folders, tmp_path / "numba", skip=SEARCH_KERNELS)
    assert not list(numba_cache.rglob("pareto.*")) and not list(numba_cache.rglob("nsga2_ops.*"))
    return child_env(PIPELINE_CACHE_DIR=str(tmp_path / "modules"),
                     NUMBA_CACHE_DIR=str(numba_cache))


_COUNT = re.compile(r"\|\s*([\d.]+)(k?)/")


@on_linux
@pytest.mark.slow
def test_a_search_s_compile_is_said_before_its_bar(studies, tmp_path):
    """A new mechanism (``new_mechanism_cache``): everything the first generations
    compile (its kernels, the optimizer's steps, the front's sorting) is compiled
    under the compile notice: once the bar shows, it moves past the first generation
    within the silence limit (it stood at 0 % with an ETA for 8 s).  The mechanism:
    a four-bar's (``support.lock_cases``), searched for ten generations (the main
    job's mechanism took 73 s of this test, 60 s of it its compile; the four-bar's
    module compiles in half that)."""
    from pipeline.study.reader import load_study
    from support.lock_cases import fourbar_sweep_study
    study = tmp_path / "fourbar_search.toml"
    study.write_text(fourbar_sweep_study(bounds={"L12": (12.0, 16.0), "L_AB": (38.0, 44.0)})
                     + '\n[search]\nmethod = "nsga2"\npopulation = 100\n'
                     'evaluations = 1000\nseed = 1\n')
    population = load_study(study).search.population
    pieces = []
    code, times, end, text = run_on_terminal(CLI + ["run", str(study), "-o",
                                                    str(tmp_path / "s.h5")],
                                             env=new_mechanism_cache(tmp_path),
                                             pieces=pieces)
    assert code == 0, text
    assert longest_silence(times, end) <= SILENCE_S, (times, end, text)
    said_live(text, "compiling the kernels of this mechanism (first run only")
    bar = [(t, p) for t, p in pieces if "search nsga2" in p]
    shown = bar[0][0]
    past_first = [t for t, p in bar for m in _COUNT.finditer(p)
                  if float(m.group(1)) * (1000 if m.group(2) else 1) > population]
    assert past_first and past_first[0] - shown <= SILENCE_S, (shown, past_first[:3], text)
