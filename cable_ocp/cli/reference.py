"""``cable-ocp scenes`` and ``cable-ocp schema [KEY]``: what a user can load and set."""

from __future__ import annotations

import textwrap

from cable_ocp.cli.arguments import add_command
from cable_ocp.cli.exits import SUCCESS
from cable_ocp.scene.bundled import models_dir, scene_names, scene_summary
from cable_ocp.scene.fields import all_rows, rows_under


def add_reference_commands(commands) -> None:
    """Add ``scenes`` and ``schema`` to the subparsers of ``cable-ocp``."""
    scenes = add_command(commands, "scenes", "list the bundled scenes", scene=False)
    scenes.set_defaults(run=_scenes)
    schema = add_command(
        commands, "schema", "the scene fields: defaults, units, ranges and meanings", scene=False
    )
    schema.add_argument(
        "key",
        nargs="?",
        help="a section or a field as --set takes it (cable, top.tow, cable.diameter); "
        "every field when left out",
    )
    schema.set_defaults(run=_schema)


def _scenes(args) -> int:
    names = scene_names()
    width = max(map(len, names))
    for name in names:
        print(f"{name:<{width}}  {scene_summary(name)}")
    print(f"(in {models_dir()}; give a name wherever a scene file is asked for)")
    return SUCCESS


def _schema(args) -> int:
    rows = rows_under(args.key) if args.key else all_rows()
    width = max(len(row["path"]) for row in rows)
    for row in rows:
        head = f"{row['path']:<{width}}  {row['kind']}, default {row['default']}"
        if row["unit"] not in ("—", "1"):
            head += f" {row['unit']}"
        print(head)
        lines = [f"range: {row['range']}", row["meaning"]]
        for line in lines:
            print(textwrap.indent(textwrap.fill(line, 96 - 4), "    "))
    return SUCCESS
