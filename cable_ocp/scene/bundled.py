"""The scene files shipped with the package, found the same way in a checkout and in an install.

The repository's top-level ``models/`` folder is installed as the data package ``cable_ocp.models``
(``pyproject.toml``: ``package-dir`` maps it, ``package-data`` ships its ``*.toml``), so
:func:`models_dir` is ``models/`` of the checkout in an editable install and
``site-packages/cable_ocp/models`` in an installed wheel.
"""

from __future__ import annotations

import argparse
import difflib
from importlib import resources
from pathlib import Path


def models_dir() -> Path:
    """Folder of the bundled scene files (``*.toml``), a real path on the file system.

    Raises
    ------
    RuntimeError
        If the package is imported from a zip archive, where the scenes are not files.
    """
    folder = resources.files("cable_ocp.models")
    if not isinstance(folder, Path):
        raise RuntimeError(
            f"the bundled scenes are not on the file system ({folder!r}): "
            "install cable_ocp unzipped (pip install) to use them"
        )
    return folder


def scene_names() -> list[str]:
    """Names of the bundled scenes (file names without ``.toml``), sorted."""
    return sorted(path.stem for path in models_dir().glob("*.toml"))


def scene_path(name: str) -> Path:
    """Path of the bundled scene ``name`` (``"paper_hill"`` or ``"paper_hill.toml"``).

    Raises
    ------
    ValueError
        If no bundled scene has that name; the message lists the names there are.
    """
    path = models_dir() / f"{name.removesuffix('.toml')}.toml"
    if not path.is_file():
        raise ValueError(
            f"scene name {name!r} is not a bundled scene{_did_you_mean(name)}; choose one of: "
            f"{', '.join(scene_names())}"
        )
    return path


def closest_names(name: str) -> list[str]:
    """The bundled scenes' names closest to a mistyped ``name`` (difflib), best first."""
    return difflib.get_close_matches(name.removesuffix(".toml"), scene_names(), n=3, cutoff=0.6)


def _did_you_mean(name: str) -> str:
    close = closest_names(name)
    return f" (did you mean {' or '.join(close)}?)" if close else ""


def scene_summary(name: str) -> str:
    """What the bundled scene ``name`` is: its file's first comment line, without the name.

    ``"paper_hill"`` gives ``"option B of the paper (sections 5-6): as paper_flat, ..."``; a file
    that opens otherwise gives ``""``.
    """
    first = scene_path(name).read_text(encoding="utf-8").partition("\n")[0]
    if not first.startswith("#"):
        return ""
    return first.lstrip("# ").split(" — ", 1)[-1].strip()


def scene_argument(text: str) -> Path:
    """A scene given on the command line: a file's path, or a bundled scene's name.

    An existing file wins; otherwise a bundled scene of that name (``paper_hill`` or
    ``paper_hill.toml``); otherwise the path as given, which loading then reports as missing.

    Raises
    ------
    argparse.ArgumentTypeError
        A name that is neither a file nor a bundled scene but close to bundled scenes' names
        (``paper_hil``), naming them.
    """
    path = Path(text)
    if path.exists() or path.parent != Path("."):
        return path
    name = text.removesuffix(".toml")
    if name in scene_names():
        return scene_path(name)
    if closest_names(name):
        raise argparse.ArgumentTypeError(
            f"{text!r} is neither a scene file nor a bundled scene{_did_you_mean(name)}; "
            "cable-ocp scenes lists the bundled ones"
        )
    return path
