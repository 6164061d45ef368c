"""The package's import graph by layer, checked and drawn (``python -m cable_ocp.studies.imports``).

The package is layered, bottom to top: ``lazy`` (the packages' lazy loader, PEP 562), ``scene``
(files in and out), ``result_files`` (results kept as netCDF), ``model`` (the rfe equations),
``drive`` (vessel, winch, end force), ``simulation`` (statics, RK4 runs), ``control`` (IPOPT,
Nelder-Mead, MPC), ``lowering``, ``sweep`` and ``studies`` (many runs; nothing below imports
them), and the faces ``cli``, ``plots``, ``entry`` (the command's entry point) and the package's
``__init__``. A module may import from its own layer and the layers below it only.
:func:`violations` lists the imports that break that rule, :func:`cycles` the modules that
import each other round a loop, at module level or inside a function (a test keeps both empty),
and :func:`draw` saves the graph with the layers as rows, so that every arrow points down.
"""

from __future__ import annotations

import ast
import sys
from dataclasses import dataclass
from pathlib import Path

PACKAGE = "cable_ocp"
# Bottom to top; layers on one row may not import each other.
LAYERS = (
    ("lazy",),
    ("scene",),
    ("result_files",),
    ("model",),
    ("drive",),
    ("simulation",),
    ("control",),
    ("lowering",),
    ("sweep", "studies"),
    ("policy",),
    ("cli", "plots", "entry", "__init__"),
)


@dataclass(frozen=True)
class Module:
    """A module of the package: dotted ``name``, its ``layer`` and the modules it ``imports``."""

    name: str
    layer: str
    imports: frozenset[str]

    @property
    def rank(self) -> int:
        """Row of its layer, 0 at the bottom."""
        return layer_rank(self.layer)


def layer_rank(layer: str) -> int:
    """Row of a layer in :data:`LAYERS` (0 at the bottom)."""
    for rank, row in enumerate(LAYERS):
        if layer in row:
            return rank
    raise ValueError(f"{layer!r} is in no layer of {PACKAGE}: add it to LAYERS")


def package_root() -> Path:
    """Folder of the installed package."""
    return Path(__file__).resolve().parents[1]


