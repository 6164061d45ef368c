"""The command line's shape (issue 41): each command in a module of its own, cli/__init__ only
the parser's assembly and main."""

from __future__ import annotations

import ast
import inspect

from cable_ocp import cli


def test_each_command_runs_from_a_module_of_its_own():
    parser = cli.build_parser()
    (commands,) = [action for action in parser._actions if action.dest == "command"]
    modules = {name: sub.get_default("run").__module__ for name, sub in commands.choices.items()}
    assert all(module.startswith("cable_ocp.cli.") for module in modules.values()), modules
    # One module per command, but scenes and schema (cable-ocp's reference) share one.
    shared = {name for name, module in modules.items() if module == "cable_ocp.cli.reference"}
    assert shared == {"scenes", "schema"}
    others = [module for name, module in modules.items() if name not in shared]
    assert len(set(others)) == len(others)


def test_the_package_module_defines_only_the_parser_and_main():
    tree = ast.parse(inspect.getsource(cli))
    defined = {node.name for node in tree.body if isinstance(node, ast.FunctionDef | ast.ClassDef)}
    assert defined == {"build_parser", "main"}
