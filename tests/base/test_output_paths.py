"""Outputs never replace inputs (issue 58, cases 3, 4, 5 and 10).

Every command that writes (run, report, export, show, show --animate, analyze,
compare, tolerance) refuses, before it computes anything, an output path that
is one of its inputs, a results file it was not asked to replace, a link to
nothing or (for pictures, pages and tables) a link at all; ``--overwrite``
replaces only a results file of the package (checked by its format).  The
audit's cases are tests of their own; a property test draws output paths
among the inputs, results files of each kind, text files, pictures, links (to
results, to unrelated files, to nothing) and folders for every writing command,
and hashes every file of the folder before and after.  A killed report leaves
no temporary file (its re-run designs and animation are made in memory)."""

import contextlib
import hashlib
import io
import os
import shutil
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

import h5py
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import pipeline.base.files as files
from pipeline.cli import main
from support.faults import digest, one_line_error

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "studies"
# a scene with an output rocker (tolerance): the main job's mechanism, whose sweep module
# the sweep below compiles anyway (ov7_base's rocker compiled one more, 35 s)
SCENE_STUDY = STUDIES / "ov7_class3.toml"
SWEEP_STUDY = STUDIES / "ov7_synthesis.toml"
# the scene the drawn cases run (base.toml): a four-bar, whose pictures draw sooner than
# the class III scene's (each accepted case with pictures draws all of them)
RUN_STUDY = STUDIES / "warp_feed_fourbar.toml"
SWEEP_N = 400                                  # enough for feasible designs and a knee


def run(*argv, cwd=None):
    """`pipeline ARGV` in this process, in ``cwd``: (exit code, stderr)."""
    err, out = io.StringIO(), io.StringIO()
    with contextlib.ExitStack() as stack:
        if cwd is not None:
            here = os.getcwd()
            os.chdir(cwd)
            stack.callback(os.chdir, here)
        stack.enter_context(contextlib.redirect_stderr(err))
        stack.enter_context(contextlib.redirect_stdout(out))
        rc = main([str(a) for a in argv])
    return rc, err.getvalue().strip()


def assert_one_line(rc, err, *needles):
    assert rc == 2, err
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    for n in needles:
        assert str(n) in err, (n, err)


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """The inputs, made once: a scene's results file, a sweep's (analysed, and
    a copy of it before its analysis), a tolerance analysis's results file."""
    d = tmp_path_factory.mktemp("made")
    assert run("run", SCENE_STUDY, "-o", d / "scene.h5", "-q", "--no-pictures")[0] == 0
    assert run("run", SWEEP_STUDY, "-o", d / "sweep.h5", "--candidates", SWEEP_N,
               "--chunk-size", SWEEP_N, "-q")[0] == 0
    shutil.copy(d / "sweep.h5", d / "unanalysed.h5")
    assert run("analyze", d / "sweep.h5", "-q")[0] == 0
    with h5py.File(d / "sweep.h5", "r") as f:
        assert int(f["analysis/knee"][()]) >= 0, "the report's comparison needs a knee"
    assert run("tolerance", d / "scene.h5", "--samples", 4, "--no-pictures", "-o",
               d / "tol.h5", "-q")[0] == 0
    return d


def fresh(made, folder, *names):
    """Copies of the made files ``names`` in ``folder``; their paths."""
    folder.mkdir(parents=True, exist_ok=True)
    return [Path(shutil.copy(made / n, folder / n)) for n in names]


# ------------------------------------------------------------------ the audit's cases
def test_3_a_report_never_replaces_a_results_file(made, tmp_path):
    sweep, scene = fresh(made, tmp_path, "unanalysed.h5", "scene.h5")
    (tmp_path / "link.html").symlink_to(scene.name)
    before = {p: digest(p) for p in (sweep, scene)}
    for out in (sweep, scene, tmp_path / "link.html", Path(f"{tmp_path}/./unanalysed.h5")):
        rc, err = run("report", sweep, "-o", out)
        assert_one_line(rc, err, out)
        assert {p: digest(p) for p in (sweep, scene)} == before
    with h5py.File(sweep, "r") as f:
        assert "analysis" not in f          # refused before the analysis ran
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.html", "scene.h5",
                                                          "unanalysed.h5"]


