"""Monte-Carlo sweeps: chunks of candidates evaluated by the compiled kernel,
locally on all cores or on a Dask cluster, written to HDF5 chunk by chunk.

Never losing finished work: every finished chunk is first saved atomically
(write to a temporary name, then rename) in a journal folder ``OUT.h5.parts``
next to the results file, then written into the HDF5 file.  The journal is the
source of truth until the run completes: ``--resume`` rebuilds the HDF5 file
from it (so a file damaged by kill -9 in the middle of a write costs nothing)
and computes only the chunks still missing.  On completion the journal is
removed.  Chunks are deterministic (see ``sweep_spec``), so an interrupted and
resumed run gives exactly the same datasets as an uninterrupted one.
"""

from __future__ import annotations

import contextlib
import logging
import os
import time
from dataclasses import dataclass
from pathlib import Path

import h5py

from ..base.files import RunLock, fault_point, replacing
from ..base.limits import CHUNK_WHY, MAX_CHUNK
from ..results.storage import FORMAT, hdf5_writing, room_for, same_study
from ..base.errors import ResultsError
from ..study.sweep_spec import SweepSpec
# the problem a worker evaluates has a module of its own (problem.py)
from .problem import SweepProblem, plain_problem
from ..compiler.notice import compile_notice
from .builds import Watch
# the journal and the results file have modules of their own
from ..results.journal import MANIFEST_DEFAULTS, Journal, manifest_for
from ..results.sweep_file import SweepFile, summarize

log = logging.getLogger("pipeline")

def _device(spec: SweepSpec, distributed) -> str:
    """The device a run takes ('cpu' or 'gpu'), before anything is written: a
    GPU asked for and missing is an error naming what is missing."""
    if distributed:
        if spec.device == "gpu":
            raise ValueError("--device gpu runs the sweep on this machine's GPU; a Dask "
                             "cluster (--scheduler) runs it on the workers' CPUs: choose one")
        return "cpu"
    if spec.device == "cpu":
        return "cpu"
    try:
        from .gpu import choose
    except Exception as e:     # numba.cuda itself does not import
        if spec.device == "auto":
            log.info("device auto: the CPU (numba.cuda does not import: %s)", e)
            return "cpu"
        raise ValueError(f"--device gpu: numba.cuda does not import ({e}); "
                         "pip install -e '.[gpu]' brings numba-cuda") from None
    return choose(spec.device)


def build_problem(study, spec: SweepSpec, tols=None, device="cpu") -> SweepProblem:
    """The sweep's problem (``problem.plain_problem``) with the builds of its
    robust metrics if it asks for one (``builds.robust_for``)."""
    from .builds import robust_for
    problem = plain_problem(study, spec, tols, device)
    problem.robust = robust_for(study, spec)
    if study.mechanism.friction is not None:
        from .sweep_friction import SweepFriction
        problem.friction = SweepFriction(study.mechanism, problem.plan)
    return problem


def evaluate_chunk_task(problem, chunk):
    """Dask task: one chunk on one worker thread."""
    return problem.evaluate_chunk(chunk, parallel=False)


# ----------------------------------------------------------------- running
@dataclass
class SweepOutcome:
    kind: str
    results: Path
    pictures: list
    summary: dict


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


def _check_existing(out: Path, journal: Journal, study, spec, resume: bool,
                    overwrite: bool = False):
    want = manifest_for(study, spec)
    check_existing(
        out, journal, resume, overwrite,
        journal_diff=lambda man: [k for k in want if k != "study_file"
                                  and man.get(k, MANIFEST_DEFAULTS.get(k)) != want[k]],
        same_results=lambda f: (same_study(f, study)
                                and int(f.attrs.get("n_candidates", -1)) == spec.candidates),
        what="sweep", other="or another candidate count")


