"""The commands the README and the guide (docs/guide/, built by docs/mkdocs.yml)
show, run as a user runs them, in this process.

A command is a line of a fenced ``sh`` block (a line of only a comment is left
out, ``  # ...`` ends a command).  Each takes one of three forms, and any other
fails the test that meets it, so that nothing shown goes unrun:

* ``pipeline ...`` runs through ``pipeline.cli.main``, at a test's size: a
  sweep of a few thousand candidates (``smaller``), an adaptive search of a few
  generations (``copy_studies`` shortens the copied studies' ``evaluations``),
  a local Dask cluster in place of ``tcp://host:8786``; a sweep that a later
  command ``--resume``s is stopped after its first chunk, as if interrupted;
* ``pip install -e . && ...``: the suite runs in that installation already, so
  the rest of the line runs;
* ``pip install --no-compile -e ".[test]" && python -m pytest -q`` is the suite itself:
  checked to be what ``.ci/run`` runs, not run inside itself."""

import contextlib
import re
import shlex
import shutil
from pathlib import Path

from pipeline.cli import main

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
MKDOCS = ROOT / "docs" / "mkdocs.yml"
GUIDE = ROOT / "docs" / "guide"
CI_RUN = ROOT / ".ci" / "run"
SMALL = "3000"                  # candidates of a sweep the tests run
SEARCH_EVALUATIONS = 300        # evaluations of an adaptive search the tests run
MAIN_JOB = "pipeline run studies/ov7_synthesis.toml"
INSTALLED = ("pip install -e . && ", 'pip install --no-compile -e ".[test]" && ')
FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```[ \t]*$", re.M | re.S)


def shell_blocks(text):
    """The commands of each fenced ``sh`` block of a Markdown text, in order."""
    blocks = []
    for lang, body in FENCE.findall(text):
        if lang == "sh":
            lines = [ln.split("  #")[0].strip() for ln in body.splitlines()]
            blocks.append([ln for ln in lines if ln and not ln.startswith("#")])
    return blocks


def python_blocks(text):
    """The source of each fenced ``python`` block of a Markdown text, in order."""
    return [body for lang, body in FENCE.findall(text) if lang == "python"]


def unfenced_commands(text):
    """Lines outside every fence that a reader would take for a command
    (indented ``pipeline ...``): each should be in an ``sh`` block."""
    return [ln for ln in FENCE.sub("", text).splitlines()
            if re.match(r"^ {4,}(\$ )?pipeline \w", ln)]


def guide_pages():
    """The guide's pages in the order of its navigation (docs/mkdocs.yml)."""
    import yaml
    nav = yaml.safe_load(MKDOCS.read_text())["nav"]

    def pages(items):
        for item in items:
            value = next(iter(item.values())) if isinstance(item, dict) else item
            yield from pages(value) if isinstance(value, list) else [GUIDE / value]
    return list(pages(nav))


def ci_test_command():
    """The line of .ci/run that runs the suite."""
    lines = [ln for ln in CI_RUN.read_text().splitlines() if "python -m pytest" in ln]
    assert len(lines) == 1, lines
    return lines[0]


def runs_in_ci(command):
    """.ci/run runs ``command``, word for word, with options after it at most."""
    words, ci = shlex.split(command), shlex.split(ci_test_command())
    return ci[:len(words)] == words


def copy_studies(folder):
    """The checkout's studies in ``folder``/studies, every adaptive search
    shortened to SEARCH_EVALUATIONS evaluations."""
    shutil.copytree(ROOT / "studies", folder / "studies")
    for path in (folder / "studies").glob("*.toml"):
        text = path.read_text()
        if "\n[search]" in text:
            text, n = re.subn(r"^evaluations = \d+", f"evaluations = {SEARCH_EVALUATIONS}",
                              text, flags=re.M)
            assert n == 1, path
            path.write_text(text)


def smaller(argv):
    """The same command with a test-sized candidate count; every run of the main
    job's study in chunks of 1000 (so that its files draw the same candidates)."""
    argv = list(argv)
    if "--candidates" in argv:
        argv[argv.index("--candidates") + 1] = SMALL
    elif argv[:2] == ["run", "studies/ov7_synthesis.toml"] and "--resume" not in argv:
        argv += ["--candidates", SMALL]
    if argv[:2] == ["run", "studies/ov7_synthesis.toml"] and "--resume" not in argv:
        argv += ["--chunk-size", "1000"]
    return argv


def pipeline_argvs(command):
    """The ``pipeline`` argument lists a shown command runs (empty for the
    suite's own command, checked against .ci/run instead)."""
    for prefix in INSTALLED:
        if command.startswith(prefix):
            rest = command[len(prefix):]
            if rest.startswith("python -m pytest"):
                assert prefix == INSTALLED[1] and runs_in_ci(command), (
                    f"{command!r} is not what .ci/run runs: {ci_test_command()!r}")
                return []
            command = rest
    argvs = []
    for part in command.split(" && "):
        argv = shlex.split(part)
        assert argv[0] == "pipeline", f"a command the tests cannot run as shown: {command!r}"
        argvs.append(smaller(argv[1:]))
    return argvs


def output_of(argv):
    return argv[argv.index("-o") + 1] if "-o" in argv else None


def run_commands(commands, monkeypatch, capsys, where=""):
    """Run the commands in order in the current folder; each must exit 0 (a
    sweep stopped to be resumed: 130, one chunk saved).  ``where`` names them in a
    failure."""
    import pipeline.runs.sweep as sw
    argvs = [a for c in commands for a in pipeline_argvs(c)]
    resumed = {output_of(a) for a in argvs if a[0] == "run" and "--resume" in a}
    real_run_sweep = sw.run_sweep
    with contextlib.ExitStack() as stack:
        cluster = None
        for argv in argvs:
            if "--scheduler" in argv and cluster is None:
                import distributed
                cluster = stack.enter_context(distributed.LocalCluster(
                    n_workers=1, threads_per_worker=1, processes=False, protocol="tcp",
                    dashboard_address=None))
            argv = [cluster.scheduler_address if a == "tcp://host:8786" else a for a in argv]
            if argv[0] == "compile" and "--show" not in argv:
                # in this process: the suite's other worker has the second core, and two
                # compile workers beside it slow the terminal tests there past their 2 s
                # (tests/compiler/test_compiler.py runs compile in worker processes)
                argv += ["-q", "-j", "1"]
            interrupt = argv[0] == "run" and "--resume" not in argv and \
                output_of(argv) in resumed - {None}
            if interrupt:      # as if stopped after its first chunk: a later line resumes it
                monkeypatch.setattr(sw, "run_sweep", lambda *a, **k: real_run_sweep(
                    *a, **k, stop_after_chunks=1))
            rc = main(argv)
            monkeypatch.setattr(sw, "run_sweep", real_run_sweep)
            captured = capsys.readouterr()
            if interrupt:
                assert rc == 130 and re.search(r"\b1 of \d+ chunks saved", captured.err), (
                    where, argv, captured.err)
                assert Path(output_of(argv) + ".parts").exists()
            else:
                assert rc == 0, (where, argv, captured.err)
