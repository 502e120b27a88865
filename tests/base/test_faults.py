"""Faults and hostile inputs: a full disk, a read-only folder, kill -9, a second
run on the same file, damaged files, hostile names and impossible bounds.
After each fault the earlier result reads back bit for bit, and the command
line says what happened in one line (exit code 2, no traceback)."""

import errno
import os
import re
import shutil
from contextlib import contextmanager
from pathlib import Path

import h5py
import pytest

import pipeline.base.files as files
from pipeline.cli import main
from support.faults import digest, one_line_error
from pipeline.study.reader import load_study
from pipeline.base.files import RunLock
from pipeline.runs.sweep import run_sweep
from pipeline.results.journal import Journal

ROOT = Path(__file__).resolve().parents[2]
N = 2000


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory, studies):
    study = load_study(studies / "ov7_synthesis.toml")
    out = tmp_path_factory.mktemp("faults") / "sweep.h5"
    run_sweep(study, out, candidates=N, chunk_size=500, progress=False)
    return out


@pytest.fixture
def sweep_copy(sweep_file, tmp_path):
    dst = tmp_path / "sweep.h5"
    shutil.copy(sweep_file, dst)
    return dst


def study_variant(studies, tmp_path, name, edits, file_name=None):
    """A copy of a shipped study with text replacements (old, new)."""
    text = (studies / name).read_text()
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    p = tmp_path / (file_name or name)
    p.write_text(text)
    return p


@contextmanager
def nothing_compiled(monkeypatch):
    """The block refuses before any kernel is built ("at once": no compile,
    no evaluation, whatever the machine's speed)."""
    import pipeline.runs.sweep as sw

    def built(*a, **k):
        raise AssertionError("a kernel was built before the refusal")
    with monkeypatch.context() as m:
        m.setattr(sw, "build_problem", built)
        yield


def full_disk(monkeypatch, after=0):
    """Every write through the atomic writer fails with ENOSPC (``after``
    writes of the temporary file succeed first: the failure comes midway)."""
    calls = {"n": 0}
    real_fsync = files._fsync

    def fsync(path):
        calls["n"] += 1
        if calls["n"] > after:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        return real_fsync(path)
    monkeypatch.setattr(files, "_fsync", fsync)


# ------------------------------------------------------------ full disk, read-only folder
def test_analyze_on_a_full_disk_keeps_the_sweep(sweep_copy, monkeypatch, capsys):
    before = digest(sweep_copy)
    full_disk(monkeypatch)
    assert main(["analyze", str(sweep_copy)]) == 2
    one_line_error(capsys, "No space left on device")
    assert digest(sweep_copy) == before
    assert not [p for p in sweep_copy.parent.iterdir() if ".partial" in p.name]


@pytest.mark.parametrize("k", [1, 2, 5, 9, 14])
def test_analyze_failing_midway_in_hdf5_keeps_the_sweep(sweep_copy, monkeypatch, capsys, k):
    """The disk fills while HDF5 writes the analysis (inside h5py, at its k-th
    dataset, not at the flush)."""
    import pipeline.analysis.fronts as an
    before = digest(sweep_copy)
    real = an.put
    count = {"n": 0}

    def put(*a, **kw):
        count["n"] += 1
        if count["n"] == k:
            raise OSError(errno.ENOSPC, "Unable to write dataset (errno = 28, error message = "
                                        "'No space left on device')")
        return real(*a, **kw)
    monkeypatch.setattr(an, "put", put)
    assert main(["analyze", str(sweep_copy)]) == 2
    one_line_error(capsys, "No space left on device")
    assert count["n"] == k
    assert digest(sweep_copy) == before


def test_report_on_a_full_disk_keeps_the_sweep(sweep_copy, monkeypatch, capsys):
    before = digest(sweep_copy)
    full_disk(monkeypatch)
    assert main(["report", str(sweep_copy)]) == 2      # it analyses first: that write fails
    one_line_error(capsys, "No space left on device")
    assert digest(sweep_copy) == before
    assert not list(sweep_copy.parent.glob("*_report.html"))


def test_scene_overwritten_on_a_full_disk_keeps_the_old_result(studies, tmp_path, monkeypatch,
                                                               capsys):
    out = tmp_path / "base.h5"
    assert main(["run", str(studies / "ov7_base.toml"), "-o", str(out), "-q"]) == 0
    before = {p.name: digest(p) for p in tmp_path.iterdir()}
    full_disk(monkeypatch)
    assert main(["run", str(studies / "ov7_base.toml"), "-o", str(out), "-q",
                 "--overwrite"]) == 2
    one_line_error(capsys, "No space left on device", str(out.parent))
    assert {p.name: digest(p) for p in tmp_path.iterdir()} == before
    monkeypatch.undo()
    assert main(["export", str(out), "--csv", str(tmp_path / "csv"), "-q"]) == 0