def run_sweep(study, out, *, candidates=None, resume=False, overwrite=False, scheduler=None,
              client=None, n_jobs=None, chunk_size=None, progress=True,
              stop_after_chunks=None, device=None, store=None) -> SweepOutcome:
    """Run (or resume) a sweep study into ``out``.  With ``resume`` the
    candidate count and chunk size come from the interrupted run's journal
    (or the finished file) unless given; ``overwrite`` replaces a finished
    file.  ``device`` (cpu | gpu | auto) and ``store`` (all | feasible)
    override the study's [sweep] device and store."""
    from dataclasses import replace
    from ..study.sweep_spec import DEVICES, STORES
    spec: SweepSpec = study.sweep
    for name, value, allowed in (("device", device, DEVICES), ("store", store, STORES)):
        if value is not None and value not in allowed:
            raise ValueError(f"--{name} must be one of {', '.join(allowed)}, got {value!r}")
    spec = replace(spec, device=device or spec.device, store=store or spec.store)
    if resume:
        n, ch = _run_sizes(Path(out))
        candidates = n if candidates is None else candidates
        chunk_size = ch if chunk_size is None else chunk_size
    if candidates is not None:
        if candidates < 1:
            raise ValueError(f"--candidates must be at least 1, got {candidates}")
        spec = spec.with_candidates(candidates)
    if chunk_size is not None:
        if not 1 <= chunk_size <= MAX_CHUNK:
            raise ValueError(f"--chunk-size must be between 1 and {MAX_CHUNK:,} ({CHUNK_WHY}), "
                             f"got {chunk_size:,}")
        spec = replace(spec, chunk_size=chunk_size)
    scheduler = scheduler or spec.scheduler
    out = Path(out)
    with RunLock(out):
        return _run_locked(study, spec, out, resume, overwrite, scheduler, client, n_jobs,
                           progress, stop_after_chunks)


def _run_sizes(out: Path):
    """(candidates, chunk size) of the run that wrote ``out``: from its journal
    if it was interrupted, else from the file; (None, None) if neither says."""
    journal = Journal(out)
    if journal.exists():
        man = journal.manifest()
        return man.get("candidates"), man.get("chunk_size")
    if out.exists():
        try:
            with h5py.File(out, "r") as f:
                n, ch = f.attrs.get("n_candidates"), f.attrs.get("chunk_size")
                return (int(n) if n is not None else None), (int(ch) if ch is not None else None)
        except OSError:
            pass
    return None, None


def _run_locked(study, spec, out, resume, overwrite, scheduler, client, n_jobs, progress,
                stop_after_chunks):
    journal = Journal(out)
    _check_existing(out, journal, study, spec, resume, overwrite)
    done = aside_or_done(out, journal, resume, overwrite, "chunk", summarize)
    if done is not None:
        return done
    # said at once: what follows (the sampler's import, the kernels' load or
    # compile) takes a second or more before the first chunk's bar
    log.info("%s: a sweep of %s candidates into %s", study.name, f"{spec.candidates:,}", out)
    problem = build_problem(study, spec, device=_device(spec, scheduler or client))
    sf = SweepFile(out, study, problem)
    fresh = not journal.exists()
    own = scheduler is not None and client is None
    if own:
        client = _connect(scheduler)     # before anything is written
    try:
        with nothing_left_before_first(out, journal, fresh, "chunk"):
            if fresh:
                journal.start(dict(manifest_for(study, spec), replaces=out.exists()))
            sf.path = journal.working_file(out)
            return _run_chunks(study, spec, out, journal, problem, sf, client, n_jobs,
                               progress, stop_after_chunks)
    finally:
        if own:
            client.close()


def aside_or_done(out: Path, journal: Journal, resume: bool, overwrite: bool, unit: str,
                  summary):
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


def _run_chunks(study, spec, out, journal, problem, sf, client, n_jobs, progress,
                stop_after_chunks):
    # the file, fresh or rebuilt from the journal below; its reference design is the
    # first evaluation, which compiles a new mechanism's kernels (once, then cached)
    with compile_notice() as prep:
        sf.create()
    finished = set(journal.done())
    t0 = time.perf_counter()
    work = sf.path
    if finished:
        log.info("resuming: %d of %d chunks already done", len(finished), spec.n_chunks)
    # a resumed run's file is rebuilt from its journal: seconds for a large sweep
    with hdf5_writing(work, expendable=False) as f, \
            _reading_journal(journal, len(finished)) as line:
        d = sf.datasets(f)
        for i, c in enumerate(sorted(finished)):
            line.set(f"{i:,}/{len(finished):,} chunks")
            sf.write_chunk(d, c, *journal.load(c))    # kept rows and counts, if any
        f.flush()
    todo = [c for c in range(spec.n_chunks) if c not in finished]
    bar = _progress(spec, len(finished), progress)
    # locally the bar is told as a chunk's work goes (its robust builds slice by slice)
    watch = Watch(bar.update) if client is None else None
    computed = 0
    try:
        with hdf5_writing(work, expendable=False) as f:
            d = sf.datasets(f)
            flushed = time.monotonic()
            for c, x, status, metrics, rejected in _chunks(problem, todo, client, n_jobs,
                                                           watch):
                computed += len(status)
                if watch is None:
                    bar.update(len(status))
                kept = sf.kept(c, x, status, metrics)     # store = feasible: those rows only
                if kept is not None:
                    x, status, metrics, index, counts = kept
                    journal.save(c, x, status, metrics, rejected, index, counts)
                    sf.write_chunk(d, c, x, status, metrics, rejected, index, counts)
                else:
                    journal.save(c, x, status, metrics, rejected)   # the source of truth
                    sf.write_chunk(d, c, x, status, metrics, rejected)
                fault_point("chunk-written", out)
                if time.monotonic() - flushed > 1.0:    # the HDF5 file: once a second
                    f.flush()
                    flushed = time.monotonic()
                if stop_after_chunks is not None and computed >= stop_after_chunks * spec.chunk_size:
                    raise KeyboardInterrupt  # test hook: an interruption at a chunk boundary
    except KeyboardInterrupt:
        bar.close()
        done = len(journal.done())
        raise SweepInterrupted(f"{out}: interrupted with {done} of {spec.n_chunks} chunks "
                               "saved; run again with --resume to continue") from None
    except BaseException:
        bar.close()        # its redrawing thread ends with it (base.progress.bar)
        raise
    bar.close()
    with hdf5_writing(work, expendable=False) as f:
        sf.sort_rows(f)
    return finish_run(out, journal, client, time.perf_counter() - t0, prep[0], computed,
                      summarize, "candidates", device=problem.device_name)


