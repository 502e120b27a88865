"""Fault injection, part two: failed replacements, planted links, a real full
disk (a small tmpfs), damaged bytes, and kill -9 at named points of the write
path (``files.fault_point``: the child process kills itself there, so the
test knows the point was reached).  After each fault nothing earlier is lost,
nothing runs that should not, and the command line ends in one line naming
the file, exit code 2."""

import errno
import os
import shutil
import signal
import subprocess
import sys
import tracemalloc
from contextlib import contextmanager
from pathlib import Path

import h5py
import numpy as np
import pytest

import pipeline
import pipeline.base.files as files
import pipeline.runs.lifecycle as lifecycle
import pipeline.runs.sweep as sw
from pipeline.cli import main
from support.faults import digest, one_line_error
from pipeline.base.errors import ResultsError
from pipeline.base.files import RunLock
from pipeline.study.reader import load_study
from pipeline.runs.sweep import build_problem, run_sweep
from pipeline.results.sweep_file import SweepFile

ROOT = Path(__file__).resolve().parents[2]


def cli(*args, env=None, cwd=None):
    """`pipeline ARGS` in a child process: (exit code, stderr)."""
    e = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    e.update(env or {})
    p = subprocess.run([sys.executable, "-m", "pipeline.cli", *map(str, args)], env=e,
                       cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                       timeout=600)
    return p.returncode, p.stderr.strip()


def hidden(folder):
    return sorted(p.name for p in Path(folder).iterdir() if p.name.startswith("."))


@pytest.fixture(scope="module")
def synthesis(studies):
    return load_study(studies / "ov7_synthesis.toml")


@pytest.fixture
def sweep(synthesis_sweep, tmp_path):
    """A copy of a finished sweep (the session's): the earlier result every
    replacement must keep.  (A sweep of this module's own compiled the main job's
    module again beside the session's sweep in a cold cache.)"""
    dst = tmp_path / "s.h5"
    shutil.copy(synthesis_sweep, dst)
    return dst


def assert_kept(path, before):
    """The earlier file is there under its own name, bit for bit, and no
    hidden copy of it waits to be deleted by a later run."""
    assert digest(path) == before
    assert not [n for n in hidden(path.parent) if n.endswith(".replaced")]


# ------------------------------------------------------------ failed replacements
def test_overwrite_on_a_missing_gpu_keeps_the_earlier_file(sweep, studies, capsys):
    before = digest(sweep)
    rc = main(["run", str(studies / "ov7_synthesis.toml"), "-o", str(sweep), "--candidates",
               "300", "--overwrite", "--device", "gpu", "-q"])
    assert rc == 2
    capsys.readouterr()
    assert_kept(sweep, before)
    assert not (sweep.parent / "s.h5.parts").exists()
    # the next plain run refuses and deletes nothing
    assert main(["run", str(studies / "ov7_synthesis.toml"), "-o", str(sweep), "--candidates",
                 "300", "-q"]) == 2
    one_line_error(capsys, sweep, "already exists")
    assert_kept(sweep, before)


def test_overwrite_with_an_unreachable_scheduler_keeps_the_earlier_file(sweep, studies, capsys,
                                                                       monkeypatch):
    monkeypatch.setattr(lifecycle, "CONNECT_TIMEOUT", "1s")
    before = digest(sweep)
    assert main(["run", str(studies / "ov7_synthesis.toml"), "-o", str(sweep), "--candidates",
                 "300", "--overwrite", "--scheduler", "tcp://127.0.0.1:9", "-q"]) == 2
    one_line_error(capsys, "cannot reach the Dask scheduler")
    assert_kept(sweep, before)
    assert sorted(p.name for p in sweep.parent.iterdir()) == ["s.h5"]