def test_read_only_folder_is_one_line(studies, tmp_path, monkeypatch, capsys):
    """A read-only file system refuses the rename (root ignores chmod, so the
    refusal is injected where the operating system would give it)."""
    def refuse(src, dst):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(dst))
    monkeypatch.setattr(files.os, "replace", refuse)
    out = tmp_path / "ro" / "base.h5"
    assert main(["run", str(studies / "ov7_base.toml"), "-o", str(out), "-q"]) == 2
    one_line_error(capsys, "Read-only file system", "base.h5")
    assert not out.exists()


def test_export_into_a_full_disk_is_one_line(studies, tmp_path, monkeypatch, capsys):
    out = tmp_path / "base.h5"
    assert main(["run", str(studies / "ov7_base.toml"), "-o", str(out), "-q",
                 "--no-pictures"]) == 0
    full_disk(monkeypatch)
    assert main(["export", str(out), "--csv", str(tmp_path / "csv"), "-q"]) == 2
    one_line_error(capsys, "No space left on device", "points.csv")
    assert not list((tmp_path / "csv").glob("*.csv"))


# kill -9 at named points of the write path: tests/base/test_fault_injection.py


# ------------------------------------------------------------ runs and journals
def test_second_run_on_the_same_file_is_refused_at_once(studies, tmp_path, capsys, monkeypatch):
    out = tmp_path / "s.h5"
    with RunLock(out), nothing_compiled(monkeypatch):
        assert main(["run", str(studies / "ov7_synthesis.toml"), "-o", str(out),
                     "--candidates", "100", "-q"]) == 2
    one_line_error(capsys, "another run is writing")
    assert not out.exists()


def test_unreachable_scheduler_leaves_nothing(studies, tmp_path, monkeypatch, capsys):
    import pipeline.runs.lifecycle as lifecycle
    monkeypatch.setattr(lifecycle, "CONNECT_TIMEOUT", "1s")
    out = tmp_path / "s.h5"
    assert main(["run", str(studies / "ov7_synthesis.toml"), "-o", str(out), "--candidates",
                 "100", "--scheduler", "tcp://127.0.0.1:9", "-q"]) == 2
    one_line_error(capsys, "cannot reach the Dask scheduler")
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith(".")) == []
    # and the retry is not blocked
    assert main(["run", str(studies / "ov7_synthesis.toml"), "-o", str(out), "--candidates",
                 "100", "-q"]) == 0


def test_damaged_journal_chunk_is_one_line(studies, tmp_path, capsys):
    study = load_study(studies / "ov7_synthesis.toml")
    out = tmp_path / "s.h5"
    with pytest.raises(KeyboardInterrupt):
        run_sweep(study, out, candidates=1000, chunk_size=250, progress=False,
                  stop_after_chunks=2)
    chunk = sorted((tmp_path / "s.h5.parts").glob("chunk_*.npz"))[0]
    chunk.write_bytes(chunk.read_bytes()[:100])
    assert main(["run", str(studies / "ov7_synthesis.toml"), "-o", str(out), "--candidates",
                 "1000", "--chunk-size", "250", "--resume", "-q"]) == 2
    one_line_error(capsys, "damaged journal chunk", chunk.name)


def test_a_killed_runs_journal_temporaries_go_once_as_the_run_resumes(studies, tmp_path,
                                                                        monkeypatch):
    study = load_study(studies / "ov7_synthesis.toml")
    out = tmp_path / "s.h5"
    with pytest.raises(KeyboardInterrupt):
        run_sweep(study, out, candidates=1000, chunk_size=250, progress=False,
                  stop_after_chunks=2)
    parts = tmp_path / "s.h5.parts"
    dead = parts / ".chunk_0000002.999999999.tmp-ab_12x.partial.npz"    # a killed writer's
    live = parts / f".chunk_0000003.{os.getpid()}.tmp-cd_34y.partial.npz"  # a live one's
    other = parts / "chunk_0000009.npz.keep"                            # not a temporary
    for p in (dead, live, other):
        p.write_bytes(b"x")
    scans, seen = [], []
    real = files._remove_stale
    monkeypatch.setattr(files, "_remove_stale", lambda t: (scans.append(t), real(t)))
    clear = Journal.clear_stale

    def cleared(journal):     # (the folder itself goes once the run completes)
        clear(journal)
        seen.append([p.exists() for p in (dead, live, other)])
    monkeypatch.setattr(Journal, "clear_stale", cleared)
    run_sweep(study, out, candidates=1000, chunk_size=250, progress=False, resume=True)
    assert seen == [[False, True, True]]
    # each chunk written without a look through the folder for its own stale files
    assert not [t for t in scans if t.parent == parts]
    with h5py.File(out, "r") as f:
        assert f["candidates/status"].shape == (1000,)