def test_4_a_scene_results_file_is_never_named_like_its_picture(made, tmp_path):
    study = STUDIES / "warp_feed_fourbar.toml"
    rc, err = run("run", study, "-o", tmp_path / "odd.png", "-q")
    assert_one_line(rc, err, "odd.png", ".h5")
    assert list(tmp_path.iterdir()) == []
    # an earlier results file of that name is kept, --overwrite or not
    older, = fresh(made, tmp_path, "scene.h5")
    older = older.rename(tmp_path / "odd.png")
    before = digest(older)
    for extra in ((), ("--overwrite",)):
        assert_one_line(*run("run", study, "-o", older, "-q", *extra), "odd.png")
        assert digest(older) == before
    # a companion picture's name taken by a results file: refused before the solve
    clash = older.rename(tmp_path / "x_kinematics.png")
    assert_one_line(*run("run", study, "-o", tmp_path / "x.h5", "-q"), clash, "HDF5")
    assert digest(clash) == before and not (tmp_path / "x.h5").exists()


def test_5_links_at_the_results_path(made, tmp_path):
    results = tmp_path / "results"
    results.mkdir()
    link = results / "ov7_synthesis.h5"
    link.symlink_to("../elsewhere/ov7_synthesis.h5")
    # a plain run: the link's target (outside results/) is not created
    rc, err = run("run", SWEEP_STUDY, "--candidates", 50, "-q", cwd=tmp_path)
    assert_one_line(rc, err, "ov7_synthesis.h5", "link to nothing")
    assert not (tmp_path / "elsewhere").exists() and link.is_symlink()
    assert_one_line(*run("run", SWEEP_STUDY, "--candidates", 50, "-q", "--overwrite",
                         cwd=tmp_path), "link to nothing")
    # --overwrite through a link to a file that is not a results file: kept
    notes = tmp_path / "notes.txt"
    notes.write_text("precious")
    link.unlink()
    link.symlink_to("../notes.txt")
    rc, err = run("run", SWEEP_STUDY, "--candidates", 50, "-q", "--overwrite", cwd=tmp_path)
    assert_one_line(rc, err, "ov7_synthesis.h5", "not a pipeline results file")
    assert notes.read_text() == "precious"
    # through a link to a results file, --overwrite replaces that file, the link stays
    older, = fresh(made, tmp_path, "tol.h5")
    link.unlink()
    link.symlink_to("../tol.h5")
    assert_one_line(*run("run", SWEEP_STUDY, "--candidates", 50, "-q", cwd=tmp_path),
                    "already exists", "--overwrite")
    assert run("run", SWEEP_STUDY, "--candidates", 50, "-q", "--overwrite",
               cwd=tmp_path)[0] == 0
    assert link.is_symlink()
    with h5py.File(older, "r") as f:
        assert f.attrs["kind"] == "sweep"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt", "results", "tol.h5"]


def test_10_tolerance_never_replaces_its_source(made, tmp_path):
    scene, = fresh(made, tmp_path, "scene.h5")
    (tmp_path / "link.h5").symlink_to("scene.h5")
    before = digest(scene)
    for out in (scene, tmp_path / "link.h5", Path(f"{tmp_path}/missing/../scene.h5")):
        for extra in ((), ("--overwrite",)):
            rc, err = run("tolerance", scene, "-o", out, "--samples", 4, *extra)
            assert_one_line(rc, err, out, "reads")
            assert digest(scene) == before
    # (a refused case makes no folder on the way either)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.h5", "scene.h5"]


def test_10_a_killed_report_leaves_no_temporary_file(made, tmp_path):
    """kill -9 while the report compares its knee with the reference design
    (both re-run as scenes): nothing in the temporary folder, nothing beside."""
    sweep, = fresh(made, tmp_path / "work", "sweep.h5")
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    env = dict(os.environ, TMPDIR=str(scratch), **{files.FAULT_VARIABLE: "design-compared"})
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    p = subprocess.run([sys.executable, "-m", "pipeline.cli", "report", str(sweep), "-o",
                        str(tmp_path / "work" / "r.html"), "--drawings", "0", "-q"],
                       env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                       timeout=600)
    assert p.returncode == -signal.SIGKILL, p.stderr      # the point was reached
    assert list(scratch.iterdir()) == []
    assert [q.name for q in (tmp_path / "work").iterdir()] == ["sweep.h5"]


