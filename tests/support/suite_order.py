"""The order of the suite's test files (``tests/conftest.py``'s
``pytest_collection_modifyitems``).

pytest-xdist hands out whole files in the order collected (``--dist loadfile
--no-loadscope-reorder``), one to each worker first, then the next file to
whichever worker is nearly done.  The session's sweep of the main job
(``synthesis_sweep``) is run by the first worker that asks for it, the others
wait on the fixture's lock: in a cold compile cache that is about two minutes of
one core (the main job's generated module), and a second worker that started
on a file reading the sweep waited for all of it, its core idle.  So the files
of the first half that read it, but the first, go behind the first half's other
files: a worker then starts on those (about half the suite's work in the order
collected: more than the sweep's compile)."""


def by_file(items):
    """The collected test items by file, in the order collected: {file: [items]}."""
    files = {}
    for item in items:
        files.setdefault(item.nodeid.split("::")[0], []).append(item)
    return files


def sweep_readers(files):
    """The files of ``by_file`` with a test that reads the session's sweep, in order."""
    return [name for name, its in files.items()
            if any("synthesis_sweep" in i.fixturenames for i in its)]


def files_in_order(names, readers):
    """``names`` (the files as collected) with the files of the first half that
    are in ``readers``, but the first of ``readers``, moved behind the first
    half's other files, in their order; every other file keeps its place."""
    half = len(names) // 2
    first_readers = [n for n in names if n in readers][:1]
    early = [n for n in names[:half] if n in readers and n not in first_readers]
    if not early:
        return list(names)
    rest = [n for n in names if n not in early]
    at = rest.index(names[half])        # (not early: every early file is before it)
    return rest[:at] + early + rest[at:]