def test_overwrite_interrupted_after_two_chunks_keeps_the_earlier_file(sweep, synthesis,
                                                                       tmp_path):
    before = digest(sweep)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(synthesis, sweep, candidates=800, chunk_size=200, progress=False,
                  overwrite=True, stop_after_chunks=2)
    assert_kept(sweep, before)
    parts = sweep.parent / "s.h5.parts"
    assert len(list(parts.glob("chunk_*.npz"))) == 2
    assert (parts / "replacement.h5").exists()      # the new file grows beside the journal
    # a plain run neither continues nor deletes: it says how to go on
    with pytest.raises(ResultsError, match="--resume"):
        run_sweep(synthesis, sweep, candidates=800, chunk_size=200, progress=False)
    assert_kept(sweep, before)
    # --resume completes the replacement, and only then is the earlier file replaced
    run_sweep(synthesis, sweep, progress=False, resume=True)
    fresh = tmp_path / "fresh.h5"
    run_sweep(synthesis, fresh, candidates=800, chunk_size=200, progress=False)
    with h5py.File(sweep, "r") as a, h5py.File(fresh, "r") as b:
        assert a.attrs["complete"] and a["candidates/status"].shape == (800,)
        for name in ("candidates/params", "candidates/status", "metrics/dwell_error",
                     "metrics/peak_reaction"):
            np.testing.assert_array_equal(a[name][()], b[name][()])
    assert not parts.exists()
    assert hidden(sweep.parent) == []


def test_overwrite_on_a_disk_that_fills_midway_keeps_the_earlier_file(sweep, studies, capsys,
                                                                      monkeypatch):
    before = digest(sweep)
    real, calls = sw.Journal.save, {"n": 0}

    def save(self, *a, **k):
        calls["n"] += 1
        if calls["n"] == 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC),
                          str(self.dir / "chunk_0000001.npz"))
        return real(self, *a, **k)
    monkeypatch.setattr(sw.Journal, "save", save)
    assert main(["run", str(studies / "ov7_synthesis.toml"), "-o", str(sweep), "--candidates",
                 "800", "--chunk-size", "200", "--overwrite", "-q", "-j", "1"]) == 2
    one_line_error(capsys, "No space left on device", "s.h5.parts")
    assert calls["n"] == 2
    assert_kept(sweep, before)


def test_overwrite_killed_between_chunks_keeps_the_earlier_file(sweep, studies):
    before = digest(sweep)
    rc, err = cli("run", studies / "ov7_synthesis.toml", "-o", sweep, "--candidates", 800,
                  "--chunk-size", 200, "--overwrite", "-q",
                  env={files.FAULT_VARIABLE: "chunk-written"})
    assert rc == -signal.SIGKILL, err
    parts = sweep.parent / "s.h5.parts"
    assert len(list(parts.glob("chunk_*.npz"))) == 1     # the point was reached
    assert_kept(sweep, before)
    rc, err = cli("run", studies / "ov7_synthesis.toml", "-o", sweep, "--resume", "-q")
    assert rc == 0, err
    with h5py.File(sweep, "r") as f:
        assert f.attrs["complete"] and f["candidates/status"].shape == (800,)
    assert hidden(sweep.parent) == []


# ------------------------------------------------------------ scenes: --overwrite and the lock
def test_a_scene_replaces_only_with_overwrite(studies, tmp_path, capsys):
    out = tmp_path / "base.h5"
    assert main(["run", str(studies / "ov7_base.toml"), "-o", str(out), "-q",
                 "--no-pictures"]) == 0
    before = digest(out)
    assert main(["run", str(studies / "ov7_base.toml"), "-o", str(out), "-q",
                 "--no-pictures"]) == 2
    one_line_error(capsys, out, "already exists", "--overwrite")
    assert digest(out) == before
    assert main(["run", str(studies / "ov7_base.toml"), "-o", str(out), "-q", "--no-pictures",
                 "--overwrite"]) == 0
    with h5py.File(out, "r") as f:
        assert f.attrs["kind"] == "scene"
    assert hidden(tmp_path) == []           # the lock is gone with the run


def test_a_scene_never_lands_on_a_sweep_being_written(sweep, studies, capsys):
    before = digest(sweep)
    assert main(["run", str(studies / "warp_feed_fourbar.toml"), "-o", str(sweep), "-q"]) == 2
    one_line_error(capsys, sweep, "already exists")
    with RunLock(sweep):                    # a sweep is writing it
        assert main(["run", str(studies / "warp_feed_fourbar.toml"), "-o", str(sweep), "-q",
                     "--overwrite"]) == 2
    one_line_error(capsys, sweep, "another run is writing")
    assert digest(sweep) == before