def test_damaged_results_file_is_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.h5"
    bad.write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 64)
    for cmd in (["browse", str(bad)], ["show", str(bad), "--candidate", "0"],
                ["analyze", str(bad)], ["export", str(bad), "--csv", str(tmp_path)]):
        assert main(cmd) == 2, cmd
        one_line_error(capsys, "bad.h5")


@pytest.mark.parametrize("damage", ["drop status", "truncate params", "drop metric"])
def test_results_file_missing_data_is_one_line(sweep_copy, capsys, damage):
    with h5py.File(sweep_copy, "r+") as f:
        if damage == "drop status":
            del f["candidates/status"]
        elif damage == "truncate params":
            p = f["candidates/params"][:10]
            del f["candidates/params"]
            f["candidates/params"] = p
        else:
            del f["metrics/dwell_error"]
    for cmd in (["browse", str(sweep_copy)], ["show", str(sweep_copy), "--candidate", "0"],
                ["analyze", str(sweep_copy)], ["report", str(sweep_copy)]):
        rc = main(cmd)
        if damage == "drop metric" and rc == 0:    # a command that does not need it
            capsys.readouterr()
            continue
        assert rc == 2, cmd
        one_line_error(capsys, "sweep.h5", "damaged")


def test_bad_stored_study_is_blamed_on_the_results_file(sweep_copy, capsys):
    with h5py.File(sweep_copy, "r+") as f:
        f.attrs["study_toml"] = f.attrs["study_toml"].replace('kind = "sweep"', 'kind = "swep"')
    assert main(["show", str(sweep_copy), "--candidate", "0"]) == 2
    err = one_line_error(capsys, f"{sweep_copy} (the study stored from", "study.kind")
    assert not err.split("error: ")[1].startswith("studies/")


# ------------------------------------------------------------ where files go
@pytest.mark.parametrize("name", ["../../escaped", "/tmp/abs_escaped", ""])
def test_hostile_study_names_write_only_under_results(studies, tmp_path, monkeypatch, name):
    study = study_variant(studies, tmp_path, "ov7_base.toml",
                          [('name = "ov7_base"', f'name = "{name}"')], file_name="hostile.toml")
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    assert main(["run", str(study), "-q"]) == 0
    written = sorted(str(p.relative_to(work)) for p in work.rglob("*") if p.is_file())
    assert written and all(w.startswith("results/hostile") for w in written), written
    assert not Path("/tmp/abs_escaped.h5").exists()
    assert not (tmp_path / "escaped.h5").exists()


def test_hostile_dynamics_case_name_is_refused(studies, tmp_path, capsys):
    study = study_variant(studies, tmp_path, "takeup_dynamics.toml",
                          [('name = "runup"', 'name = "../../runup"')])
    assert main(["run", str(study), "-o", str(tmp_path / "r" / "t.h5"), "-q"]) == 2
    one_line_error(capsys, "dynamics.cases[0].name")
    assert not list(tmp_path.rglob("*.png")) and not list(tmp_path.parent.glob("runup*"))


# ------------------------------------------------------------ inputs against physics
@pytest.mark.parametrize("edits, needles", [
    ([('L12 = { param = "crank.length" }',
       'L12 = { param = "crank.length", min = -60.0, max = 60.0 }')],
     ["sweep.variables.L12.min", "a length (> 0)", "-60"]),
    ([('L12 = { param = "crank.length" }',
       'L12 = { param = "crank.length", min = 0.0, max = 60.0 }')],
     ["sweep.variables.L12.min", "a length (> 0)"]),
    ([("spread = 0.2 ", "spread = 5.0 ")], ["sweep.spread", "a length (> 0)"]),
    ([('"crank 1-2" = "crank.length"', '"crank 1-2" = "P1.x"')],
     ["sweep.mass_model", "reference value", "is 0"]),
    ([("candidates = 250000 ", "candidates = 1000000000000 ")],
     ["sweep.candidates", "at most 1,000,000,000"]),
    ([("positions = 360 ", "positions = 1000000000 ")], ["sweep.positions", "at most 100,000"]),
    ([("chunk_size = 10000 ", "chunk_size = 100000000 ")], ["sweep.chunk_size", "at most"]),
    ([("seed = 20261121", "seed = 100000000000000000000")], ["sweep.seed", "64-bit integer"]),
    ([("spread = 0.2 ", "spread = 1e400 ")], ["spread"]),
    ([("stroke = [11.0, 15.0]", "stroke = [11.0, 1" + "0" * 400 + "]")],
     ["sweep.constraints.stroke", "64-bit float"]),
])
def test_impossible_sweeps_are_refused_at_once(studies, tmp_path, capsys, monkeypatch, edits,
                                               needles):
    study = study_variant(studies, tmp_path, "ov7_synthesis.toml", edits)
    with nothing_compiled(monkeypatch):
        assert main(["run", str(study), "-o", str(tmp_path / "x.h5"), "-q"]) == 2
    one_line_error(capsys, str(study), *needles)
    assert not (tmp_path / "x.h5").exists()


