"""Writing files without ever damaging an earlier result.

Every file the project writes goes through ``replacing``: the content is
written to a temporary file in the target's folder, flushed to the disk, and
renamed over the target only when complete.  A full disk, a read-only folder,
an exception or a kill at any point leaves the previous file as it was (and no
half-written file under the target's name).  ``safe_name`` turns a label (a
study's name, a dynamics case's name) into a file name that stays in its
folder.
"""

from __future__ import annotations

import errno
import glob
import os
import re
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path

from .errors import ResultsError


def safe_name(label: str, fallback: str = "results") -> str:
    """``label`` as a plain file name: letters, digits, '-', '_' and '.' only,
    no leading dot (never a path, never hidden, never empty)."""
    s = re.sub(r"[^A-Za-z0-9._-]+", "_", str(label)).strip("._")
    return s or fallback


def _fsync(path: Path):
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_dir(folder: Path):
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # pragma: no cover - a platform without directory handles
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
    finally:
        os.close(fd)


class Writeback:
    """The pages of a growing file that ``replacing`` will fsync once complete,
    written to the disk while the file grows: ``kick()`` (after a flush) starts
    one fsync of ``path`` on a thread of its own unless one is under way (fsync
    lets other threads run), so that the final fsync, which the run waits for
    alone, finds little left: the main job's 1,000,000-candidate file (114 MB)
    took 0.18 s there.  The same pages go to the disk either way; an error is
    the final fsync's to report."""

    def __init__(self, path):
        self.path = Path(path)
        self._pool = self._busy = None

    def kick(self):
        if self._busy is not None and not self._busy.done():
            return
        if self._pool is None:
            from concurrent.futures import ThreadPoolExecutor
            self._pool = ThreadPoolExecutor(1, thread_name_prefix="pipeline-writeback")
        self._busy = self._pool.submit(self._sync)

    def _sync(self):
        try:
            _fsync(self.path)
        except OSError:
            pass

    def close(self):
        """Wait for the fsync under way, if any."""
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None


# The fault-injection hook of the tests (tests/base/test_faults.py): the environment
# variable names a point of the write path where the process kills itself with
# SIGKILL, as a power cut or `kill -9` would, so that a test knows the point was
# reached.  Unset (always, outside the tests) it costs one dictionary lookup.
FAULT_VARIABLE = "PIPELINE_FAULT"


def fault_point(name: str, target=None):
    """Die here (SIGKILL) if ``PIPELINE_FAULT`` names this point; with
    ``PIPELINE_FAULT=point:text`` only where ``text`` is in the target's name."""
    want = os.environ.get(FAULT_VARIABLE)
    if not want:
        return
    point, _, match = want.partition(":")
    if point == name and (not match or match in str(target or "")):
        import signal
        os.kill(os.getpid(), signal.SIGKILL)


def temporary_beside(target) -> Path:
    """A new, empty temporary file in ``target``'s folder, created exclusively
    (O_EXCL: a name planted there, a symbolic link included, is never followed)
    under an unpredictable name that keeps the target's suffix (writers that go
    by the suffix, such as matplotlib, still work) and carries this process's
    id (``_remove_stale`` clears a killed writer's file)."""
    target = Path(target)
    fd, name = tempfile.mkstemp(prefix=f".{target.stem}.{os.getpid()}.tmp-",
                                suffix=f".partial{target.suffix}", dir=target.parent)
    try:
        mask = os.umask(0)
        os.umask(mask)
        os.fchmod(fd, 0o666 & ~mask)    # the mode any new file gets, not mkstemp's 0600
    finally:
        os.close(fd)
    return Path(name)


# a temporary file's name (``temporary_beside``): its target's stem and suffix, the
# writer's process id (the name ends in one way only: the id, its random part, "partial")
_TEMPORARY = re.compile(r"\.(?P<stem>.+)\.(?P<pid>\d+)(?:\.tmp-[A-Za-z0-9_]+)?"
                        r"\.partial(?P<suffix>(?:\.[^.]+)?)")