def test_the_report_makes_nothing_in_the_temporary_folder(made, tmp_path, monkeypatch):
    """Its comparison and its animation are made in memory: tempfile is never
    asked for a file or a folder of its own (one beside an output is
    ``files.replacing``'s, which a later run clears)."""
    sweep, = fresh(made, tmp_path, "sweep.h5")
    asked = []
    for name in ("mkdtemp", "mkstemp"):
        real = getattr(tempfile, name)

        def spy(*a, _real=real, _name=name, **k):
            if k.get("dir") is None and (len(a) < 3 or a[2] is None):
                asked.append(_name)
            return _real(*a, **k)
        monkeypatch.setattr(tempfile, name, spy)
    rc, err = run("report", sweep, "-o", tmp_path / "r.html", "--drawings", "0", "-q")
    assert rc == 0, err
    assert asked == []
    page = (tmp_path / "r.html").read_text()
    assert "image/gif" in page and "No comparison" not in page   # both were made


# ------------------------------------------------------------------ the property
# The folder every drawn case writes into: inputs, results files of each kind,
# text files and pictures, links (to results, to unrelated files, to folders, to
# nothing), folders, and names not yet taken.
LINKS = {"to_sweep.h5": "sweep.h5", "to_scene.h5": "scene.h5", "to_tol.h5": "tol.h5",
         "to_notes.h5": "notes.txt", "to_notes.gif": "notes.txt", "to_sub": "sub",
         "dangling.h5": "gone/x.h5", "dangling.gif": "gone/x.gif", "dangling_dir": "gone/d",
         "sub/points.csv": "../notes.txt"}
NEW = ("new.h5", "new.png", "new.gif", "new.html", "newdir", "clash.h5")
OUTPUTS = ("scene.h5", "scene2.h5", "sweep.h5", "tol.h5", "base.toml", "synthesis.toml",
           "notes.txt", "picture.png", "old.gif", "old.html", "clash.png", "sub", "empty",
           *[k for k in LINKS if "/" not in k], *NEW)
SPELLINGS = ("plain", "dot", "absolute", "detour", "missing")

COMMANDS = {   # name: (arguments before the output, the option naming it, after; inputs)
    "run-scene": (["run", "base.toml"], "-o", [], ["base.toml"]),
    "run-sweep": (["run", "synthesis.toml", "--candidates", "40", "--chunk-size", "40"], "-o",
                  [], ["synthesis.toml"]),
    "report": (["report", "sweep.h5", "--drawings", "0", "--top", "3"], "-o", [],
               ["sweep.h5"]),
    "export": (["export", "sweep.h5"], "--csv", [], ["sweep.h5"]),
    "show": (["show", "sweep.h5", "--candidate", "reference"], "-o", [], ["sweep.h5"]),
    "animate": (["show", "scene.h5", "--animate", "--frames", "2"], "-o", [], ["scene.h5"]),
    "analyze": (["analyze"], None, [], []),
    "compare": (["compare", "scene.h5", "scene2.h5"], "-o", [], ["scene.h5", "scene2.h5"]),
    "tolerance": (["tolerance", "scene.h5", "--samples", "4"], "-o", [], ["scene.h5"]),
}
RESULTS_WRITERS = ("run-scene", "run-sweep", "tolerance")
FOLDER_WRITERS = {"export": ["candidates.csv"], "compare": ["scene_vs_scene2_compare.png"]}


