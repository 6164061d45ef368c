"""Write a folder of results atomically, and never delete anything the program did not write.

A results folder carries the marker file :data:`MARKER`. :func:`atomic_directory` writes into a
scratch folder next to the target and renames it into place when the block succeeds; it replaces
an existing target only if that is an empty folder or a previous results folder (with the marker).
Scratch folders are named ``.NAME.cable_ocp-tmp-XXXXXXXX``; one left behind by a killed run is
removed by the next run to the same target. :func:`check_target` applies the same rules without
writing, so a command can refuse a bad target before any heavy work.
"""

from __future__ import annotations

import json
import math
import os
import secrets
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

MARKER = ".cable_ocp-results"
SCRATCH_TAG = "cable_ocp-tmp-"
BACKUP_TAG = "cable_ocp-old-"


class OutputError(ValueError):
    """A results folder that must not be written (it would delete files not ours)."""


def check_target(target: str | os.PathLike) -> Path:
    """Check that ``target`` may be (re)placed by a results folder; return its absolute path.

    Allowed: a path that does not exist (its nearest existing parent a writable folder), an empty
    folder, or a previous results folder (it holds :data:`MARKER`).

    Raises
    ------
    OutputError
        A ``ValueError`` naming the folder and why: a file, the working directory or one of its
        parents, the home or root folder, a non-empty folder without the marker, an unwritable
        parent.
    """
    given = Path(target)
    path = given.expanduser().resolve()
    cwd = Path.cwd().resolve()

    def refuse(reason: str) -> OutputError:
        return OutputError(f"results folder {str(given)!r} ({path}): {reason}; nothing was written")

    if path == cwd or path in cwd.parents:
        raise refuse("is the working directory or one of its parents; give a new subfolder")
    if path == Path.home().resolve() or path == Path(path.anchor):
        raise refuse("is the home or root folder; give a new subfolder")
    if path.exists() and not path.is_dir():
        raise refuse("exists and is not a folder")
    if path.is_dir():
        try:
            names = {p.name for p in path.iterdir()}
        except OSError as error:
            raise refuse(f"cannot be read ({error.strerror})") from error
        if names and MARKER not in names:
            raise refuse(
                f"is a folder that is not empty and has no {MARKER} marker (it was not written "
                "by cable-ocp, whose results folders are replaced as a whole); give a new or "
                "empty folder"
            )
    parent = path.parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise refuse(f"{parent} is not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise refuse(f"the folder {parent} is not writable")
    return path


def _remove_stale(parent: Path, name: str) -> None:
    """Remove scratch and backup folders of ``name`` left in ``parent`` by an interrupted run."""
    prefixes = tuple(f".{name}.{tag}" for tag in (SCRATCH_TAG, BACKUP_TAG))
    for stale in parent.iterdir():
        if stale.name.startswith(prefixes) and stale.is_dir() and not stale.is_symlink():
            shutil.rmtree(stale, ignore_errors=True)


def _fresh(parent: Path, name: str, tag: str) -> Path:
    """A new folder ``.name.tagXXXXXXXX`` in ``parent`` (permissions from the umask)."""
    while True:
        path = parent / f".{name}.{tag}{secrets.token_hex(4)}"
        try:
            path.mkdir()
            return path
        except FileExistsError:
            continue


@contextmanager
def atomic_directory(target: str | os.PathLike) -> Iterator[Path]:
    """Yield a scratch folder that replaces ``target`` only if the block succeeds.

    ``target`` is checked by :func:`check_target` first. The scratch folder gets the marker
    file and ordinary permissions (0777 less the umask, 0755 with the usual umask 022). On an
    exception, interruption included, the scratch folder is removed and ``target`` is left as it
    was.

    Raises
    ------
    OutputError
        If ``target`` must not be replaced (see :func:`check_target`).
    """
    target = check_target(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    _remove_stale(target.parent, target.name)
    scratch = _fresh(target.parent, target.name, SCRATCH_TAG)
    try:
        (scratch / MARKER).write_text(
            "Written by cable-ocp; the next run writing here replaces this folder as a whole.\n"
        )
        yield scratch
    except BaseException:
        shutil.rmtree(scratch, ignore_errors=True)
        raise
    backup = None
    if target.exists():
        check_target(target)
        backup = _fresh(target.parent, target.name, BACKUP_TAG)
        target.rename(backup / target.name)
    scratch.rename(target)
    if backup is not None:
        shutil.rmtree(backup, ignore_errors=True)


def write_atomic(path: str | os.PathLike, data: str | bytes, mode: int | None = None) -> Path:
    """Write a file so that a reader sees either the old or the whole new content, never a part.

    The content goes to a scratch file ``.NAME.XXXXXXXX.tmp`` beside ``path``, which is then
    renamed onto it. ``mode`` (default: :func:`file_mode` of the folder) is set before the
    rename.
    """
    path = Path(path)
    scratch = path.parent / f".{path.name}.{secrets.token_hex(4)}.tmp"
    try:
        with open(scratch, "xb") as handle:
            handle.write(data.encode() if isinstance(data, str) else data)
        os.chmod(scratch, file_mode(path.parent) if mode is None else mode)
        os.replace(scratch, path)
    except BaseException:
        scratch.unlink(missing_ok=True)
        raise
    return path


def file_mode(folder: str | os.PathLike) -> int:
    """Permissions of a results file in ``folder``: the folder's own, without execute bits."""
    return os.stat(folder).st_mode & 0o666


def json_text(data: Any) -> str:
    """JSON text of ``data`` with NaN and infinities written as ``null`` (strict JSON).

    Numpy scalars and arrays are converted to Python numbers and lists.
    """
    return json.dumps(_finite(data), indent=1, allow_nan=False)


def _finite(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    if hasattr(value, "tolist"):  # numpy scalar or array
        return _finite(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
