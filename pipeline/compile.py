"""Compile the kernels of studies ahead of time: `pipeline compile [STUDY ...]`.

Each study's mechanism is compiled into its generated module
(``pipeline.compiler``), and the kernels the study uses are run once on a
tiny problem, which fills numba's on-disk cache: the next run of the study
compiles nothing.  ``--show`` prints the generated source.
"""

from __future__ import annotations

import dataclasses
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
    return Compiled(study.name, study.kind, Path(mod.SOURCE_PATH), time.perf_counter() - t)


def source(study) -> str:
    """The generated source of the kernels ``study`` uses."""
    from .compiler import source_for
    plan = study.mechanism.compile()
    rocker = tuple(study.output.rocker) if study.kind == "sweep" else None
    return source_for(plan, rocker)


def compile_all(paths=()) -> list[Compiled]:
    """Compile every study named (or found), saying which one it compiles and
    for how long (a study new to the cache takes minutes)."""
    from .base.progress import ticking
    from .study.reader import load_study
    files = study_files(paths)
    done = []
    for k, p in enumerate(files, 1):
        study = load_study(p)
        with ticking(f"compile {k}/{len(files)}: {study.name} ({study.kind})"):
            done.append(compile_study(study))
    return done