def test_a_scene_never_lands_on_an_interrupted_sweep(synthesis, studies, tmp_path, capsys):
    out = tmp_path / "s.h5"
    with pytest.raises(KeyboardInterrupt):
        run_sweep(synthesis, out, candidates=400, chunk_size=200, progress=False,
                  stop_after_chunks=1)
    assert main(["run", str(studies / "ov7_base.toml"), "-o", str(out), "-q",
                 "--overwrite"]) == 2
    one_line_error(capsys, out, "unfinished sweep")
    run_sweep(synthesis, out, progress=False, resume=True)       # the sweep goes on
    with h5py.File(out, "r") as f:
        assert f.attrs["kind"] == "sweep" and f.attrs["complete"]


def test_a_scene_killed_before_its_rename_keeps_the_earlier_result(studies, tmp_path):
    out = tmp_path / "base.h5"
    assert main(["run", str(studies / "ov7_base.toml"), "-o", str(out), "-q",
                 "--no-pictures"]) == 0
    before = digest(out)
    rc, err = cli("run", studies / "ov7_base.toml", "-o", out, "--overwrite", "--no-pictures",
                  "-q", env={files.FAULT_VARIABLE: "before-rename:base.h5"})
    assert rc == -signal.SIGKILL, err
    partial = [n for n in hidden(tmp_path) if n.endswith(".partial.h5")]
    assert len(partial) == 1 and (tmp_path / partial[0]).stat().st_size > 0   # reached
    assert digest(out) == before
    # the next run clears the killed writer's copy
    assert main(["run", str(studies / "ov7_base.toml"), "-o", str(out), "-q", "--no-pictures",
                 "--overwrite"]) == 0
    assert hidden(tmp_path) == []


# ------------------------------------------------------------ planted links
def test_temporary_names_are_new_files_no_one_could_plant(tmp_path):
    target = tmp_path / "x.h5"
    victim = tmp_path / "victim"
    victim.write_text("precious")
    # the names the writer used to take: .x.<pid>.partial.h5
    (tmp_path / f".x.{os.getpid()}.partial.h5").symlink_to(victim)
    a, b = files.temporary_beside(target), files.temporary_beside(target)
    assert a != b and a.parent == b.parent == tmp_path
    for t in (a, b):
        assert t.is_file() and not t.is_symlink() and t.stat().st_size == 0
        assert t.name.startswith(f".x.{os.getpid()}.tmp-") and t.name.endswith(".partial.h5")
    files.write_text(target, "new")
    assert victim.read_text() == "precious" and target.read_text() == "new"


