"""Names of a package imported on first use (PEP 562), written once for every package that does.

A package's ``__init__`` maps each public name to the module that defines it and installs the
two module hooks :func:`lazy_names` returns::

    _SOURCES = {"simulate": "cable_ocp.simulation.run", "plots": "cable_ocp.plots"}
    __all__ = list(_SOURCES)
    __getattr__, __dir__ = lazy_names(globals(), _SOURCES)

so that importing the package imports none of those modules until a name is used.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from importlib import import_module


def lazy_names(
    namespace: dict, sources: Mapping[str, str]
) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of a package whose names are imported on first use.

    Parameters
    ----------
    namespace : dict
        The package's ``globals()``: its ``__name__``, and where a name is kept once imported.
    sources : mapping of str to str
        Each public name and the dotted module that defines it; a name whose module is
        ``<package>.<name>`` (a subpackage, such as ``cable_ocp.plots``) is that module itself.

    Returns
    -------
    __getattr__ : callable
        The name's value, imported from its module and kept in ``namespace``; AttributeError,
        naming the package, for a name not in ``sources``.
    __dir__ : callable
        The package's names, the lazy ones included, sorted.
    """
    package = namespace["__name__"]

    def __getattr__(name: str) -> object:
        try:
            source = sources[name]
        except KeyError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        module = import_module(source)
        value = module if source == f"{package}.{name}" else getattr(module, name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted({*namespace, *sources})

    return __getattr__, __dir__
