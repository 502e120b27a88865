"""The names of the flat package's subpackages (``pipeline.model``,
``pipeline.study``, ``pipeline.analysis``), kept importable from them for one
release with a warning: one module-level ``__getattr__`` for each
(``old_names``).  Old module paths are ``pipeline.old_paths``'."""

import importlib
import warnings


def by_name(table: dict) -> dict:
    """{name: the module that defines it} from {module: its names, space-separated}."""
    return {name: module for module, names in table.items() for name in names.split()}


def old_names(package: str, where):
    """A module ``__getattr__`` for ``package``: a name of ``where`` (``by_name``;
    or a function that gives it, called at the first old name: a table derived
    from modules the package cannot import while it is imported) warns
    (``DeprecationWarning``, naming the module that defines it) and gives the
    very object."""
    table = {}

    def __getattr__(name):
        if not table:
            table.update(where() if callable(where) else where)
        if name not in table:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        warnings.warn(f"{package}.{name} is an old import path, kept for one release: import "
                      f"{name} from {table[name]} (the next release removes the old "
                      "path; docs/guide/architecture.md)", DeprecationWarning, stacklevel=2)
        return getattr(importlib.import_module(table[name]), name)
    __getattr__.__doc__ = (f"A name of the flat package's ``{package}``: it warns "
                           "(``DeprecationWarning``, naming the module that defines it) and "
                           "gives the very object.")
    return __getattr__


def group_type_names() -> dict:
    """{class name: its module} of every group-type folder's classes
    (``pipeline.group_types``): where ``pipeline.model`` and
    ``pipeline.model.groups`` once defined them."""
    from .. import group_types
    return {c.__name__: m.__name__ for m in group_types.part("model")
            for c in m.STUDY_TYPES + getattr(m, "BUILT", ())}
