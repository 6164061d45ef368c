"""Names of a package imported on first use (PEP 562), written once for every package that does.

A package's ``__init__`` imports its public names under ``if TYPE_CHECKING:`` (for type checkers
and the import graph, :mod:`cable_ocp.studies.imports`) and installs the two module hooks that
:func:`lazy_names` makes from those imports::

    if TYPE_CHECKING:
        from cable_ocp import plots
        from cable_ocp.simulation.run import simulate

    __all__ = ["plots", "simulate"]
    __getattr__, __dir__ = lazy_names(globals())

so that importing the package imports none of those modules until a name is used, and each
name's module is stated once (scientific-python's ``lazy_loader.attach_stub`` reads a stub the
same way). A package may give the map itself instead (``lazy_names(globals(), sources)``).
"""

from __future__ import annotations

import ast
from collections.abc import Callable, Mapping
from importlib import import_module
from pathlib import Path


def lazy_names(
    namespace: dict, sources: Mapping[str, str] | None = None
) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of a package whose names are imported on first use.

    Parameters
    ----------
    namespace : dict
        The package's ``globals()``: its ``__name__``, its ``__file__``, and where a name is
        kept once imported.
    sources : mapping of str to str, optional
        Each public name and the dotted module that defines it; a name whose module is
        ``<package>.<name>`` (a subpackage, such as ``cable_ocp.plots``) is that module itself.
        By default the imports under the package's ``if TYPE_CHECKING:`` (:func:`declared`).

    Returns
    -------
    __getattr__ : callable
        The name's value, imported from its module and kept in ``namespace``; AttributeError,
        naming the package, for a name not in ``sources``.
    __dir__ : callable
        The package's names, the lazy ones included, sorted.
    """
    package = namespace["__name__"]
    sources = declared(Path(namespace["__file__"]), package) if sources is None else dict(sources)

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


def declared(path: Path, package: str) -> dict[str, str]:
    """The names that ``path`` (a file of ``package``) imports under ``if TYPE_CHECKING:``.

    Each with its dotted module; ``from <package> import sub`` names the subpackage
    ``<package>.sub`` itself.

    Raises
    ------
    ValueError
        Naming the file: an import there that is relative or renames its name (``as``).
    """
    found = {}
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if not (isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING"):
            continue
        for statement in node.body:
            if not isinstance(statement, ast.ImportFrom) or statement.level:
                raise ValueError(f"{path}: under TYPE_CHECKING, only 'from package.module import'")
            for alias in statement.names:
                if alias.asname is not None:
                    raise ValueError(f"{path}: {alias.name} as {alias.asname}: not renamed")
                own = statement.module == package
                found[alias.name] = f"{package}.{alias.name}" if own else statement.module
    return found