def _layer_of(name: str) -> str:
    parts = name.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def _imported(tree: ast.AST, known: set[str]) -> set[str]:
    """Modules of the package that an AST imports (``from cable_ocp import x`` names ``x``)."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module == PACKAGE:
                found |= {f"{PACKAGE}.{alias.name}" for alias in node.names}
            elif node.module.startswith(PACKAGE + "."):
                for alias in node.names:  # a submodule by name, else the module itself
                    submodule = f"{node.module}.{alias.name}"
                    found.add(submodule if submodule in known else node.module)
        elif isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names if alias.name.startswith(PACKAGE + ".")}
    return {name for name in found if name in known}


def modules(root: Path | None = None) -> list[Module]:
    """Every module of the package with its layer and its imports of the package."""
    root = root or package_root()
    paths = sorted(root.rglob("*.py"))
    names = {}
    for path in paths:
        parts = path.relative_to(root.parent).with_suffix("").parts
        dotted = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        names[dotted] = path
    known = set(names)
    return [
        Module(name, _layer_of(name), frozenset(_imported(ast.parse(path.read_text()), known)))
        for name, path in sorted(names.items())
    ]


def violations(root: Path | None = None) -> list[str]:
    """Imports from a higher layer, or across layers of one row, as ``a -> b`` lines."""
    graph = {m.name: m for m in modules(root)}
    broken = []
    for module in graph.values():
        for target in sorted(module.imports):
            other = graph[target]
            upward = other.rank > module.rank
            sideways = (
                other.rank == module.rank
                and other.layer != module.layer
                and module.rank < len(LAYERS) - 1  # the faces may use each other
            )
            if (upward or sideways) and other.layer != "__init__":
                broken.append(f"{module.name} ({module.layer}) -> {target} ({other.layer})")
    return broken


def cycles(root: Path | None = None) -> list[str]:
    """Groups of modules that import each other round a loop, as ``a -> b -> a`` lines.

    Every import counts, at module level or inside a function (a local import that breaks a
    cycle at import time still ties the two modules together), and so do the names a package's
    ``__init__`` loads lazily. One line per strongly connected group of the graph (Tarjan's
    algorithm), showing one loop through it.
    """
    graph = {m.name: sorted(m.imports) for m in modules(root)}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    groups: list[list[str]] = []

    def visit(name: str) -> None:
        index[name] = low[name] = len(index)
        stack.append(name)
        for target in graph[name]:
            if target not in index:
                visit(target)
                low[name] = min(low[name], low[target])
            elif target in stack:
                low[name] = min(low[name], index[target])
        if low[name] == index[name]:
            group = []
            while not group or group[-1] != name:
                group.append(stack.pop())
            if len(group) > 1 or name in graph[name]:
                groups.append(sorted(group))

    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 10 * len(graph)))
    try:
        for name in sorted(graph):
            if name not in index:
                visit(name)
    finally:
        sys.setrecursionlimit(limit)
    return [" -> ".join(_loop(graph, set(group), group[0])) for group in sorted(groups)]


def _loop(graph: dict[str, list[str]], group: set[str], start: str) -> list[str]:
    """A shortest path from ``start`` back to itself within ``group`` (breadth first)."""
    came: dict[str, str] = {}
    frontier = [start]
    while frontier:
        following = []
        for name in frontier:
            for target in graph[name]:
                if target == start:
                    path = [name]
                    while path[-1] != start:
                        path.append(came[path[-1]])
                    return [*reversed(path), start]
                if target in group and target not in came:
                    came[target] = name
                    following.append(target)
        frontier = following
    raise ValueError(f"{start} is on no loop")  # a group of Tarjan's always has one


def _box(name: str) -> str:
    """What a module is drawn as: a sub-package of a layer (e.g. studies.stability) is one box."""
    parts = name.split(".")
    return ".".join(parts[1:3]) if len(parts) > 2 else (parts[1] if len(parts) > 1 else PACKAGE)


def draw(path: str | Path, root: Path | None = None) -> Path:
    """Save the import graph as a picture: layers as rows (faces on top), imports as arrows.

    Returns the path written.
    """
    import matplotlib.pyplot as plt

    graph = modules(root)
    imported = {target for module in graph for target in module.imports}
    # A layer's own package (its __init__ with a docstring only) is left out of the picture.
    shown = [m for m in graph if m.imports or m.name in imported]
    boxes: dict[str, int] = {}
    for module in shown:
        boxes.setdefault(_box(module.name), module.rank)
    edges = {(_box(m.name), _box(t)) for m in graph for t in m.imports if _box(m.name) != _box(t)}
    rows: dict[int, list[str]] = {}
    for box, rank in sorted(boxes.items()):
        rows.setdefault(rank, []).append(box)
    width = max(len(r) for r in rows.values())
    figure, axes = plt.subplots(figsize=(max(12, 1.6 * width), 1.6 * len(LAYERS)))
    where = {}
    for rank, row in rows.items():
        for k, box in enumerate(row):
            where[box] = ((k + 0.5) * width / len(row), rank)
    for source, target in sorted(edges):
        (x0, y0), (x1, y1) = where[source], where[target]
        color = "tab:red" if y1 > y0 else "0.6"
        arrow = {"arrowstyle": "->", "color": color, "lw": 0.6, "alpha": 0.5}
        axes.annotate("", (x1, y1 + 0.18), (x0, y0 - 0.18), arrowprops=arrow)
    for box, (x, y) in where.items():
        axes.text(x, y, box.split(".", 1)[-1], ha="center", va="center", fontsize=8,
                  bbox={"boxstyle": "round", "fc": "white", "ec": "0.3"})  # fmt: skip
    for rank, row in enumerate(LAYERS):
        axes.axhspan(rank - 0.45, rank + 0.45, color=f"C{rank}", alpha=0.08)
        axes.text(-0.3, rank, " / ".join(row), ha="right", va="center", fontsize=10,
                  fontweight="bold")  # fmt: skip
    axes.set_xlim(-2.5, width + 0.2)
    axes.set_ylim(-0.6, len(LAYERS) - 0.4)
    axes.axis("off")
    count = sum(len(m.imports) for m in graph)
    axes.set_title(f"{PACKAGE}: {len(graph)} modules, {count} imports; every arrow points down "
                   "(a red one would point up)")  # fmt: skip
    path = Path(path)
    figure.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(figure)
    return path


def main(argv: list[str] | None = None) -> int:
    """``python -m cable_ocp.studies.imports [PICTURE.png]``: check the layers, draw the graph."""
    argv = sys.argv[1:] if argv is None else argv
    broken, loops = violations(), cycles()
    for line in broken:
        print(f"layer violation: {line}")
    for line in loops:
        print(f"import cycle: {line}")
    if argv:
        print(f"wrote {draw(argv[0])}")
    layers = {m.layer for m in modules()}
    print(f"{len(modules())} modules in {len(layers)} layers; {len(broken)} violations, "
          f"{len(loops)} cycles")  # fmt: skip
    return 1 if broken or loops else 0


if __name__ == "__main__":
    sys.exit(main())