def _remove_stale(target: Path):
    """Temporary files of ``target`` left by a process that was killed (their
    process id is gone); the whole name must match, so another file's
    temporary file is never touched."""
    for p in target.parent.glob(f".{glob.escape(target.stem)}.*.partial{glob.escape(target.suffix)}"):
        m = _TEMPORARY.fullmatch(p.name)
        if m and m["stem"] == target.stem and m["suffix"] == target.suffix:
            _remove_if_dead(p, int(m["pid"]))


def remove_stale_in(folder: Path):
    """Every temporary file in ``folder`` left by a process that was killed, at
    once: for a folder that one run writes many files into (a journal), which
    then writes each with ``replacing(..., stale=False)`` instead of looking
    through the whole folder for every file."""
    for p in Path(folder).glob(".*.partial*"):
        m = _TEMPORARY.fullmatch(p.name)
        if m:
            _remove_if_dead(p, int(m["pid"]))


def _remove_if_dead(p: Path, pid: int):
    """``p`` removed where process ``pid``, its writer, is gone."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        p.unlink(missing_ok=True)
    except OSError:
        pass


# ----------------------------------------------------------------- output paths
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def is_hdf5(path) -> bool:
    """Whether ``path`` (a link followed) holds an HDF5 file: its signature at
    the start or after a user block (512 bytes, 1 KiB, 2 KiB, ...)."""
    try:
        with open(path, "rb") as fh:
            size, at = os.fstat(fh.fileno()).st_size, 0
            while at + 8 <= size:
                fh.seek(at)
                if fh.read(8) == HDF5_SIGNATURE:
                    return True
                at = 512 if at == 0 else 2 * at
    except OSError:
        return False
    return False


def _same_file(a, b) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:          # one of them is not there (or not reachable)
        return os.path.realpath(a) == os.path.realpath(b)


def _where(path) -> Path:
    """Where a write to ``path`` lands: ``path`` if it is there (a file, a
    folder or a link), else, since the folders on the way that are missing are
    made as folders ("new/../x.h5" is x.h5), the tidy name of that place (the
    links in the folders that are there followed only where needed)."""
    path = Path(path)
    if os.path.lexists(path):
        return path
    real = Path(os.path.realpath(path.parent)) / path.name
    tidy = Path(os.path.normpath(path))
    return tidy if Path(os.path.realpath(tidy.parent)) / tidy.name == real else real


def check_output(path, *, inputs=(), replaces=None, overwrite=False) -> Path:
    """Refuse, before anything is computed, an output path whose write would
    lose something (ResultsError, one line naming ``path`` and what to do):
    a folder, a symbolic link to nothing (the write would create its target
    wherever it points), a file the command reads (``inputs``, links and hard
    links included; even with --overwrite).

    ``replaces``: for a command that writes results files, the test that an
    existing file is one (``results.storage.is_results_file``, by its format):
    only such a file is replaced, and only with ``overwrite`` (a link is
    followed only to one).  None for pictures, pages and tables: they replace
    an earlier one of theirs, never an HDF5 file (a results file) and never
    through a symbolic link, whose target would be an unrelated file.

    Returns the path to write: ``path`` itself, or where it leads when a
    folder on the way is not there yet ("new/../x.h5" is x.h5)."""
    given, path = Path(path), _where(path)
    if path.is_symlink() and not path.exists():
        raise ResultsError(given, f"is a symbolic link to nothing ({os.readlink(path)}); "
                                  "refusing to create a file through it: delete the link or "
                                  "give another name")
    if path.is_dir():
        raise ResultsError(given, "is a folder; give a file name")
    for p in inputs:
        if p is not None and _same_file(path, p):
            same = "" if Path(p) == given else f" ({p})"
            raise ResultsError(given, f"is a file this command reads{same}; its output would "
                                      "replace it: give another output name")
    if not path.exists():
        return path
    if replaces is None:
        if path.is_symlink():
            raise ResultsError(given, f"is a symbolic link (to {os.readlink(path)}); refusing "
                                      "to write through it: delete the link or give another "
                                      "name")
        if is_hdf5(path):
            raise ResultsError(given, "is an HDF5 file (a results file); this command's output "
                                      "would replace it: give another name")
        return path
    if not replaces(path):
        raise ResultsError(given, "is not a pipeline results file (by its format); refusing "
                                  "to replace it, as every command does: give another name")
    if not overwrite:
        raise ResultsError(given, "already exists; --overwrite replaces it, -o writes "
                                  "another file")
    return path


def check_output_folder(folder) -> Path:
    """Refuse a folder for outputs that is a file, or a symbolic link to
    nothing (the folder would be made wherever it points)."""
    given, folder = Path(folder), _where(folder)
    if folder.is_symlink() and not folder.exists():
        raise ResultsError(given, f"is a symbolic link to nothing ({os.readlink(folder)}); "
                                  "refusing to make a folder through it: delete the link or "
                                  "give another folder")
    if folder.exists() and not folder.is_dir():
        raise ResultsError(given, "is a file; give a folder for the outputs")
    return folder


def refuse_link(path, what="a results file"):
    """A symbolic link where a run writes its own files (a journal folder, a
    lock) is refused: it would send the run's writes elsewhere."""
    path = Path(path)
    if path.is_symlink():
        raise ResultsError(path, f"is a symbolic link where {what} belongs; refusing to write "
                                 "through it (delete the link)")