def test_a_planted_link_at_the_old_temporary_name_is_not_followed(studies, tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    out = tmp_path / "base.h5"
    (tmp_path / f".base.{os.getpid()}.partial.h5").symlink_to(victim)
    assert main(["run", str(studies / "ov7_base.toml"), "-o", str(out), "-q",
                 "--no-pictures"]) == 0
    assert victim.read_text() == "precious"
    with h5py.File(out, "r") as f:
        assert f.attrs["kind"] == "scene"


def test_a_planted_journal_link_is_refused(studies, tmp_path, capsys):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    out = tmp_path / "s.h5"
    (tmp_path / "s.h5.parts").symlink_to(elsewhere)
    assert main(["run", str(studies / "ov7_synthesis.toml"), "-o", str(out), "--candidates",
                 "100", "-q"]) == 2
    one_line_error(capsys, "s.h5.parts", "symbolic link")
    assert list(elsewhere.iterdir()) == [] and not out.exists()


def test_a_planted_lock_link_is_refused(studies, tmp_path, capsys):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    out = tmp_path / "base.h5"
    (tmp_path / ".base.h5.lock").symlink_to(victim)
    assert main(["run", str(studies / "ov7_base.toml"), "-o", str(out), "-q"]) == 2
    one_line_error(capsys, ".base.h5.lock", "symbolic link")
    assert victim.read_text() == "precious" and not out.exists()


def test_analyzing_a_link_updates_the_file_it_leads_to(sweep, tmp_path):
    link = tmp_path / "link.h5"
    link.symlink_to(sweep)
    assert main(["analyze", str(link), "-q"]) == 0
    assert link.is_symlink() and link.resolve() == sweep.resolve()
    with h5py.File(sweep, "r") as f:
        assert f["analysis"].attrs["complete"]
    assert hidden(tmp_path) == []


def test_no_lock_file_is_left_beside_any_output(sweep, studies, tmp_path):
    assert main(["run", str(studies / "ov7_base.toml"), "-o", str(tmp_path / "b.h5"),
                 "-q"]) == 0
    assert main(["analyze", str(sweep), "-q"]) == 0
    assert main(["run", str(studies / "ov7_synthesis.toml"), "-o", str(tmp_path / "n.h5"),
                 "--candidates", "100", "-q"]) == 0
    assert hidden(tmp_path) == []


def test_the_lock_still_excludes_after_its_file_was_removed(tmp_path):
    out = tmp_path / "s.h5"
    with RunLock(out):
        pass                                # removed by the run that held it
    with RunLock(out):
        with pytest.raises(ResultsError, match="another run is writing"):
            with RunLock(out):
                pass


# ------------------------------------------------------------ a real full disk
@contextmanager
def small_disk(folder: Path, size: str):
    """A tmpfs of ``size`` mounted on ``folder`` (root only)."""
    folder.mkdir(parents=True, exist_ok=True)
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)],
                       capture_output=True, text=True)
    if r.returncode:
        pytest.fail(f"mount tmpfs failed: {r.stderr.strip()}")
    try:
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], check=False)


needs_root = pytest.mark.skipif(
    os.geteuid() != 0 or shutil.which("mount") is None,
    reason="a real full disk is a small tmpfs, which only root can mount (CI runs as root)")


@needs_root
@pytest.mark.parametrize("size", ["12m", "3m", "1m"])
def test_a_sweep_on_a_full_disk_ends_in_one_line(studies, tmp_path, size):
    """12 MiB: the disk fills after some chunks; 3 MiB: before HDF5 writes the
    first (it used to end in a segfault: a write HDF5 meets a full disk in is now
    refused before it starts, storage.room_for); 1 MiB: while the journal saves
    a chunk."""
    with small_disk(tmp_path / "disk", size) as disk:
        out = disk / "s.h5"
        rc, err = cli("run", studies / "ov7_synthesis.toml", "-o", out, "--candidates", 200000,
                      "-q")
        assert rc == 2, err
        assert len(err.splitlines()) == 1 and "Traceback" not in err, err
        assert "No space left on device" in err and str(disk) in err, err


@needs_root
def test_a_search_on_a_full_disk_ends_in_one_line(studies, tmp_path):
    text = (studies / "ov7_search.toml").read_text()
    assert "evaluations = 20000" in text
    study = tmp_path / "search.toml"
    study.write_text(text.replace("evaluations = 20000", "evaluations = 100000"))
    with small_disk(tmp_path / "disk", "2m") as disk:
        rc, err = cli("run", study, "-o", disk / "s.h5", "-q")
        assert rc == 2, err
        assert len(err.splitlines()) == 1 and "Traceback" not in err, err
        assert "No space left on device" in err and str(disk) in err, err


@needs_root
def test_a_scene_on_a_full_disk_keeps_the_earlier_result(studies, tmp_path):
    with small_disk(tmp_path / "disk", "2m") as disk:
        out = disk / "base.h5"
        rc, err = cli("run", studies / "ov7_base.toml", "-o", out, "--no-pictures", "-q")
        assert rc == 0, err
        before = digest(out)
        free = shutil.disk_usage(disk).free
        (disk / "filler").write_bytes(b"\0" * (free - 64 * 1024))
        rc, err = cli("run", studies / "ov7_base.toml", "-o", out, "--no-pictures", "-q",
                      "--overwrite")
        assert rc == 2, err
        assert len(err.splitlines()) == 1 and "Traceback" not in err, err
        assert "No space left on device" in err and "base.h5" in err, err
        assert digest(out) == before
        assert sorted(p.name for p in disk.iterdir()) == ["base.h5", "filler"]