def test_too_many_candidates_on_the_command_line(studies, tmp_path, capsys, monkeypatch):
    with nothing_compiled(monkeypatch):
        assert main(["run", str(studies / "ov7_synthesis.toml"), "-o", str(tmp_path / "x.h5"),
                     "--candidates", str(10 ** 12), "-q"]) == 2
    one_line_error(capsys, "--candidates", "1,000,000,000")


def test_scene_positions_limit(studies, tmp_path, capsys):
    text = (studies / "ov7_base.toml").read_text()
    m = re.search(r"^dense_positions = \d+", text, re.M)
    if m:
        text = text.replace(m.group(0), "dense_positions = 1000000000")
    else:
        text = text.replace("[output]\n", "[output]\ndense_positions = 1000000000\n")
    study = tmp_path / "big.toml"
    study.write_text(text)
    assert main(["run", str(study), "-o", str(tmp_path / "x.h5"), "-q"]) == 2
    one_line_error(capsys, "dense_positions", "at most 100,000")


# ------------------------------------------------------------ found in review
def test_overwrite_that_fails_before_its_first_chunk_keeps_the_old_file(studies, tmp_path,
                                                                         monkeypatch):
    import pipeline.runs.sweep as sw
    study = load_study(studies / "ov7_synthesis.toml")
    out = tmp_path / "s.h5"
    run_sweep(study, out, candidates=300, progress=False)
    before = digest(out)

    def interrupted(self):
        raise KeyboardInterrupt       # Ctrl-C while the new run compiles
    monkeypatch.setattr(sw.SweepFile, "create", interrupted)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(study, out, candidates=400, progress=False, overwrite=True)
    assert digest(out) == before
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.endswith(".lock")) == ["s.h5"]
    monkeypatch.undo()
    run_sweep(study, out, candidates=400, progress=False, overwrite=True)
    with h5py.File(out, "r") as f:
        assert f["candidates/status"].shape == (400,)
    assert not list(tmp_path.glob(".s.h5.replaced"))


def test_stale_cleanup_never_touches_another_files_temporary(tmp_path):
    other = tmp_path / ".sweep.2.999999999.partial.h5"     # sweep.2.h5's, pid 999999999
    other.write_bytes(b"x")
    bracket = tmp_path / ".run1.999999999.partial.h5"      # run1.h5's, not run[1].h5's
    bracket.write_bytes(b"x")
    files.write_text(tmp_path / "sweep.h5", "a")
    files.write_text(tmp_path / "run[1].h5", "b")
    assert other.exists() and bracket.exists()
    files.write_text(tmp_path / "run1.h5", "c")            # its own stale file goes
    assert not bracket.exists()


def test_analysis_waits_for_no_one_while_a_run_writes(sweep_copy, capsys):
    before = digest(sweep_copy)
    with RunLock(sweep_copy):
        assert main(["analyze", str(sweep_copy)]) == 2
    one_line_error(capsys, "a sweep or another analysis is writing this file")
    assert digest(sweep_copy) == before


def test_h5py_error_texts_name_the_target_file():
    e = OSError("Unable to synchronously create file (unable to open file: name = "
                "'/x/.out.123.partial.h5', errno = 28, error message = 'No space left on "
                "device', flags = 13, o_flags = 242)")
    assert files.os_error_text(e) == "/x/out.h5: No space left on device"


def test_names_and_units_never_become_markup_in_the_report(studies, tmp_path):
    study = study_variant(studies, tmp_path, "ov7_synthesis.toml",
                          [('L12 = { param = "crank.length" }',
                            'L12 = { param = "crank.length", units = "<img src=x onerror=alert(1)>" }')])
    out = tmp_path / "s.h5"
    assert main(["run", str(study), "-o", str(out), "--candidates", "600", "-q"]) == 0
    assert main(["report", str(out), "-o", str(tmp_path / "r.html"), "-q", "--drawings", "1"]) == 0
    page = (tmp_path / "r.html").read_text()
    from pipeline.views.page import unpacked
    from support.html_page import packed_element
    data = packed_element(page, "explorer-data")        # packed: base64 holds no markup
    text = unpacked(data).decode("utf-8")               # and the JSON inside escapes it
    assert "<" not in data + text and ">" not in data + text and "\\u003cimg" in text
    assert "<img src=x" not in page
