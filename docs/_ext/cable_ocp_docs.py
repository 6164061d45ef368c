"""Sphinx directives of the cable_ocp site: tables generated from the code, never typed twice.

``scene-schema``
    One table per scene section (``cable``, ``environment``, ...), each field with its type,
    default, unit, allowed range and meaning, read from the field declarations of
    :mod:`cable_ocp.scene.schema` when the site is built (:mod:`cable_ocp.scene.fields`, as
    ``cable-ocp schema`` prints them).
``cli-help``
    The ``--help`` text of ``cable-ocp`` and of each of its commands, from
    :func:`cable_ocp.cli.build_parser`.
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

from cable_ocp.scene.fields import field_rows, schema_sections

logger = logging.getLogger(__name__)

CACHE = Path(__file__).resolve().parent.parent / "_build" / ".jupyter_cache"


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ") or " "


class SceneSchema(SphinxDirective):
    """``scene-schema``: the tables of every scene section with units and ranges."""

    def run(self):
        """The tables, parsed as MyST Markdown."""
        lines = []
        for path, cls in schema_sections():
            title = f"`[{path}]`" if path else "top level"
            lines += [f"**{title}** — {cls.__name__}: {(cls.__doc__ or '').splitlines()[0]}", ""]
            lines += ["| field | type | default | unit | range | meaning |",
                      "|---|---|---|---|---|---|"]  # fmt: skip
            for row in field_rows(cls, path):
                if row["missing"]:
                    text = f"scene field {row['path']} declares no {row['missing']} (schema.py)"
                    logger.warning(text, location=self.get_location())
                cells = (f"`{row['field']}`", row["kind"], f"`{row['default']}`", row["unit"],
                         row["range"], row["meaning"])  # fmt: skip
                lines.append("| " + " | ".join(_cell(c) for c in cells) + " |")
            lines.append("")
        container = nodes.container()
        self.state.nested_parse(StringList(lines, source="cable_ocp.scene.schema"), 0, container)
        return container.children


def _subcommands(parser: argparse.ArgumentParser):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


class CliHelp(SphinxDirective):
    """``cli-help``: ``cable-ocp --help`` and ``cable-ocp COMMAND --help``, as printed."""

    def run(self):
        """A rubric and a literal block per command."""
        import os

        from cable_ocp.cli import build_parser

        os.environ["COLUMNS"] = "100"
        parser = build_parser()
        out = []
        for name, sub in [("cable-ocp", parser), *_subcommands(parser).items()]:
            title = name if name == "cable-ocp" else f"cable-ocp {name}"
            section = nodes.rubric(text=title)
            block = nodes.literal_block(text=sub.format_help())
            block["language"] = "text"
            out += [section, block]
        return out


class FrontDoor(SphinxDirective):
    """``front-door``: an autosummary of ``cable_ocp.__all__``, each name where it is defined."""

    def run(self):
        """The autosummary of the callables and classes, then the data in a line."""
        import inspect
        from pathlib import Path

        import cable_ocp
        from cable_ocp.lazy import declared

        sources = declared(Path(cable_ocp.__file__), "cable_ocp")  # each name's module, once
        lines, data = [".. autosummary::", "   :nosignatures:", ""], []
        for name in cable_ocp.__all__:
            source = sources[name]
            value = getattr(cable_ocp, name)
            if not (inspect.ismodule(value) or inspect.isclass(value) or callable(value)):
                data.append(f"``{name}`` = ``{value!r}`` (:mod:`{source}`)")
                continue
            target = source if source == f"cable_ocp.{name}" else f"{source}.{name}"
            lines.append(f"   ~{target}")
        lines += ["", "Data: " + "; ".join(data) + "."] if data else []
        container = nodes.container()
        self.state.nested_parse(StringList(lines, source="cable_ocp.__all__"), 0, container)
        return container.children


# |v|, |phi'|: absolute values in plain-text docstrings, not reStructuredText substitutions.
BARS = re.compile(r"(?<![\\|\w])\|(?=[^\s|])([^|`\n]{1,40}?)(?<=[^\s|\\])\|(?![|\w])")


def escape_bars(app, what, name, obj, options, lines):
    """Escape the bars of absolute values (``|v|``) outside tables, for docutils."""
    for k, line in enumerate(lines):
        if not line.lstrip().startswith(("|", "+")):
            lines[k] = BARS.sub(r"\\|\1\\|", line)


def lenient_in_docstrings(app, domain, node) -> bool | None:
    """Count, not warn about, an unresolved reference written in a docstring.

    The pages written for the site (the guide, the front door) are checked strictly
    (``nitpicky``); the docstrings' own ``:data:`` and ``:class:`` references to names without a
    page of their own are listed at the end of the build instead (``unresolved_in_docstrings``).
    """
    if not str(node.get("refdoc", "")).startswith("api/generated/"):
        return None
    app.env.cable_ocp_unresolved = getattr(app.env, "cable_ocp_unresolved", 0) + 1
    return True


def report_unresolved(app, exception) -> None:
    """Say how many docstring references did not resolve (none of them fails the build)."""
    count = getattr(app.env, "cable_ocp_unresolved", 0)
    if exception is None and count:
        logger.info(f"unresolved_in_docstrings: {count} references")


# The sidebar lists the site two levels deep: the guide's pages, the gallery's notebooks and the
# API's packages, not the 146 modules under them (each package's page lists its modules).
SIDEBAR_DEPTH = 2


def short_sidebar(app, pagename, templatename, context, doctree) -> None:
    """Furo's navigation tree cut to :data:`SIDEBAR_DEPTH` (Furo draws the whole toctree)."""
    if "furo_navigation_tree" not in context or "toctree" not in context:
        return
    from furo.navigation import get_navigation_tree

    tree = context["toctree"](
        collapse=False, titles_only=True, maxdepth=SIDEBAR_DEPTH, includehidden=True
    )
    context["furo_navigation_tree"] = get_navigation_tree(tree)


def setup(app):
    """Register the directives, the docstring filter and the short sidebar."""
    app.connect("warn-missing-reference", lenient_in_docstrings)
    app.connect("build-finished", report_unresolved)
    app.add_directive("scene-schema", SceneSchema)
    app.add_directive("front-door", FrontDoor)
    app.connect("autodoc-process-docstring", escape_bars)
    app.add_directive("cli-help", CliHelp)
    app.connect("html-page-context", short_sidebar, priority=900)  # after Furo's own (500)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
