"""The import paths of the flat package, kept for one release.

Issue 26 moved the modules of ``pipeline/`` into one package per layer
(docs/guide/architecture.md).  Code written against the old paths keeps working
until the next release: ``import pipeline.sweep`` gives the module
``pipeline.runs.sweep`` itself (the very same object, so a monkeypatch through
the old path acts on the real module), ``from pipeline.forces import
scene_forces`` the function of ``pipeline.solve.reactions``, and
``python -m pipeline.metrics`` runs ``pipeline.model.metric_catalogue``.
Each old path, the first time a process imports it, warns (``DeprecationWarning``,
naming the new path, attributed to the importing line); so does a name taken
from the re-exports of ``pipeline.model``, ``pipeline.study`` and
``pipeline.analysis`` (their ``__init__``).

``MOVED`` below is the whole list.  Nothing inside ``pipeline/`` imports an old
path (tests/test_architecture.py checks it); the next release deletes this
module and its import in ``pipeline/__init__.py``.  ``pipeline.model``,
``pipeline.study`` and ``pipeline.analysis`` are packages now: their
``__init__`` re-exports what the old modules' users imported.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

# packages that took an old module's name: their __init__ re-exports its names
REEXPORTED = ("model", "study", "analysis")

# old module, under pipeline. -> where it is now; an old package's name covers
# its modules too (pipeline.groups.prp -> pipeline.model.groups.prp, which moved again)
MOVED = {
    "errors": "base.errors",
    "limits": "base.limits",
    "files": "base.files",
    "expressions": "base.expressions",
    "version": "base.version",
    "pareto": "kernels.pareto",
    "groups": "model.groups",
    # the group types' modules, now each type's folder (pipeline.group_types)
    "model.groups.rrr": "group_types.rrr.model",
    "model.groups.rrp": "group_types.rrp.model",
    "model.groups.rpr": "group_types.rpr.model",
    "model.groups.prp": "group_types.prp.model",
    "model.groups.rpp": "group_types.rpp.model",
    "model.groups.ppr": "group_types.rpp.model",
    "model.groups.class3": "group_types.class3.model",
    "model.groups.class3_slider": "group_types.class3.model",
    "kernels.triad": "group_types.class3.kernels",
    "model.groups.base": "model.group_base",
    "motion_law": "model.motion_law",
    "metrics": "model.metric_catalogue",
    "compiler.forces": "compiler.force_equations",
    "compiler.gpu": "compiler.cuda_source",
    "scene": "solve.scene",
    "forces": "solve.reactions",
    "peaks": "solve.peaks",
    "dynamics": "solve.crank_motion",
    "study_section": "study.section",
    "slide_check": "study.slide_check",
    "sweep_spec": "study.sweep_spec",
    "search_spec": "study.search_spec",
    "sampling": "study.sampling",
    "objectives": "study.objectives",
    "storage": "results.storage",
    "scene_file": "results.scene_file",
    "sweep_file": "results.sweep_file",
    "search_file": "results.search_file",
    "journal": "results.journal",
    "sweep": "runs.sweep",
    "search": "runs.search",
    "search_problem": "runs.search_problem",
    "gpu": "runs.gpu",
    "ranking": "analysis.ranking",
    "candidate": "analysis.candidate",
    "plots": "views.plots",
    "dynamics_plots": "views.dynamics_plots",
    "animate": "views.animate",
    "show": "views.show",
    "browse": "views.browse",
    "report": "views.report",
    "report_assets": "views.report_assets",
    "report_figures": "views.report_figures",
    "export": "views.export",
    "tables": "views.tables",
}


def _moved_once(name: str) -> str | None:
    head, _, rest = name.partition(".")
    if head != "pipeline" or not rest:
        return None
    parts = rest.split(".")
    for i in range(len(parts), 0, -1):
        old = ".".join(parts[:i])
        if old in MOVED:
            return ".".join(["pipeline", MOVED[old], *parts[i:]])
    return None


def new_name(name: str) -> str | None:
    """Where the module ``name`` (``pipeline.X...``) is now, or None if it did not
    move: followed to the end where it moved twice (``pipeline.groups.rrr``, to
    ``pipeline.model.groups.rrr``, then to ``pipeline.group_types.rrr.model``)."""
    new = _moved_once(name)
    while new is not None and _moved_once(new) is not None:
        new = _moved_once(new)
    return new


def deprecated(old: str, new: str) -> str:
    """The warning's text for the old path ``old``, now ``new``."""
    return (f"{old} is an old import path, kept for one release: import {new} "
            "(the next release removes the old path; docs/guide/architecture.md)")


class OldPaths(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds an old path and loads it as the module at its new path."""

    def find_spec(self, name, path=None, target=None):
        new = new_name(name)
        if new is None:
            return None
        # the import system's own frames are skipped: the warning names the importing line
        warnings.warn(deprecated(name, new), DeprecationWarning, stacklevel=2)
        return importlib.util.spec_from_loader(name, self, is_package=False)

    def create_module(self, spec):
        module = importlib.import_module(new_name(spec.name))
        spec.loader_state = module.__spec__   # put back by exec_module
        return module

    def exec_module(self, module):
        # the import system has set the module's __spec__ to the old path's;
        # the module keeps its own (nothing else of it is touched)
        module.__spec__ = module.__spec__.loader_state

    def get_code(self, name):
        """``python -m pipeline.<old>``: run the module at its new path as the main one."""
        return compile(f"import runpy\nrunpy.run_module({new_name(name)!r}, "
                       "run_name='__main__', alter_sys=True)\n", f"<{name}>", "exec")


def install():
    """Put the finder first on ``sys.meta_path`` (once)."""
    if not any(isinstance(f, OldPaths) for f in sys.meta_path):
        sys.meta_path.insert(0, OldPaths())