class RunLock:
    """One writer per results file: a second run on the same file, or an
    analysis while a sweep writes it, is refused at once (an advisory lock on
    a hidden file beside it, released when the process ends, however it
    ends, and removed when the run ends)."""

    def __init__(self, out, what="another run is writing this file"):
        self.out = Path(out)
        real = Path(os.path.realpath(out))     # two links to one file: one lock
        self.path = real.with_name(f".{real.name}.lock")
        self.what = what

    def __enter__(self):
        import fcntl
        self.path.parent.mkdir(parents=True, exist_ok=True)
        refuse_link(self.path, "a run's lock file")
        while True:
            try:
                self.fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW
                                  | os.O_CLOEXEC, 0o644)
            except OSError as e:
                if e.errno == errno.ELOOP:
                    refuse_link(self.path, "a run's lock file")
                raise
            try:
                fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                os.close(self.fd)
                raise ResultsError(self.out, f"{self.what}; wait for it to finish, or write to "
                                             "another file with -o") from None
            # the lock holds only if the name still leads to the file locked: a run
            # that just ended removed it (and a new one may have been made)
            held = os.fstat(self.fd)
            try:
                now = os.stat(self.path, follow_symlinks=False)
            except FileNotFoundError:
                now = None
            if now is not None and (now.st_ino, now.st_dev) == (held.st_ino, held.st_dev):
                return self
            os.close(self.fd)

    def __exit__(self, *exc):
        import fcntl
        try:
            os.unlink(self.path)        # while locked: no other run holds this name
        except FileNotFoundError:
            pass
        fcntl.flock(self.fd, fcntl.LOCK_UN)
        os.close(self.fd)


def errno_of(e: Exception):
    """The operating system's error number behind ``e``: its own, or the one
    HDF5 folds into its text (h5py raises RuntimeError for a failed flush)."""
    if getattr(e, "errno", None):
        return e.errno
    m = re.search(r"errno = (\d+)", str(e))
    return int(m.group(1)) if m else None


def naming(e: Exception, target) -> OSError:
    """``e`` as an OSError that names ``target`` (the file the user asked
    for), not the temporary file or nothing at all."""
    code = errno_of(e)
    reason = os.strerror(code) if code else " ".join(str(e).split()) or type(e).__name__
    return OSError(code, reason, str(target))


