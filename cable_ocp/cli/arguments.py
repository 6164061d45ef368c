"""Argparse types of the command line, each refusing a value out of its range in one line.

``DefaultsShown`` is the commands' help formatter; :func:`add_set` adds the ``--set`` option
that :func:`parse_overrides` reads and :func:`scene_from` applies, :func:`knot_angles` reads
``--knots``.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from pathlib import Path

from cable_ocp.scene import schema
from cable_ocp.scene.bundled import scene_argument

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

OUT_HELP = (
    "results folder, written atomically: a new or empty folder, or a previous results folder "
    "(marked by .cable_ocp-results), which is replaced"
)

SCENE_HELP = "the scene: a TOML file, or a bundled scene's name (cable-ocp scenes lists them)"
INTERPRETED_HELP = "the interpreted model (default: compiled to C, the library cached on disk)"


def add_command(
    commands, name: str, summary: str, description: str | None = None, scene: bool = True
) -> argparse.ArgumentParser:
    """A command's parser, each option's default in its help (:class:`DefaultsShown`).

    Parameters
    ----------
    commands : argparse subparsers
        Those of ``cable-ocp``.
    name, summary : str
        The command and its line in ``cable-ocp --help``.
    description : str, optional
        What ``cable-ocp NAME --help`` says beside the options.
    scene : bool
        The command takes a SCENE and a required ``--out`` (else it adds its own arguments).
    """
    parser = commands.add_parser(
        name, formatter_class=DefaultsShown, help=summary, description=description
    )
    if scene:
        parser.add_argument("scene", type=scene_argument, help=SCENE_HELP)
        parser.add_argument("--out", type=Path, required=True, help=OUT_HELP)
    return parser


def add_model_options(parser: argparse.ArgumentParser, elements: str, step: str) -> None:
    """Add ``--elements`` and ``--step``, a reduced model's ``ModelSettings``, with their help."""
    parser.add_argument("--elements", type=integer(1, 1000), help=elements)
    parser.add_argument("--step", type=positive, help=step)


def add_engine_command(
    commands, name: str, summary: str, description: str, spec: tuple[str, str], out_help: str
) -> argparse.ArgumentParser:
    """A command that runs the cases of a TOML file on the Dask engine (``sweep``, ``learn``).

    It takes the file (``spec``: its argument's name and help), ``--out`` (``out_help``), and
    where the engine runs: ``--scheduler`` or ``--workers``, both checked by
    :func:`cable_ocp.sweep.runner.check_engine` before any work.
    """
    parser = add_command(commands, name, summary, description, scene=False)
    parser.add_argument(spec[0], type=Path, help=spec[1])
    parser.add_argument("--out", type=Path, required=True, help=out_help)
    parser.add_argument(
        "--scheduler", help="address of a running Dask scheduler, e.g. tcp://h:8786"
    )
    parser.add_argument(
        "--workers",
        type=int,
        help="LocalCluster workers, at most one per core (default: one per core)",
    )
    return parser


def add_animate(parser: argparse.ArgumentParser) -> None:
    """Add ``--animate``: also write the run as ``animation.gif`` (``plots.animate``)."""
    parser.add_argument(
        "--animate",
        action="store_true",
        help="also write animation.gif: the cable (paid out as it grows), the end's path and the "
        "seabed over time",
    )


def add_quiet(parser: argparse.ArgumentParser) -> None:
    """Add ``--quiet``: the command shows no progress (its results and its summary are the same)."""
    parser.add_argument("--quiet", action="store_true", help="no progress bars or solver logs")


def add_set(parser: argparse.ArgumentParser, example: str, what: str = "a scene field") -> None:
    """Add ``--set KEY=VALUE`` (repeatable): override ``what``, e.g. ``--set example``."""
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help=f"override {what}, e.g. --set {example} (repeatable)")  # fmt: skip


def parse_overrides(pairs: list[str]) -> dict:
    """``["model.elements=30", "top.motion='tow'"]`` -> ``{"model.elements": 30, ...}``.

    Values are read as TOML, so numbers, booleans, strings and arrays keep their types; a bare
    word is taken as a string.
    """
    overrides = {}
    for pair in pairs:
        key, sep, text = pair.partition("=")
        if not sep:
            raise ValueError(f"--set {pair!r}: expected KEY=VALUE, e.g. model.elements=30")
        try:
            value = tomllib.loads(f"v = {text}")["v"]
        except (ValueError, RecursionError):  # not TOML: taken as a string
            value = text
        overrides[key.strip()] = value
    return overrides


def scene_from(args: argparse.Namespace, path=None):
    """The scene given (``path``, else the SCENE argument), ``--set``'s overrides applied.

    Loaded and checked by :func:`cable_ocp.scene.schema.load_scene` (SceneError naming the field
    that is wrong, before any work).
    """
    return schema.load_scene(args.scene if path is None else path, parse_overrides(args.set))


def knot_angles(text: str) -> list[float]:
    """An argparse type: comma-separated finite knot angles, rad."""
    if not text.strip():
        raise argparse.ArgumentTypeError(
            "empty: give the angles phi_1..phi_p in rad, comma-separated, or leave --knots out "
            "for a locked winch"
        )
    values = []
    for k, item in enumerate(text.split(","), start=1):
        try:
            value = float(item)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"knot {k} = {item.strip()!r:.40} is not a number; give the angles phi_1..phi_p "
                "in rad, comma-separated, e.g. 0,0.5,1"
            ) from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"knot {k} = {item.strip()!r}: must be finite")
        values.append(value)
    return values


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


class Renamed(argparse.Action):
    """An option of a previous release, hidden from the help and refused saying what it became.

    ``now`` (a keyword of ``add_argument``) says it: "argument --old: became NOW", argparse's one
    line, exit 2, before any work.
    """

    def __init__(self, option_strings: list[str], dest: str, now: str, **kwargs) -> None:
        super().__init__(option_strings, dest, help=argparse.SUPPRESS, **kwargs)
        self.now = now

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        """Refuse the option, whatever its value."""
        raise argparse.ArgumentError(self, f"became {self.now}")


class DefaultsShown(argparse.RawDescriptionHelpFormatter):
    """Help that ends each option with its default, unless the help already says it.

    Flags (``store_true``, ``store_false``) and options without a fixed default (None: it
    follows from the scene, as the help says) show none.
    """

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        default = action.default
        if (
            "default" in text
            or default in (None, [], argparse.SUPPRESS)
            or isinstance(default, bool)
            or not action.option_strings
        ):
            return text
        return f"{text} (default: %(default)s)"
