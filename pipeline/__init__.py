"""pipeline: exact analysis and Monte-Carlo synthesis of planar hinged-lever mechanisms."""

from importlib.metadata import PackageNotFoundError, version as _version

try:
    __version__ = _version("pipeline")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.1.0"