@pytest.fixture(scope="module")
def world(made, tmp_path_factory):
    """The folder of the drawn cases, made once (a pristine master; a case that
    may write gets a copy of it)."""
    w = tmp_path_factory.mktemp("world") / "w"
    w.mkdir()
    for n in ("scene.h5", "sweep.h5", "tol.h5"):
        shutil.copy(made / n, w / n)
    shutil.copy(made / "scene.h5", w / "scene2.h5")
    shutil.copy(made / "tol.h5", w / "clash.png")      # clash.h5's picture name: a results file
    shutil.copy(RUN_STUDY, w / "base.toml")
    shutil.copy(SWEEP_STUDY, w / "synthesis.toml")
    (w / "notes.txt").write_text("a designer's notes\n")
    (w / "picture.png").write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)))
    (w / "old.gif").write_bytes(b"GIF89a" + bytes(100))
    (w / "old.html").write_text("<p>an earlier page</p>\n")
    (w / "sub").mkdir()
    (w / "empty").mkdir()
    shutil.copy(made / "tol.h5", w / "sub" / "candidates.csv")   # export's name: results
    for name, target in LINKS.items():
        (w / name).symlink_to(target)
    return w


def state(folder):
    """Every entry under ``folder`` (links not followed): a file's hash, a
    link's target, a folder."""
    out = {}
    for base, dirs, names in os.walk(folder):
        for n in dirs + names:
            p = Path(base) / n
            rel = str(p.relative_to(folder))
            if p.is_symlink():
                out[rel] = ("link", os.readlink(p))
            elif p.is_dir():
                out[rel] = ("dir",)
            else:
                out[rel] = ("file", hashlib.sha256(p.read_bytes()).hexdigest())
    return out


def is_results(p, kind=None):
    try:
        with h5py.File(p, "r") as f:
            return f.attrs.get("format") == "pipeline-results" and (
                kind is None or f.attrs.get("kind") == kind)
    except (OSError, ValueError):
        return False


def hdf5(p):
    return Path(p).read_bytes()[:8] == b"\x89HDF\r\n\x1a\n"


def spelled(w, name, how):
    return {"plain": name, "dot": f"./{name}", "absolute": str(w / name),
            "detour": f"empty/../{name}", "missing": f"missing/../{name}"}[how]


def writable(w, p, inputs):
    """Whether a picture, page or table may be written at ``p`` (the spec):
    not a folder, a link, an input, an HDF5 file."""
    p = w / p
    if p.is_symlink() or p.is_dir():
        return False
    if not p.exists():
        return True
    return not any(p.samefile(w / i) for i in inputs) and not hdf5(p)


def companions(cmd, name, pictures):
    """The pictures a results writer names after its results file ``name``."""
    stem = Path(name).stem
    if cmd == "run-scene" and pictures:
        return [f"{stem}.png", f"{stem}_kinematics.png"]
    if cmd == "tolerance" and pictures:
        return [f"{stem}_histograms.png", f"{stem}_tornado.png"]
    return []


def expected(w, cmd, name, overwrite, pictures):
    """(accepted?, class of the case): what the spec says of writing ``name``."""
    p = w / name
    inputs = COMMANDS[cmd][3]
    if p.is_symlink() and not p.exists():
        return False, "dangling"
    kind = ("new" if not p.exists() else "folder" if p.is_dir() else
            ("link-" if p.is_symlink() else "") + ("results" if is_results(p) else "plain"))
    if cmd == "analyze":
        return is_results(p, "sweep") and not p.is_dir(), kind
    if cmd in FOLDER_WRITERS:
        ok = kind in ("new", "folder") and all(
            writable(w, Path(name) / f, inputs) for f in FOLDER_WRITERS[cmd])
        return ok, kind
    if kind == "folder" or (p.exists() and any(p.samefile(w / i) for i in inputs)):
        return False, kind
    if cmd in RESULTS_WRITERS:
        if cmd == "run-scene" and pictures and p.suffix == ".png":
            return False, kind
        if not all(writable(w, c, inputs) for c in companions(cmd, name, pictures)):
            return False, kind
        return kind == "new" or (overwrite and kind.endswith("results")), kind
    from matplotlib.backend_bases import FigureCanvasBase
    if cmd == "animate" and p.suffix != ".gif":
        return False, kind
    if cmd == "show" and p.suffix[1:] not in FigureCanvasBase.get_supported_filetypes():
        return False, kind
    return kind in ("new", "plain"), kind


