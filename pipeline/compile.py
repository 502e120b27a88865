"""Compile the kernels of studies ahead of time: `pipeline compile [STUDY ...]`.

Each study's mechanism is compiled into its generated module
(``pipeline.compiler``), and the kernels the study uses are run once on a
tiny problem, which fills numba's on-disk cache: the next run of the study
compiles nothing.  ``--show`` prints the generated source.
"""

from __future__ import annotations

import dataclasses
import os
import time
from dataclasses import dataclass
from pathlib import Path

STUDIES = Path("studies")      # of the current folder: a project's studies (as in a checkout)


@dataclass
class Compiled:
    study: str
    kind: str
    source: Path          # the generated module's file
    seconds: float        # generation, import and compilation (a cached run: the load)
    process: int = 0      # the process that compiled it (its id)


def study_files(paths=()) -> list[Path]:
    """The studies named, or every study in the folder studies/ of the current
    folder (where `pipeline run studies/...` finds them too; the installed
    package carries no studies)."""
    if paths:
        return [Path(p) for p in paths]
    found = sorted(STUDIES.glob("*.toml"))
    if not found:
        raise FileNotFoundError(f"{STUDIES.resolve()}: no study files (*.toml) here; name the "
                                "studies to compile: pipeline compile STUDY.toml ...")
    return found


def compile_study(study) -> Compiled:
    """Generate, import and compile the kernels ``study`` uses."""
    import numpy as np

    from .compiler import kernels_for
    from .solve.crank_motion import integrate, with_changes
    from .solve.scene import run_scene
    from .runs.sweep import build_problem
    t = time.perf_counter()     # the kernels' generation, import and compilation (or load)
    mech = study.mechanism
    plan = mech.compile()
    if study.kind == "sweep":
        pb = build_problem(study, dataclasses.replace(study.sweep, positions=36))
        pb.evaluate_rows(np.ascontiguousarray(plan.par[None, :]), parallel=False)
        mod = pb.kernels
    else:
        run_scene(dataclasses.replace(study, output=dataclasses.replace(
            study.output, table_positions=12, dense_positions=36)))
        mod = kernels_for(plan)
        if getattr(study, "dynamics", None) is not None and study.dynamics.cases:
            case = study.dynamics.cases[0]
            integrate(plan, mech, with_changes(case, t_end=case.sample_dt))
    return Compiled(study.name, study.kind, Path(mod.SOURCE_PATH), time.perf_counter() - t,
                    os.getpid())


def source(study) -> str:
    """The generated source of the kernels ``study`` uses: a scene's module; for
    a sweep, its mechanism's module, then the sweep's own, which imports from it."""
    from .compiler import source_for
    plan = study.mechanism.compile()
    if study.kind != "sweep":
        return source_for(plan)
    return source_for(plan) + "\n\n" + source_for(plan, tuple(study.output.rocker))


def compile_all(paths=(), jobs=None) -> list[Compiled]:
    """Compile every study named (or found), saying which one it compiles and
    for how long (a study new to the cache takes half a minute or more).

    numba compiles one function at a time in a process, so the studies whose
    kernels differ are compiled side by side in ``jobs`` worker processes (all
    cores by default), each filling the one on-disk cache; studies of the same
    mechanism go to the same worker, one after the other, so that nothing is
    compiled twice at once (a sweep's module imports the kernels the rocker
    does not change from its mechanism's module, which a scene compiles)."""
    from .compiler.parallel import default_jobs
    from .study.reader import load_study
    files = study_files(paths)
    studies = [load_study(p) for p in files]      # a bad study stops here, before any work
    groups = same_kernels(studies)
    jobs = default_jobs() if jobs is None else int(jobs)
    if jobs < 1:
        raise ValueError(f"--jobs must be at least 1, got {jobs}")
    jobs = min(jobs, len(groups))
    if jobs == 1:
        return _in_this_process(studies)
    return _in_processes(files, studies, groups, jobs)


def same_kernels(studies) -> list[list[int]]:
    """The studies' indices grouped by the kernels they compile, in the order
    first met: by their mechanism's module (``source_for(plan)``: a sweep's own
    module imports from it everything its rocker does not change)."""
    from .compiler import source_for
    groups: dict[str, list[int]] = {}
    for k, study in enumerate(studies):
        groups.setdefault(source_for(study.mechanism.compile()), []).append(k)
    return list(groups.values())


def _in_this_process(studies) -> list[Compiled]:
    from .base.progress import ticking
    done = []
    for k, study in enumerate(studies, 1):
        with ticking(f"compile {k}/{len(studies)}: {study.name} ({study.kind})"):
            done.append(compile_study(study))
    return done


def _compile_files(paths) -> list[Compiled]:
    """Worker process: compile the studies ``paths`` one after the other."""
    from .study.reader import load_study
    return [compile_study(load_study(p)) for p in paths]


def _in_processes(files, studies, groups, jobs) -> list[Compiled]:
    import logging
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    from .base.progress import ticking
    log = logging.getLogger("pipeline")
    done: dict[int, Compiled] = {}
    what = f"compile {len(studies)} studies ({len(groups)} sets of kernels) in {jobs} processes"
    # spawn: a fresh interpreter per worker (no fork of this process's threads)
    with ticking(what) as line, ProcessPoolExecutor(
            jobs, mp_context=multiprocessing.get_context("spawn")) as pool:
        running = {pool.submit(_compile_files, [str(files[k]) for k in g]): g for g in groups}
        try:
            while running:
                finished, _ = wait(running, return_when=FIRST_COMPLETED)
                for fut in finished:
                    group = running.pop(fut)
                    for k, c in zip(group, fut.result()):
                        done[k] = c
                        log.info("compiled %d/%d: %s (%s) in %.1f s", len(done), len(studies),
                                 c.study, c.kind, c.seconds)
                line.set(f"{len(done)}/{len(studies)} done")
        except BaseException:
            pool.shutdown(wait=False, cancel_futures=True)
            raise
    return [done[k] for k in range(len(studies))]
