"""A process of this package's own beside the running one (the compile beside a
sweep, the workers of a refinement): ``python -P -m MODULE`` on the package this
process runs.

``-P`` keeps the working folder off the new interpreter's path, and the folder
that holds this ``pipeline`` goes first on its PYTHONPATH: a ``pipeline`` folder
or ``pipeline.py`` where the user works shadows nothing, and a package found
through a script's own path (an uninstalled checkout) is found there too."""

from __future__ import annotations

import os
import sys
from pathlib import Path

_HOME = str(Path(__file__).resolve().parents[2])     # the folder that holds pipeline/


def module_command(module: str, *args: str) -> tuple[list[str], dict]:
    """(argv, environment) of ``python -P -m module args`` on this package."""
    path = os.pathsep.join([_HOME] + [p for p in [os.environ.get("PYTHONPATH")] if p])
    return [sys.executable, "-P", "-m", module, *args], dict(os.environ, PYTHONPATH=path)
