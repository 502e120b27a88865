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

import glob
import os
import re
import shutil
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


def temporary_beside(target) -> Path:
    """A temporary name in ``target``'s folder that keeps its suffix (so
    writers that go by the suffix, such as matplotlib, still work)."""
    target = Path(target)
    return target.with_name(f".{target.stem}.{os.getpid()}.partial{target.suffix}")


def _remove_stale(target: Path):
    """Temporary files of ``target`` left by a process that was killed (their
    process id is gone); the whole name must match, so another file's
    temporary file is never touched."""
    pattern = re.compile(rf"\.{re.escape(target.stem)}\.(\d+)\.partial{re.escape(target.suffix)}")
    for p in target.parent.glob(f".{glob.escape(target.stem)}.*.partial{glob.escape(target.suffix)}"):
        m = pattern.fullmatch(p.name)
        if not m:
            continue
        try:
            os.kill(int(m.group(1)), 0)
        except ProcessLookupError:
            p.unlink(missing_ok=True)
        except OSError:
            continue


class RunLock:
    """One writer per results file: a second run on the same file, or an
    analysis while a sweep writes it, is refused at once (an advisory lock on
    a hidden file beside it, released when the process ends, however it
    ends)."""

    def __init__(self, out, what="another run is writing this file"):
        self.out = Path(out)
        self.path = self.out.with_name(f".{self.out.name}.lock")
        self.what = what

    def __enter__(self):
        import fcntl
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(self.fd)
            raise ResultsError(self.out, f"{self.what}; wait for it to finish, or write to "
                                         "another file with -o") from None
        return self

    def __exit__(self, *exc):
        import fcntl
        fcntl.flock(self.fd, fcntl.LOCK_UN)
        os.close(self.fd)


@contextmanager
def replacing(target, copy_of=None):
    """Yield a temporary path to write ``target`` to; on success it is flushed
    and renamed over ``target``, on any error (or interruption) removed.

    ``copy_of``: start from a copy of that file (an in-place update, such as
    the analysis of a sweep, is made on the copy and swapped in)."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    _remove_stale(target)
    tmp = temporary_beside(target)
    try:
        if copy_of is not None:
            shutil.copyfile(copy_of, tmp)
        yield tmp
        _fsync(tmp)
        os.replace(tmp, target)
        _fsync_dir(target.parent)
    except BaseException:
        try:
            tmp.unlink()
        except FileNotFoundError:
            pass
        raise


def write_text(target, text: str):
    """``target`` gets ``text`` (UTF-8) atomically."""
    with replacing(target) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(target)


def save_figure(fig, target, **kw):
    """``fig.savefig`` to ``target`` atomically; returns the path."""
    with replacing(target) as tmp:
        fig.savefig(tmp, **kw)
    return Path(target)


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
    name = re.sub(r"(^|/)\.([^/]+)\.\d+\.partial(\.[^/]*)?$", r"\1\2\3", name)
    name = re.sub(r"\.tmp$", "", name)
    return f"{name}: {reason}" if name else reason