@needs_root
@pytest.mark.parametrize("command", ["report", "export", "show", "animate"])
def test_outputs_onto_a_full_disk_name_the_file(sweep, tmp_path, command):
    assert main(["analyze", str(sweep), "-q"]) == 0
    with small_disk(tmp_path / "disk", "64k") as disk:
        args = {"report": ["report", sweep, "-o", disk / "r.html", "--drawings", 0],
                "export": ["export", sweep, "--csv", disk / "tables"],
                "show": ["show", sweep, "--candidate", "reference", "-o", disk / "c.png"],
                "animate": ["show", sweep, "--candidate", "reference", "--animate",
                            "--frames", 24, "-o", disk / "c.gif"]}[command]
        rc, err = cli(*args, "-q")
        assert rc == 2, err
        assert len(err.splitlines()) == 1 and "Traceback" not in err, err
        assert "No space left on device" in err and str(disk) in err, err
        assert [p.name for p in disk.rglob("*") if p.is_file()] == []


# ------------------------------------------------------------ damaged bytes
def flip(path, offset, count=200):
    data = bytearray(Path(path).read_bytes())
    for i in range(offset, min(offset + count, len(data))):
        data[i] ^= 0xFF
    Path(path).write_bytes(bytes(data))


def damage(path, where):
    """200 flipped bytes in the object header of the group ``candidates`` (its
    links), or in the compressed first chunk of ``candidates/params`` (the
    designs, which every command reads)."""
    with h5py.File(path, "r") as f:
        if where == "header":
            offset = h5py.h5o.get_info(f["candidates"].id).addr
        else:
            offset = f["candidates/params"].id.get_chunk_info(0).byte_offset
    flip(path, offset)


@pytest.mark.parametrize("where", ["header", "chunk"])
def test_flipped_bytes_end_in_one_line_everywhere(sweep, tmp_path, capsys, where):
    damage(sweep, where)
    for cmd in (["browse", sweep], ["show", sweep, "--candidate", "0", "-o", tmp_path / "c.png"],
                ["analyze", sweep], ["report", sweep, "-o", tmp_path / "r.html"],
                ["export", sweep, "--csv", tmp_path / "t"],
                ["show", sweep, "--candidate", "0", "--animate", "--frames", "12",
                 "-o", tmp_path / "c.gif"]):
        assert main([str(c) for c in cmd]) == 2, cmd
        one_line_error(capsys, sweep)
    with pytest.raises(ResultsError, match="s.h5"):
        pipeline.open(sweep)


def test_a_feasible_store_file_without_its_candidate_index_is_refused(synthesis, tmp_path,
                                                                      capsys):
    out = tmp_path / "f.h5"
    run_sweep(synthesis, out, candidates=400, chunk_size=200, progress=False, store="feasible")
    with h5py.File(out, "r+") as f:
        for i in range(f["candidates/params"].ndim):
            for s in list(f["candidates/params"].dims[i].values()):
                if s.name == "/candidate":
                    f["candidates/params"].dims[i].detach_scale(s)
        del f["candidate"]
    with pytest.raises(ResultsError, match="candidate"):
        pipeline.open(out)
    assert main(["browse", str(out)]) == 2
    one_line_error(capsys, out, "candidate")


def test_status_codes_out_of_range_are_refused(sweep, capsys):
    with h5py.File(sweep, "r+") as f:
        st = f["candidates/status"]
        raw = st[()].astype("i1")
        raw[:3] = 42
        del f["candidates/status"]
        f.create_dataset("candidates/status", data=raw)
    assert main(["browse", str(sweep)]) == 2
    one_line_error(capsys, sweep, "candidates/status[0] = 42, not a status code")