def may_change(master, cmd, name, entry, before, now, spelling):
    """Whether an accepted case may have changed (or made) ``entry``: its
    output ``name`` (a link's target only for a results file replaced), the
    pictures named after it, the tables or picture in its folder, a folder
    named on the way there (``spelling``: "missing/../x").  ``master``: the
    folder as it was (``before``: its state; ``now``: after)."""
    if entry not in before and now.get(entry) == ("dir",) and entry in Path(spelling).parts:
        return True
    out = Path(name)
    real = Path(os.path.realpath(master / out)).relative_to(master)
    fresh_or_plain = entry not in before or (before[entry][0] == "file"
                                             and not hdf5(master / entry))
    if cmd == "analyze":
        return Path(entry) == real
    if cmd in FOLDER_WRITERS:
        return (Path(entry) == out and entry not in before) or (
            Path(entry).parent == real and fresh_or_plain)
    if Path(entry) == real and (cmd in RESULTS_WRITERS or Path(entry) == out):
        return True
    return (cmd in RESULTS_WRITERS and Path(entry).parent == out.parent
            and Path(entry).name.startswith(out.stem) and entry.endswith(".png")
            and fresh_or_plain)


def test_no_output_replaces_an_input_or_an_unrelated_file(world, tmp_path_factory):
    """Every writing command, output paths drawn among the folder's entries
    (spelled four ways), with and without --overwrite and pictures: a refused
    case is one line (exit 2) and changes nothing; an accepted one changes only
    its own outputs, never an input or any other file.  A refused case runs
    every time (it is refused before anything is computed); an accepted one
    runs once per command and kind of path."""
    pristine = state(world)
    verified, drawn, refused = set(), [], []

    @settings(max_examples=500)
    @example(cmd="analyze", name="sweep.h5", how="plain", overwrite=False, pictures=False)
    @example(cmd="analyze", name="to_sweep.h5", how="detour", overwrite=False, pictures=False)
    @given(cmd=st.sampled_from(sorted(COMMANDS)), name=st.sampled_from(OUTPUTS),
           how=st.sampled_from(SPELLINGS), overwrite=st.booleans(), pictures=st.booleans())
    def case(cmd, name, how, overwrite, pictures):
        drawn.append((cmd, name))
        ok, kind = expected(world, cmd, name, overwrite, pictures)
        ok = ok and not (cmd == "analyze" and how == "missing")   # an input is read, not made
        opts = {"overwrite": overwrite and cmd in RESULTS_WRITERS,
                "pictures": pictures and cmd in ("run-scene", "tolerance")}
        key = (cmd, kind, *opts.values())
        if ok and key in verified:
            return
        w = world
        if ok:
            w = tmp_path_factory.mktemp("case") / "w"
            shutil.copytree(world, w, symlinks=True)
        before_args, option, after, _ = COMMANDS[cmd]
        out = spelled(w, name, how)
        argv = [*before_args, *([option] if option else []), out, *after, "-q"]
        argv += ["--overwrite"] if opts["overwrite"] else []
        argv += ["--no-pictures"] if cmd in ("run-scene", "tolerance") and not pictures else []
        rc, err = run(*argv, cwd=w)
        now = state(w)
        changed = sorted(k for k in set(now) | set(pristine) if now.get(k) != pristine.get(k))
        if not ok:
            refused.append(cmd)
            if changed:             # put the folder back before failing
                shutil.rmtree(world)
                shutil.copytree(w_master, world, symlinks=True)
            assert rc == 2 and len(err.splitlines()) == 1 and "Traceback" not in err, (
                argv, err)
            assert changed == [], (argv, changed)
            return
        assert rc == 0, (argv, err)
        assert changed, argv
        wrong = [k for k in changed if k not in now
                 or not may_change(world, cmd, name, k, pristine, now, spelled(w, name, how))]
        assert wrong == [], (argv, wrong)
        verified.add(key)
        shutil.rmtree(w.parent)

    w_master = tmp_path_factory.mktemp("master") / "w"
    shutil.copytree(world, w_master, symlinks=True)
    case()
    assert len(drawn) >= 500
    # every command was drawn, and accepted and refused both ran for each
    assert {c for c, _ in drawn} == set(COMMANDS)
    assert {k[0] for k in verified} == set(COMMANDS) == set(refused)
