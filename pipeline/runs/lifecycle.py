"""The life of a run into one results file, the same for a Monte-Carlo sweep
(its units are chunks of candidates) and an adaptive search (its units are
generations); ``sweep.py`` and ``search.py`` say only what a unit is.  A GPU
sweep is a sweep whose problem evaluates on the GPU (``problem.SweepProblem``):
it goes through this life unchanged.

1. ``check_existing``: refuse anything that would overwrite or mix results
   silently; ``aside_or_done``: with --overwrite the earlier file stays as it
   is until the new one is complete, a --resume of a finished run is done.
2. ``journalled``: the Dask client if asked for (``connected``), the journal
   started (a fresh run) or taken up (a resumed one), and a fresh run that
   ends before its first unit is saved leaves nothing behind
   (``nothing_left_before_first``).
3. The units, each saved in the journal, the source of truth, before it goes
   into the results file (``SaveThenWrite``); an interruption keeps every
   finished unit and says how to go on (``stopping_safely``).
4. ``finish_run``: the file marked complete, a replacement renamed over the
   file it replaces, the journal removed, the run's summary.
"""

from __future__ import annotations

import contextlib
import logging
import os
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import h5py

from ..base.errors import ResultsError
from ..base.files import replacing
from ..results.journal import Journal
from ..results.storage import FORMAT, hdf5_writing, room_for

log = logging.getLogger("pipeline")


@dataclass
class SweepOutcome:
    kind: str
    results: Path
    pictures: list
    summary: dict


class SweepInterrupted(KeyboardInterrupt):
    """Raised after an interruption, once everything finished is safe."""


# ----------------------------------------------------------------- before writing
def check_existing(out: Path, journal: Journal, resume: bool, overwrite: bool, *,
                   journal_diff, same_results, what: str, other: str):
    """Refuse anything that would overwrite or mix results silently (a sweep's
    or a search's): ``journal_diff(manifest)`` lists what differs in an
    interrupted run's journal (or raises), ``same_results(f)`` says whether a
    finished file holds this run's results; ``what`` names the run ("sweep"),
    ``other`` what else a file may hold."""
    if not resume:
        if journal.exists():
            raise ResultsError(journal.dir, "holds an unfinished run; continue it with --resume "
                                            "(or delete the folder to start again)")
        if out.exists() and not overwrite:
            raise ResultsError(out, "already exists; --overwrite replaces it, -o writes "
                                    "another file, --resume continues an interrupted run")
        return
    if journal.exists():
        diff = journal_diff(journal.manifest())
        if diff:
            raise ResultsError(journal.dir, "belongs to another run (different "
                               + ", ".join(diff) + "); refusing to mix results")
        return
    if out.exists():
        _check_finished(out, same_results, what, other)


def _check_finished(out: Path, same_results, what: str, other: str):
    """A --resume without a journal: ``out`` must be this run's finished file."""
    try:
        with h5py.File(out, "r") as f:
            ours = f.attrs.get("format") == FORMAT
            same = ours and same_results(f)
            complete = bool(f.attrs.get("complete", False))
    except OSError:
        raise ResultsError(out, "is truncated or not an HDF5 file and there is no journal "
                                "to rebuild it from; refusing to touch it") from None
    if not ours:
        raise ResultsError(out, "is not a pipeline results file; refusing to write into it")
    if not same:
        raise ResultsError(out, f"holds another study's results ({other}); "
                                "refusing to write into it")
    if not complete:
        raise ResultsError(out, f"is an unfinished {what} whose journal is gone; "
                                "run again into a new file")


def aside_or_done(out: Path, journal: Journal, resume: bool, overwrite: bool, summary):
    """Before a run (sweep or search) writes: with --overwrite the finished file
    stays as it is, under its name, until the new run is complete (the new one
    is written in the journal folder, ``Journal.working_file``); a --resume of
    a finished run returns its outcome (``summary(out)``), else None."""
    if overwrite and out.exists() and not resume:
        log.info("replacing %s when the new run is complete (until then it stays as it is)",
                 out)
    if resume and not journal.exists() and out.exists():
        log.info("%s is already complete; nothing to resume", out)
        return SweepOutcome("sweep", out, [], summary(out))
    return None


