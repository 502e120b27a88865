"""pipeline: exact analysis and Monte-Carlo synthesis of planar hinged-lever mechanisms.

The Python API (``pipeline.api``; see docs/guide/api.md): ``load_study``, ``run``,
``solve_scene`` (a scene solved in memory), ``open`` (a results file as pandas
DataFrames), ``tolerance`` (how a design holds up when it is made), ``compare``
(designs side by side), ``candidates``, ``scene_tables``, ``with_units``; pictures from
``pipeline.views.plots`` as matplotlib Figures.  Importing the package loads no kernels and
leaves matplotlib's backend alone.
"""

from .base.version import __version__
from .old_paths import install as _install_old_paths

_install_old_paths()    # the flat package's import paths, kept for one release (old_paths.py)

__all__ = ["__version__", "load_study", "run", "solve_scene", "open", "tolerance", "compare",
           "candidates", "scene_tables", "with_units"]


def __getattr__(name):
    """The API's functions, imported from ``pipeline.api`` when first asked for:
    a process that imports a part of the package only (the kernels, as the
    compiler's process beside a run does) does not import the API's
    dependencies (pandas, h5py, the study reader: half a second)."""
    if name in __all__:
        from . import api
        return getattr(api, name)
    raise AttributeError(f"module 'pipeline' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
