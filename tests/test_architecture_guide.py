"""The guide's page "How the package is built" (docs/guide/architecture.md) stays true to the code.

Without building the site: every name the page cross-references exists, the registry's fields it
lists are the registry's, the layers of the README's table it includes are those the import check
enforces, and the source lines it quotes are where it says.
"""

from __future__ import annotations

import dataclasses
import importlib
import re
from pathlib import Path

import pytest

from cable_ocp.control.solvers import Solver
from cable_ocp.studies.imports import LAYERS

ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "guide" / "architecture.md"
ROLE = re.compile(r"\{(mod|func|class|data|meth|attr)\}`~?([^`<]+?)(?: <([^>]+)>)?`")


def _resolve(dotted: str) -> object:
    """The object a dotted name names: the longest importable module, then attributes."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            found = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for name in parts[cut:]:
            found = getattr(found, name)
        return found
    raise ImportError(dotted)


def test_the_guide_lists_the_page():
    index = (ROOT / "docs" / "guide" / "index.md").read_text(encoding="utf-8")
    assert re.search(r"^architecture$", index, re.M)


def test_every_name_the_page_refers_to_exists():
    names = [target or name for _, name, target in ROLE.findall(PAGE.read_text(encoding="utf-8"))]
    assert len(names) > 15
    missing = []
    for name in names:
        try:
            _resolve(name.strip())
        except (ImportError, AttributeError):
            missing.append(name)
    assert not missing, f"the page names what the package does not have: {missing}"


def test_the_registry_fields_the_page_lists_are_the_registrys():
    page = PAGE.read_text(encoding="utf-8")
    table = re.search(r"\| field \| what it declares \|\n\|[-| ]+\|\n((?:\|.*\|\n)+)", page)
    assert table, "the page has no table of the registry's fields"
    listed = re.findall(r"^\| `(\w+)` \|", table.group(1), re.M)
    assert listed == [f.name for f in dataclasses.fields(Solver)]


def test_the_layers_the_page_shows_are_the_ones_the_import_check_enforces():
    page = PAGE.read_text(encoding="utf-8")
    table = page.split("| layer | what it holds |", 1)[1].split("\n\n", 1)[0]
    rows = re.findall(r"^\| ((?:`[^`]+`,? ?)+) \|", table, re.M)
    shown = [tuple(re.findall(r"`([^`]+)`", row)) for row in rows]
    assert shown[::-1] == list(LAYERS)


@pytest.mark.parametrize(
    "source, start, end",
    re.findall(
        r"```\{literalinclude\} \.\./\.\./(\S+)\n(?::language: \w+\n)?:start-at: [\"'](.+)[\"']\n"
        r":end-at: [\"'](.+)[\"']",
        PAGE.read_text(encoding="utf-8"),
    ),
)
def test_the_quoted_source_is_where_the_page_says(source, start, end):
    text = (ROOT / source).read_text(encoding="utf-8")
    assert start in text
    assert end in text.split(start, 1)[1]


def _python_blocks(page: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", page, re.S)


def test_the_new_solver_example_runs_against_the_registry():
    """The page's solver module and registry entry, executed with the package's own names."""
    from dataclasses import dataclass

    from cable_ocp.control.checks import Rule, check_fields
    from cable_ocp.control.problem import ProblemSolver, SolverOutcome, WinchProblem
    from cable_ocp.control.solvers import KNOTS

    module, entry = [b for b in _python_blocks(PAGE.read_text(encoding="utf-8")) if "Solver" in b]
    names = {"dataclass": dataclass, "Rule": Rule, "check_fields": check_fields,
             "ProblemSolver": ProblemSolver, "SolverOutcome": SolverOutcome,
             "WinchProblem": WinchProblem, "Solver": Solver, "KNOTS": KNOTS}  # fmt: skip
    exec(module, names)
    assert names["CoordinateSearchSettings"]().max_evaluations > 0
    with pytest.raises(ValueError, match="CoordinateSearchSettings.max_evaluations = 0"):
        names["CoordinateSearchSettings"](max_evaluations=0)
    solver = eval(entry.split("\n", 1)[1], names)
    assert isinstance(solver, Solver) and not solver.closed_loop and not solver.shootings
    assert solver.transcription is KNOTS and solver.settings is names["CoordinateSearchSettings"]
    with pytest.raises(ValueError, match="open-loop problem only"):
        names["CoordinateSearch"](None, None).solve(None, [0.0], fixed={0: 0.0})