# ----------------------------------------------------------------- the journal
def journalled(out: Path, journal: Journal, manifest: dict, unit: str, scheduler, client,
               run_units, first=None):
    """``run_units(client)`` inside the run's journal: the Dask client first
    (``connected``; before anything is written), then a fresh run's journal
    started with ``manifest`` (``first(journal)`` writes what must be there
    before the manifest that makes a journal of the folder), a resumed run's
    taken as it is.  A fresh run that ends before its first ``unit`` is saved
    leaves nothing behind."""
    fresh = not journal.exists()
    with connected(scheduler, client) as client, \
            nothing_left_before_first(out, journal, fresh, unit):
        if fresh:
            if first is not None:
                journal.dir.mkdir(parents=True, exist_ok=True)
                first(journal)
            journal.start(dict(manifest, replaces=out.exists()))
        journal.clear_stale()     # (a killed run's temporary files: once, not per unit)
        return run_units(client)


@contextlib.contextmanager
def nothing_left_before_first(out: Path, journal: Journal, fresh: bool, unit: str):
    """A fresh run (sweep or search) that fails or is stopped before its first
    ``unit`` is saved leaves nothing behind; a file it was to replace
    (``--overwrite``) was never touched."""
    replaces = out.exists()
    try:
        yield
    except BaseException as e:
        if fresh and not journal.done():
            journal.remove()
            if not replaces:
                out.unlink(missing_ok=True)
            if isinstance(e, KeyboardInterrupt):
                raise SweepInterrupted(f"{out}: interrupted before the first {unit} finished; "
                                       "nothing was written") from None
        raise


# ----------------------------------------------------------------- the units
class SaveThenWrite:
    """Finished units (chunks, generations) of a run: each saved in the journal,
    the source of truth, before it is written into the results file.
    ``save(units)`` journals a list of units, ``write(units)`` writes them into
    the open file given to ``open``.  Units are saved when ``save_every_s`` has
    passed since the last save and written (saved first) when
    ``write_every_s`` has passed since the last write (0: each at once); the
    file is flushed after a write when ``flush_every_s`` has passed, and then
    its pages go to the disk beside the run where ``writeback``
    (``base.files.Writeback``) is given: a file that is fsync'ed when complete."""

    def __init__(self, save, save_every_s=0.0, write_every_s=0.0, flush_every_s=0.0,
                 writeback=None):
        self._save, self._write, self.f = save, None, None
        self.writeback = writeback
        self.save_every_s, self.write_every_s = save_every_s, write_every_s
        self.flush_every_s = flush_every_s
        self.unsaved, self.unwritten = [], []
        self.writing = True
        self.saved_at = self.written_at = self.flushed_at = time.monotonic()

    def open(self, f, write):
        """Write into the open HDF5 file ``f`` by ``write(units)`` from now on."""
        self.f, self._write = f, write
        self.written_at = self.flushed_at = time.monotonic()

    def add(self, unit, saved=False):
        """A finished unit (``saved``: already in the journal, a resumed run's)."""
        if not saved:
            self.unsaved.append(unit)
        if self.writing:
            self.unwritten.append(unit)
        if _due(self.written_at, self.write_every_s):
            self.write()
        elif _due(self.saved_at, self.save_every_s):
            self.save()

    def save(self):
        """Every unit not yet journalled, now."""
        if self.unsaved:
            self._save(list(self.unsaved))
            self.unsaved.clear()
        self.saved_at = time.monotonic()

    def write(self):
        """Every unit not yet in the file, now (journalled first)."""
        self.save()
        if self.unwritten:
            self._write(list(self.unwritten))
            self.unwritten.clear()
            if _due(self.flushed_at, self.flush_every_s):
                self.f.flush()
                if self.writeback is not None:
                    self.writeback.kick()
                self.flushed_at = time.monotonic()
        self.written_at = time.monotonic()

    def stop_writing(self):
        """No more units go into this file (it is to be written again whole)."""
        self.writing = False
        self.unwritten.clear()


def _due(since: float, every_s: float) -> bool:
    return every_s == 0 or time.monotonic() - since > every_s


@contextlib.contextmanager
def stopping_safely(out: Path, journal: Journal, bar, total: int, unit: str,
                    kept: SaveThenWrite | None = None):
    """Around a run's units: the progress ``bar`` closed however they end; an
    interruption journals what is finished (``kept``) and says how many of the
    ``total`` units are saved and how to go on; a failure journals what it
    can."""
    try:
        yield
    except KeyboardInterrupt:
        bar.close()
        if kept is not None:
            kept.save()             # every finished unit is kept
        raise SweepInterrupted(f"{out}: interrupted with {len(journal.done())} of {total} "
                               f"{unit}s saved; run again with --resume to continue") from None
    except BaseException:
        bar.close()        # its redrawing thread ends with it (base.progress.bar)
        if kept is not None:
            with contextlib.suppress(Exception):
                kept.save()     # what was finished is kept where the failure allows
        raise
    bar.close()


