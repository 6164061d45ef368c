"""Argparse types of the command line, each refusing a value out of its range in one line.

``DefaultsShown`` is the commands' help formatter.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

OUT_HELP = (
    "results folder, written atomically: a new or empty folder, or a previous results folder "
    "(marked by .cable_ocp-results), which is replaced"
)

SCENE_HELP = "the scene: a TOML file, or a bundled scene's name (cable-ocp scenes lists them)"


def integer(low: int, high: int) -> Callable[[str], int]:
    """An argparse type: an integer from ``low`` to ``high``."""

    def convert(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r:.40}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{text:.40} is out of range: must be {low} to {high}")
        return value

    return convert


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r:.40}") from None


def positive(text: str) -> float:
    """An argparse type: a finite number > 0."""
    value = _number(text)
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r:.40} is out of range: must be finite and > 0")
    return value


def weight(text: str) -> float:
    """An argparse type: a finite number >= 0 (a weight of the objective)."""
    value = _number(text)
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"{text!r:.40} is out of range: must be finite and >= 0")
    return value


def fraction(text: str) -> float:
    """An argparse type: a number from 0 to 1."""
    value = _number(text)
    if not 0 <= value <= 1:
        raise argparse.ArgumentTypeError(f"{text!r:.40} is out of range: must be 0 to 1")
    return value


class DefaultsShown(argparse.RawDescriptionHelpFormatter):
    """Help that ends each option with its default, unless the help already says it.

    Flags (``store_true``) and options without a fixed default (None: it follows from the scene,
    as the help says) show none.
    """

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        default = action.default
        if (
            "default" in text
            or default in (None, False, [], argparse.SUPPRESS)
            or not action.option_strings
        ):
            return text
        return f"{text} (default: %(default)s)"