def _reading_journal(journal: Journal, n: int):
    """Around a resumed run's read of its journal (``n`` chunks saved): a line
    that says so and counts its seconds (nothing for a fresh run)."""
    if not n:
        return contextlib.nullcontext(_NoLine())
    from ..base.progress import ticking
    return ticking(f"reading the journal {journal.dir.name}")


class _NoLine:
    def set(self, detail):
        pass


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
    journal.remove()
    res = summary(out)
    res["wall_time"] = f"{wall:.1f} s"
    if compile_s > 1.0:
        res["compile_time"] = f"{compile_s:.1f} s (not in the wall time; cached from now on)"
    if computed:
        res["throughput"] = f"{computed / wall:,.0f} {unit}/s"
    if device != "cpu":
        res["device"] = device
    return SweepOutcome("sweep", out, [], res)


class SweepInterrupted(KeyboardInterrupt):
    """Raised after an interruption, once everything finished is safe."""


def _progress(spec, done, enabled):
    """A bar on a terminal, plain lines elsewhere (base.progress)."""
    from ..base.progress import bar
    return bar(spec.candidates, initial=done * spec.chunk_size if done else 0, unit="cand",
               desc="sweep", enabled=enabled, unit_scale=True, smoothing=0.1)


def _chunks(problem, todo, client, n_jobs, watch=None):
    """Yield (chunk, x, status, metrics) as chunks finish.  Locally, when the
    caller stops (an interruption, a failure), the chunk at work stops at its
    next slice (``watch``) and the one queued behind it never starts."""
    if client is not None:
        yield from _dask_chunks(problem, todo, client)
        return
    if n_jobs is not None and n_jobs < 1:
        raise ValueError(f"--jobs must be at least 1, got {n_jobs}")
    # the next chunk is drawn and evaluated while the caller journals and writes
    # this one (the kernels run on the worker threads, HDF5 on this one)
    from concurrent.futures import ThreadPoolExecutor
    watch = Watch() if watch is None else watch
    ahead = ThreadPoolExecutor(1, thread_name_prefix="pipeline-chunks")
    try:
        pending = None
        for c in todo:
            nxt = ahead.submit(problem.evaluate_chunk, c, True, n_jobs, watch)
            if pending is not None:
                yield pending.result()
            pending = nxt
        if pending is not None:
            yield pending.result()
    except BaseException:       # KeyboardInterrupt, or the caller's own end (GeneratorExit)
        watch.stop()
        raise
    finally:
        ahead.shutdown(wait=True, cancel_futures=True)


CONNECT_TIMEOUT = "20s"     # how long to wait for a Dask scheduler to answer, unless
CONNECT_TIMEOUT_ENV = "PIPELINE_CONNECT_TIMEOUT"    # this variable says (seconds, or "30s")


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


def _dask_chunks(problem, todo, client):
    """The same kernels on the workers of a Dask ``client``."""
    from dask.distributed import as_completed
    remote = client.scatter(problem, broadcast=True)
    futures = [client.submit(evaluate_chunk_task, remote, c, pure=False) for c in todo]
    for fut in as_completed(futures):
        yield fut.result()
