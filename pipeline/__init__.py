"""pipeline: exact analysis and Monte-Carlo synthesis of planar hinged-lever mechanisms.

The Python API (``pipeline.api``; see docs/api.md): ``load_study``, ``run``,
``open`` (a results file as pandas DataFrames), ``candidates``,
``scene_tables``, ``with_units``.  Importing the package loads no kernels and
leaves matplotlib's backend alone.
"""

from .api import candidates, load_study, open, run, scene_tables, with_units  # noqa: A004
from .version import __version__

__all__ = ["__version__", "load_study", "run", "open", "candidates", "scene_tables",
           "with_units"]
