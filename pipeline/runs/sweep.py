"""Monte-Carlo sweeps: chunks of candidates evaluated by the compiled kernel,
locally on all cores, on a Dask cluster or on this machine's GPU, written to
HDF5 chunk by chunk.

The run's life (refusals, journal, save-then-write, completion) is
``lifecycle``'s, shared with the adaptive search; here is what a chunk is.
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
import time
from pathlib import Path

import h5py
import numpy as np

from ..base.files import RunLock, Writeback, fault_point
from ..base.limits import CHUNK_WHY, MAX_CHUNK
from ..results.storage import hdf5_writing, same_study
from ..study.objectives import feasibility
from ..study.sweep_spec import SweepSpec
# the problem a worker evaluates has a module of its own (problem.py)
from .problem import SweepProblem, plain_problem
from ..compiler.notice import compile_notice
from .builds import Watch
from .draw_ahead import drawing_ahead
# the journal and the results file have modules of their own
from ..results.journal import MANIFEST_DEFAULTS, Journal, manifest_for
from ..results.sweep_file import SweepFile, counted, summarize
from .lifecycle import (SaveThenWrite, SweepOutcome, aside_or_done, check_existing, finish_run,
                        journalled, stopping_safely)

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
    done = aside_or_done(out, journal, resume, overwrite, summarize)
    if done is not None:
        return done
    # said at once: what follows (the sampler's import, the kernels' load or
    # compile) takes a second or more before the first chunk's bar
    log.info("%s: a sweep of %s candidates into %s", study.name, f"{spec.candidates:,}", out)
    problem = build_problem(study, spec, device=_device(spec, scheduler or client))
    sf = SweepFile(out, study, problem)

    def run_chunks(client):
        sf.path = journal.working_file(out)
        # the sampler's import and the draws in a process beside, from now on
        with drawing_ahead(problem, client is None) as draw:
            return _run_chunks(spec, out, journal, problem, sf, client, n_jobs, progress,
                               stop_after_chunks, draw)
    return journalled(out, journal, manifest_for(study, spec), "chunk", scheduler, client,
                      run_chunks)


def _run_chunks(spec, out, journal, problem, sf, client, n_jobs, progress, stop_after_chunks,
                draw=None):
    # the file, fresh or rebuilt from the journal below; its reference design is the
    # first evaluation, which compiles a new mechanism's kernels (once, then cached)
    with compile_notice() as prep:
        sf.create()
    finished = set(journal.done())
    t0 = time.perf_counter()
    if finished:
        log.info("resuming: %d of %d chunks already done", len(finished), spec.n_chunks)
    _rebuild(sf, journal, finished)
    todo = [c for c in range(spec.n_chunks) if c not in finished]
    bar = _progress(spec, len(finished), progress)
    # locally the bar is told as a chunk's work goes (its robust builds slice by slice)
    watch = Watch(bar.update) if client is None else None
    # a replacement (written in the journal folder, renamed over ``out`` when
    # complete) is fsync'ed then: its pages go to the disk as it grows
    writeback = Writeback(sf.path) if Path(sf.path) != Path(out) else None
    record = SaveThenWrite(lambda chunks: [journal.save(*_journal_part(c)) for c in chunks],
                           flush_every_s=1.0, writeback=writeback)  # the file: once a second
    computed = 0
    # each chunk is journalled as it comes: on a failure nothing is kept back to save
    with stopping_safely(out, journal, bar, spec.n_chunks, "chunk"), \
            hdf5_writing(sf.path, expendable=False) as f, \
            (contextlib.closing(writeback) if writeback else contextlib.nullcontext()):
        d = sf.datasets(f)
        record.open(f, lambda chunks: _write(sf, d, chunks, out))
        for c, x, status, metrics, rejected, kept in _chunks(problem, todo, client, n_jobs,
                                                             watch, draw):
            computed += len(status)
            if watch is None:
                bar.update(len(status))
            record.add(_stored(sf, c, x, status, metrics, rejected, kept))
            if stop_after_chunks is not None and computed >= stop_after_chunks * spec.chunk_size:
                raise KeyboardInterrupt  # test hook: an interruption at a chunk boundary
    with hdf5_writing(sf.path, expendable=False) as f:
        sf.sort_rows(f)
    return finish_run(out, journal, client, time.perf_counter() - t0, prep[0], computed,
                      summarize, "candidates", device=problem.device_name)


def _stored(sf: SweepFile, c, x, status, metrics, rejected, kept=None):
    """What chunk ``c`` stores, (c, x, status, metrics, judged, rejected, index,
    counts): every row (index and counts None), or with store = feasible its
    feasible rows, ``index`` their candidate indices and ``counts`` the chunk's
    candidates per status and feasible.  ``kept``: the rows the GPU judged
    feasible, ``metrics`` theirs alone (``SweepProblem.evaluate_chunk``): judged
    here again, where a row judged otherwise stops the run."""
    lo, _ = sf.spec.chunk_bounds(c)
    if kept is not None:
        status_kept = status[kept]
        judged = feasibility(sf.spec, status_kept, metrics, sf.problem.has_margin)
        if not judged.feasible.all():
            bad = lo + kept[~judged.feasible]
            raise RuntimeError(f"chunk {c}: the GPU kept candidates {bad[:5].tolist()} as "
                               "feasible and the host judges them otherwise (a defect: "
                               "report it)")
        feasible = np.zeros(len(status), bool)
        feasible[kept] = True
        return (c, x[kept], status_kept, metrics, judged, rejected, lo + kept,
                counted(status, feasible))
    judged = feasibility(sf.spec, status, metrics, sf.problem.has_margin)
    if not sf.feasible_only:
        return c, x, status, metrics, judged, rejected, None, None
    keep = np.flatnonzero(judged.feasible)
    return (c, x[keep], status[keep], metrics[keep], judged.rows(keep), rejected, lo + keep,
            counted(status, judged.feasible))


def _journal_part(chunk):
    """What the journal keeps of a stored chunk (``_stored``): all but ``judged``."""
    c, x, status, metrics, _, rejected, index, counts = chunk
    return c, x, status, metrics, rejected, index, counts


def _write(sf: SweepFile, d, chunks, out):
    """Stored chunks (``_stored``) into the datasets ``d``."""
    for chunk in chunks:
        sf.write_chunk(d, *chunk)
        fault_point("chunk-written", out)


def _rebuild(sf: SweepFile, journal: Journal, finished):
    """A resumed run's file rebuilt from its journal (the chunks ``finished``):
    seconds for a large sweep."""
    with hdf5_writing(sf.path, expendable=False) as f, \
            _reading_journal(journal, len(finished)) as line:
        d = sf.datasets(f)
        for i, c in enumerate(sorted(finished)):
            line.set(f"{i:,}/{len(finished):,} chunks")
            x, status, metrics, rejected, *kept = journal.load(c)   # kept rows and counts
            judged = feasibility(sf.spec, status, metrics, sf.problem.has_margin)
            sf.write_chunk(d, c, x, status, metrics, judged, rejected, *kept)
        f.flush()


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


def _progress(spec, done, enabled):
    """A bar on a terminal, plain lines elsewhere (base.progress)."""
    from ..base.progress import bar
    return bar(spec.candidates, initial=done * spec.chunk_size if done else 0, unit="cand",
               desc="sweep", enabled=enabled, unit_scale=True, smoothing=0.1)


def _chunks(problem, todo, client, n_jobs, watch=None, draw=None):
    """Yield (chunk, x, status, metrics) as chunks finish.  Locally, when the
    caller stops (an interruption, a failure), the chunk at work stops at its
    next slice (``watch``) and the one queued behind it never starts.  ``draw``:
    the draws' source (``SweepProblem.draw_chunk``), where not this process."""
    if client is not None:
        yield from _dask_chunks(problem, todo, client)
        return
    if n_jobs is not None and n_jobs < 1:
        raise ValueError(f"--jobs must be at least 1, got {n_jobs}")
    # the next chunk is evaluated while the caller journals and writes this one
    # (the kernels run on the worker threads, HDF5 on this one), and the chunks
    # after it are drawn meanwhile, in order (a Sobol sequence continues), so that
    # no core waits on the sampler between two chunks.  On k > 1 cores the plain
    # kernels run k chunks side by side, each whole on one thread (one call):
    # split in ranges, a chunk's threads met at its end, each range came back
    # for the GIL, and a thread the writing main thread held up kept the other
    # waiting (3 % of the threads' time); a candidate's numbers are its own.
    # The last chunk is shared out in ranges again: no thread waits alone for it
    from collections import deque
    from concurrent.futures import ThreadPoolExecutor
    from ..compiler.parallel import default_jobs
    watch = Watch() if watch is None else watch
    jobs = default_jobs() if n_jobs is None else n_jobs
    # (at most MAX_CHUNK rows side by side: what a chunk may hold stays in memory)
    side = min(jobs, max(1, MAX_CHUNK // problem.spec.chunk_size)) if (
        jobs > 1 and _side_by_side(problem)) else 1
    chunk_jobs = 1 if side > 1 else n_jobs
    ahead = ThreadPoolExecutor(side, thread_name_prefix="pipeline-chunks")
    drawer = ThreadPoolExecutor(1, thread_name_prefix="pipeline-draws")
    draws = {}

    def evaluate(c, threads):
        return problem.evaluate_chunk(c, True, threads, watch, draws.pop(c).result())
    try:
        pending = deque()
        for i, c in enumerate(todo):
            for d in todo[i:i + 2]:      # drawn in order, one chunk ahead
                if d not in draws:
                    draws[d] = drawer.submit(problem.draw_chunk, d, draw)
            pending.append(ahead.submit(evaluate, c, n_jobs if i == len(todo) - 1
                                        else chunk_jobs))
            if len(pending) > side:     # one more queued: no thread waits for the caller
                yield pending.popleft().result()
        while pending:
            yield pending.popleft().result()
    except BaseException:       # KeyboardInterrupt, or the caller's own end (GeneratorExit)
        watch.stop()
        raise
    finally:
        ahead.shutdown(wait=True, cancel_futures=True)
        drawer.shutdown(wait=True, cancel_futures=True)


def _side_by_side(problem) -> bool:
    """Whether chunks of ``problem`` run side by side, each on one thread: the
    plain kernels on the CPU (the robust metrics' and friction's builds share
    their own work out on the threads; the GPU takes one chunk at a time)."""
    return (problem.device != "gpu" and problem.robust is None
            and problem.friction is None)


def _dask_chunks(problem, todo, client):
    """The same kernels on the workers of a Dask ``client``."""
    from dask.distributed import as_completed
    remote = client.scatter(problem, broadcast=True)
    futures = [client.submit(evaluate_chunk_task, remote, c, pure=False) for c in todo]
    for fut in as_completed(futures):
        yield fut.result()