# ----------------------------------------------------------------- the end
def finish_run(out: Path, journal: Journal, client, wall: float, compile_s: float,
               computed: int, summary, unit: str, device: str = "cpu") -> SweepOutcome:
    """A run (sweep or search) has written everything: the file is marked
    complete (a replacement is renamed over the file it replaces only now), the
    journal goes, and its outcome says the wall time, the compile time apart
    and the throughput (``summary(out)``: the file's own summary; ``unit``:
    what was computed)."""
    work = journal.working_file(out)
    room_for(work, 0)
    with hdf5_writing(work, expendable=False) as f:
        f.attrs["complete"] = True
        f.attrs["wall_time_s"] = wall
        f.attrs["engine"] = "dask" if client is not None else "local"
        f.attrs["device"] = device
    if work != out:
        with replacing(out) as tmp:     # the earlier file is replaced whole, now
            os.replace(work, tmp)
    # the journal's files go on a thread of their own while the summary reads the
    # file (unlinking them lets other threads run: 0.15 s for the main job's 100)
    remover = threading.Thread(target=journal.remove, name="pipeline-journal-remove")
    remover.start()
    try:
        res = summary(out)
    finally:
        remover.join()
    res["wall_time"] = f"{wall:.1f} s"
    if compile_s > 1.0:
        res["compile_time"] = f"{compile_s:.1f} s (not in the wall time; cached from now on)"
    if computed:
        res["throughput"] = f"{computed / wall:,.0f} {unit}/s"
    if device != "cpu":
        res["device"] = device
    return SweepOutcome("sweep", out, [], res)


# ----------------------------------------------------------------- a Dask cluster
CONNECT_TIMEOUT = "20s"     # how long to wait for a Dask scheduler to answer, unless
CONNECT_TIMEOUT_ENV = "PIPELINE_CONNECT_TIMEOUT"    # this variable says (seconds, or "30s")


@contextlib.contextmanager
def connected(scheduler, client):
    """The run's Dask client: ``client`` as given, a new one of ``scheduler``
    (closed at the end), or None (this machine's cores)."""
    if scheduler is None or client is not None:
        yield client
        return
    own = _connect(scheduler)
    try:
        yield own
    finally:
        own.close()


def _connect_timeout() -> float:
    """Seconds to wait for a Dask scheduler: $PIPELINE_CONNECT_TIMEOUT, else
    CONNECT_TIMEOUT."""
    from dask.utils import parse_timedelta
    text = os.environ.get(CONNECT_TIMEOUT_ENV, "").strip() or CONNECT_TIMEOUT
    try:
        s = float(parse_timedelta(text, default="seconds"))
    except (ValueError, KeyError, TypeError):
        s = float("nan")
    if not 0 < s < float("inf"):
        raise ValueError(f"{CONNECT_TIMEOUT_ENV}: {text!r} is not a time to wait (seconds "
                         "above 0, e.g. 30 or 30s)")
    return s


def _connect(scheduler):
    """A client of the Dask scheduler at ``scheduler``; dask is imported only here.
    The wait says what it waits for and how long at most, and counts its seconds
    (an unreachable scheduler is retried until the timeout)."""
    from ..base.progress import ticking
    needs = "--scheduler needs dask: pip install 'pipeline[dask]'"
    try:
        timeout = _connect_timeout()
    except ImportError:  # pragma: no cover - depends on the installation
        raise ValueError(needs) from None
    with ticking(f"connecting (at most {timeout:g} s) to the Dask scheduler {scheduler}",
                 say_done=False):
        try:
            from dask.distributed import Client
        except ImportError:  # pragma: no cover - depends on the installation
            raise ValueError(needs) from None
        try:
            return Client(scheduler, timeout=timeout)
        except (OSError, TimeoutError) as e:
            raise ValueError(f"cannot reach the Dask scheduler {scheduler} within {timeout:g} s "
                             f"({CONNECT_TIMEOUT_ENV} sets how long to wait): {e}") from None
