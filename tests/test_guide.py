"""The guide (docs/guide/, a site built by MkDocs from docs/mkdocs.yml): it builds
with --strict (no broken link, no page outside the navigation's reach), and
every command it shows in an sh block runs, as tests/test_readme.py runs the
README's (test-sized: tests/support/shell_blocks.py).  Each block runs on its
own, in a fresh folder holding the studies and the README's main job, as a
reader who has done the README's set-up would run it."""

import os
import shutil
import subprocess
import sys

import pytest

from support.shell_blocks import (GUIDE, MAIN_JOB, MKDOCS, copy_studies, guide_pages,
                                  pipeline_argvs, run_commands, shell_blocks,
                                  unfenced_commands)
from support.sweep_helpers import assert_same_results


def build(config, site):
    """mkdocs build --strict as .ci/run runs it (not -q: it hides the warnings that
    --strict counts, and a broken link then passes)."""
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict",
                           "-f", str(config), "-d", str(site)],
                          capture_output=True, text=True, timeout=600,
                          env=dict(os.environ, NO_MKDOCS_2_WARNING="1"))


def test_the_guide_builds_with_strict_checks(tmp_path):
    """A warning (a broken link or anchor, a missing page or image) fails the build.
    MkDocs and its Material theme are in the test extra: never skipped."""
    site = tmp_path / "site"
    r = build(MKDOCS, site)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    assert (site / "index.html").exists() and (site / "speed" / "index.html").exists()
    assert list((site / "assets" / "stylesheets").glob("main.*.css"))     # Material's


def test_a_broken_link_fails_the_build(tmp_path):
    """The check above can fail: a copy of the guide with a link to no page and one
    to no anchor does not build."""
    docs = tmp_path / "docs"
    shutil.copytree(MKDOCS.parent, docs, ignore=shutil.ignore_patterns("site"))
    page = docs / "guide" / "gpu.md"
    page.write_text(page.read_text() + "\n[a page](no_such_page.md)\n")
    r = build(docs / "mkdocs.yml", tmp_path / "site")
    assert r.returncode != 0 and "no_such_page.md" in r.stderr, r.stderr[-3000:]
    page.write_text(page.read_text().replace("no_such_page.md", "speed.md#no-such-anchor"))
    r = build(docs / "mkdocs.yml", tmp_path / "site")
    assert r.returncode != 0 and "no-such-anchor" in r.stderr, r.stderr[-3000:]


def test_every_guide_page_is_in_its_navigation():
    pages = guide_pages()
    assert sorted(pages) == sorted(GUIDE.rglob("*.md")), set(pages) ^ set(GUIDE.rglob("*.md"))


def test_the_guide_shows_its_commands_in_sh_blocks():
    """A command written outside an sh block would escape the test below."""
    for page in guide_pages():
        assert not unfenced_commands(page.read_text()), page


def guide_blocks():
    return [(page.name, block) for page in guide_pages()
            for block in shell_blocks(page.read_text())]


def test_the_guide_shows_commands_this_test_can_run():
    """Every command is one run_commands knows (else it fails naming it), and the
    guide shows at least the commands the README's list had."""
    blocks = guide_blocks()
    for _, block in blocks:
        for command in block:
            pipeline_argvs(command)
    shown = " ".join(c for _, block in blocks for c in block)
    for command in ("run", "export", "show", "analyze", "browse", "report", "tolerance",
                    "compare", "compile", "doctor"):
        assert f"pipeline {command} " in shown + " ", command
    assert "--resume" in shown and "--scheduler" in shown and "--store feasible" in shown


@pytest.mark.slow
def test_every_guide_command_runs(tmp_path, monkeypatch, capsys):
    """Each sh block of each page, in order, after the README's main job; what the
    sweeps write holds: the bigger sweep (interrupted after its first chunk, then
    continued by --resume), the cluster run and the feasible-only run have the main
    job's candidates and numbers."""
    import h5py
    import numpy as np

    base = tmp_path / "base"
    base.mkdir()
    copy_studies(base)
    monkeypatch.chdir(base)
    run_commands([MAIN_JOB], monkeypatch, capsys)
    main_job = base / "results" / "ov7_synthesis.h5"
    with h5py.File(main_job, "r") as f:
        feasible = f["candidates/feasible"][()]
        params = f["candidates/params"][()]
        dwell = f["metrics/dwell_error"][()]
    checked = set()
    for k, (page, block) in enumerate(guide_blocks()):
        folder = tmp_path / f"{k:02d}_{page[:-3]}"
        folder.mkdir()
        shutil.copytree(base / "studies", folder / "studies")
        (folder / "results").mkdir()
        shutil.copy(main_job, folder / "results")
        monkeypatch.chdir(folder)
        run_commands(block, monkeypatch, capsys, where=f"{page}, sh block {k}")
        results = folder / "results"
        if (results / "big_sweep.h5").exists():     # interrupted, then resumed
            assert_same_results(main_job, results / "big_sweep.h5")
            assert not (results / "big_sweep.h5.parts").exists()
            checked.add("resume")
        if (results / "cluster.h5").exists():
            assert_same_results(main_job, results / "cluster.h5")
            with h5py.File(results / "cluster.h5", "r") as f:
                assert f.attrs["engine"] == "dask"
            checked.add("cluster")
        if (results / "huge.h5").exists():
            # --store feasible: exactly the main job's feasible rows, with their sweep index
            with h5py.File(results / "huge.h5", "r") as f:
                np.testing.assert_array_equal(f["candidate"][()], np.flatnonzero(feasible))
                np.testing.assert_array_equal(f["candidates/params"][()], params[feasible])
                np.testing.assert_array_equal(f["metrics/dwell_error"][()], dwell[feasible])
            checked.add("feasible only")
    assert checked == {"resume", "cluster", "feasible only"}