# ------------------------------------------------------------ messages that name the file
def test_a_garbled_journal_manifest_is_one_line(synthesis, studies, tmp_path, capsys):
    out = tmp_path / "s.h5"
    with pytest.raises(KeyboardInterrupt):
        run_sweep(synthesis, out, candidates=400, chunk_size=200, progress=False,
                  stop_after_chunks=1)
    (tmp_path / "s.h5.parts" / "manifest.json").write_text('{"candidates": 4')
    assert main(["run", str(studies / "ov7_synthesis.toml"), "-o", str(out), "--resume",
                 "-q"]) == 2
    one_line_error(capsys, "manifest.json", "damaged journal manifest")


def test_a_file_open_for_writing_elsewhere_is_one_line(sweep, capsys):
    holder = subprocess.Popen(
        [sys.executable, "-c", "import h5py, sys; f = h5py.File(sys.argv[1], 'a'); "
         "print('open', flush=True); sys.stdin.read()", str(sweep)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "open"
        assert main(["browse", str(sweep)]) == 2
        one_line_error(capsys, sweep, "open for writing")
        with pytest.raises(ResultsError, match="open for writing"):
            pipeline.open(sweep)
    finally:
        holder.communicate("", timeout=60)


def test_a_folder_as_a_results_file_is_one_line(tmp_path, capsys):
    folder = tmp_path / "results.h5"
    folder.mkdir()
    for cmd in (["browse", folder], ["analyze", folder], ["export", folder, "--csv", tmp_path],
                ["report", folder]):
        assert main([str(c) for c in cmd]) == 2, cmd
        one_line_error(capsys, folder, "folder")


# ------------------------------------------------------------ kill -9 inside analyze and report
def test_analyze_killed_before_its_rename_keeps_the_sweep(sweep):
    before = digest(sweep)
    rc, err = cli("analyze", sweep, "-q", env={files.FAULT_VARIABLE: "before-rename:s.h5"})
    assert rc == -signal.SIGKILL, err
    partial = [n for n in hidden(sweep.parent) if n.endswith(".partial.h5")]
    assert len(partial) == 1                                    # the point was reached
    assert (sweep.parent / partial[0]).stat().st_size >= sweep.stat().st_size   # a full copy
    assert digest(sweep) == before
    assert main(["analyze", str(sweep), "-q"]) == 0             # the next run clears it
    assert hidden(sweep.parent) == []


def test_report_killed_before_its_rename_leaves_no_page(sweep):
    # (no design drawn: what is tested is the page's rename, not its pictures)
    rc, err = cli("report", sweep, "-q", "--drawings", "0",
                  env={files.FAULT_VARIABLE: "before-rename:s_report.html"})
    assert rc == -signal.SIGKILL, err
    partial = [n for n in hidden(sweep.parent) if n.endswith(".partial.html")]
    assert len(partial) == 1 and (sweep.parent / partial[0]).read_text().rstrip().endswith(
        "</html>")                                              # written whole, not renamed
    assert not list(sweep.parent.glob("*_report.html"))
    with h5py.File(sweep, "r") as f:                            # its analysis came first, whole
        assert f["analysis"].attrs["complete"]
    assert main(["report", str(sweep), "-q", "--drawings", "0"]) == 0
    assert hidden(sweep.parent) == []


# ------------------------------------------------------------ sizes
def test_a_huge_sweep_file_is_created_without_holding_its_index(synthesis):
    """--candidates 10^9 used to allocate the whole candidate index (7.45 GiB)
    at once; it is written a million at a time."""
    n = 4_000_000
    spec = synthesis.sweep.with_candidates(n)
    from dataclasses import replace
    spec = replace(spec, chunk_size=100_000)
    problem = build_problem(synthesis, spec)
    problem.evaluate_rows(np.ascontiguousarray(problem.plan.par[None, :]), False)   # compiled
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        sf = SweepFile(Path(d) / "big.h5", synthesis, problem)
        tracemalloc.start()
        sf.create()
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        with h5py.File(sf.path, "r") as f:
            k = f["candidate"]
            assert k.shape == (n,) and k[0] == 0 and k[n - 1] == n - 1
            assert k[1_234_567] == 1_234_567
    assert peak < 8 * n / 2, f"{peak / 2**20:.1f} MiB held for a {8 * n / 2**20:.0f} MiB index"
