"""The installed version of the package (written into every results file)."""

from importlib.metadata import PackageNotFoundError, version as _version

try:
    __version__ = _version("pipeline")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.1.0"