@contextmanager
def replacing(target, copy_of=None, stale=True):
    """Yield a temporary path to write ``target`` to; on success it is flushed
    and renamed over ``target``, on any error (or interruption) removed.  A
    target that is a symbolic link is written through: the file it leads to is
    replaced, the link stays (a link to nothing is refused: ``check_output``).
    An operating-system error names ``target``.

    ``copy_of``: start from a copy of that file (an in-place update, such as
    the analysis of a sweep, is made on the copy and swapped in).  ``stale``:
    a killed writer's temporary files of ``target`` are removed first (False:
    the caller cleared the folder once, ``remove_stale_in``)."""
    target = Path(target)
    if target.is_symlink():
        if not target.exists():
            check_output(target)        # a link to nothing: refused, its target not made
        target = Path(os.path.realpath(target))
    if target.is_dir():
        raise ResultsError(target, "is a folder; give a file name")
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        if stale:
            _remove_stale(target)
        tmp = temporary_beside(target)
    except OSError as e:
        raise naming(e, target) from None
    try:
        if copy_of is not None:
            shutil.copyfile(copy_of, tmp)
        yield tmp
        fault_point("before-fsync", target)
        _fsync(tmp)
        fault_point("before-rename", target)
        os.replace(tmp, target)
        _fsync_dir(target.parent)
    except BaseException as e:
        try:
            tmp.unlink()
        except FileNotFoundError:
            pass
        if (isinstance(e, OSError) and not isinstance(e, FileNotFoundError)
                or isinstance(e, RuntimeError) and errno_of(e)):
            raise naming(e, target) from None
        raise


def write_text(target, text: str):
    """``target`` gets ``text`` (UTF-8) atomically."""
    with replacing(target) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(target)


def save_figure(fig, target, **kw):
    """``fig.savefig`` to ``target`` atomically (``check_output``: never over a
    results file, never through a link); returns the path."""
    check_output(target)
    with replacing(target) as tmp, literal_text(fig), laid_out_once(fig, kw.get("dpi")):
        fig.savefig(tmp, **kw)
    return Path(target)


@contextmanager
def literal_text(fig):
    """Draw ``fig`` with every text as written: a study's names and titles are
    the user's text, and a '$' in them is a dollar sign, not the start of a
    formula (matplotlib's mathtext fails on an unclosed one, after the whole
    computation).  The texts drawn so far are switched over, and the tick
    labels made while drawing follow the setting."""
    import matplotlib
    from matplotlib.text import Text
    for t in fig.findobj(Text):
        t.set_parse_math(False)
    with matplotlib.rc_context({"text.parse_math": False}):
        yield fig


@contextmanager
def laid_out_once(fig, dpi=None):
    """Save ``fig`` (at ``dpi``, else the saving default) with one drawing:
    its layout is done here, at the resolution it is saved at, and held while
    it is saved.  matplotlib's ``savefig`` would otherwise draw the whole figure
    once unseen, only to lay it out, then again for the picture (the picture
    is the same byte for byte; a scene's pictures take a tenth less time, its
    many-panel kinematics a fifth)."""
    import matplotlib
    engine = fig.get_layout_engine()
    if engine is None:
        yield fig
        return
    dpi = matplotlib.rcParams["savefig.dpi"] if dpi is None else dpi
    dpi = fig.dpi if dpi == "figure" else dpi
    screen = fig.dpi
    fig.dpi = dpi
    try:
        engine.execute(fig)
    finally:
        fig.dpi = screen
    fig.set_layout_engine(None)
    try:
        yield fig
    finally:
        fig.set_layout_engine(engine)


def os_error_text(e: OSError) -> str:
    """One line for an operating-system error: the file and the reason.
    h5py folds errno and the file name into a long text; a temporary name is
    given as the file it stands for."""
    msg = str(e)
    name = str(e.filename or "")
    m = re.search(r"name = '([^']*)'", msg)
    if m and not name:
        name = m.group(1)
    if isinstance(e, BlockingIOError) or "unable to lock file" in msg:
        return (f"{name}: another run or program has this file open for writing" if name
                else "a file is open for writing in another run or program")
    m = re.search(r"errno = (\d+)", msg)
    if m:
        reason = os.strerror(int(m.group(1)))
    elif e.strerror and "(" not in e.strerror:
        reason = e.strerror
    else:
        reason = msg.splitlines()[0] if msg else type(e).__name__
    name = re.sub(r"(^|/)\.([^/]+)\.\d+(?:\.tmp-[A-Za-z0-9_]+)?\.partial(\.[^/]*)?$",
                  r"\1\2\3", name)
    name = re.sub(r"\.tmp$", "", name)
    return f"{name}: {reason}" if name else reason
