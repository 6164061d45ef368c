"""Write a folder of results atomically, and never delete anything the program did not write.

A results folder carries the marker file :data:`MARKER`. :func:`atomic_directory` writes into a
scratch folder next to the target and renames it into place when the block succeeds; it replaces
an existing target only if that is an empty folder or a previous results folder (with the marker).
Scratch folders are named ``.NAME.cable_ocp-tmp-XXXXXXXX``; one left behind by a killed run is
removed by the next run to the same target. :func:`check_target` applies the same rules without
writing, so a command can refuse a bad target before any heavy work.

Two runs never write one folder: every writer holds the folder's lock, the file
``.NAME.cable_ocp-lock`` beside it (:func:`folder_lock`, the operating system's ``flock``, with the
owner's process written in it), for as long as it writes; a folder another live process holds is
refused, naming that process. A lock whose owner died is taken over. Because only the lock's
holder writes a folder's scratch folders, the ones it finds are a killed run's.
"""

from __future__ import annotations

import json
import math
import os
import secrets
import shutil
import socket
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

try:
    import fcntl
except ModuleNotFoundError:  # Windows: no lock, one run per folder is then the user's care
    fcntl = None

MARKER = ".cable_ocp-results"
SCRATCH_TAG = "cable_ocp-tmp-"
BACKUP_TAG = "cable_ocp-old-"
LOCK_TAG = "cable_ocp-lock"
# The longest random part of a scratch or backup name (".NAME." + tag + 8 hex digits).
NAME_EXTRA = 2 + max(len(SCRATCH_TAG), len(BACKUP_TAG)) + 8


class OutputError(ValueError):
    """A results folder that must not be written (it would delete files not ours)."""


class FolderInUse(OutputError):
    """A results folder that another live process holds; ``holder`` names it."""

    def __init__(self, message: str, holder: str):
        super().__init__(message)
        self.holder = holder


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

    def refuse(reason: str) -> OutputError:
        return OutputError(f"results folder {str(given)!r} ({path}): {reason}; nothing was written")

    path = given
    try:
        path = given.expanduser().resolve(strict=False)
        path.exists()
    except (OSError, RuntimeError) as error:  # a symlink loop, a name too long for the system
        raise refuse(f"cannot be resolved ({getattr(error, 'strerror', None) or error})") from None
    cwd = Path.cwd().resolve()

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
    if path.is_symlink() and not path.exists():
        raise refuse("is a symbolic link that leads nowhere (or to itself)")
    parent = path.parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise refuse(f"{parent} is not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise refuse(f"the folder {parent} is not writable")
    longest = os.pathconf(parent, "PC_NAME_MAX") - NAME_EXTRA
    too_long = [part for part in path.relative_to(parent).parts if len(part.encode()) > longest]
    if too_long or len(str(path).encode()) + NAME_EXTRA >= os.pathconf(parent, "PC_PATH_MAX"):
        raise refuse(
            f"its name is too long for the file system (at most {longest} bytes a folder name, "
            "with room for the scratch folder's)"
        )
    return path


# Locks this process holds, by folder: a command holds its folder's lock from its first check to
# its last write, and atomic_directory inside it takes the same lock again.
_HELD: dict[Path, list] = {}
_HELD_GUARD = threading.Lock()


def lock_path(folder: str | os.PathLike) -> Path:
    """The lock file of the results folder ``folder``: ``.NAME.cable_ocp-lock`` beside it."""
    folder = Path(folder)
    return folder.parent / f".{folder.name}.{LOCK_TAG}"


def _owner_alive(record: str) -> bool:
    """Whether the owner named by a lock file's first line (``pid N on HOST ...``) may be alive.

    Only a process of this host can be seen to be dead; one of another host counts as alive.
    """
    words = record.split()
    if len(words) < 4 or words[0] != "pid" or not words[1].isdigit() or words[2] != "on":
        return True
    if words[3] != socket.gethostname():
        return True
    try:
        os.kill(int(words[1]), 0)
    except ProcessLookupError:
        return False
    except OSError:  # PermissionError: another user's live process
        return True
    return True


def _acquire(path: Path) -> tuple[int, str]:
    """Open and ``flock`` the lock file ``path``; returns the descriptor, or the holder's record.

    The descriptor is -1 when another live process holds the lock. A lock still held after its
    owner died (a child process kept the descriptor) is broken: the file is replaced.
    """
    while True:
        handle = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            record = os.pread(handle, 1000, 0).decode(errors="replace").strip() or "unknown"
            if _owner_alive(record):
                os.close(handle)
                return -1, record
            if os.fstat(handle).st_ino == os.stat(path).st_ino:
                path.unlink(missing_ok=True)  # its owner is dead: a new file, a new lock
            os.close(handle)
            continue
        try:
            same = os.fstat(handle).st_ino == os.stat(path).st_ino
        except FileNotFoundError:  # removed by its previous holder meanwhile
            same = False
        if same:
            return handle, ""
        os.close(handle)


@contextmanager
def folder_lock(
    target: str | os.PathLike, what: str | None = None, reentrant: bool = True
) -> Iterator[Path]:
    """Hold the lock of the results folder ``target`` for the block; yield its absolute path.

    The lock is the operating system's (``flock`` on :func:`lock_path`), so it is released when
    its owner ends, in whatever way; the file names the owner (process, host, start, ``what``)
    for the message of a refused run, and a lock whose named owner is dead is taken over. A
    process may take a lock it holds again (a command, then its :func:`atomic_directory`). The
    lock file is removed when the lock is released.

    Parameters
    ----------
    target : path-like
        The results folder (it need not exist).
    what : str, optional
        What holds it, e.g. ``"cable-ocp sweep grid.toml"``; default: the command line.
    reentrant : bool
        Whether a lock this process holds already may be taken again (false: it is refused as
        another holder's; a sweep does not run inside another).

    Raises
    ------
    FolderInUse
        An ``OutputError`` naming the folder and the process that holds it.
    """
    given = Path(target)
    folder = given.expanduser().resolve()
    if fcntl is None:
        yield folder
        return
    with _HELD_GUARD:
        held = _HELD.get(folder)
        if held is not None and reentrant:
            held[1] += 1
    if held is not None and not reentrant:
        holder = os.pread(held[0], 1000, 0).decode(errors="replace").strip()
        raise FolderInUse(
            f"results folder {str(given)!r} ({folder}) is in use by this process ({holder}); "
            "nothing was written",
            holder,
        )
    if held is None:
        path = lock_path(folder)
        path.parent.mkdir(parents=True, exist_ok=True)
        handle, holder = _acquire(path)
        if handle < 0:
            raise FolderInUse(
                f"results folder {str(given)!r} ({folder}) is in use by another process "
                f"({holder}): wait for it to end, or give another folder; nothing was written",
                holder,
            )
        if what is None:
            what = " ".join([Path(sys.argv[0]).name, *sys.argv[1:]]) if sys.argv else ""
        started = time.strftime("%Y-%m-%d %H:%M:%S")
        owner = f"pid {os.getpid()} on {socket.gethostname()} since {started}"
        os.pwrite(handle, f"{owner}{', ' + what[:300] if what else ''}\n".encode(), 0)
        held = [handle, 1]
        with _HELD_GUARD:
            _HELD[folder] = held
    try:
        yield folder
    finally:
        with _HELD_GUARD:
            held[1] -= 1
            last = held[1] == 0
            if last:
                del _HELD[folder]
        if last:
            lock_path(folder).unlink(missing_ok=True)  # while held: no other holder's file
            os.close(held[0])  # releases the lock


@contextmanager
def claimed_target(target: str | os.PathLike | None) -> Iterator[Path | None]:
    """:func:`check_target` and :func:`folder_lock` of ``target`` for the block (None: nothing).

    What a command does first, so that a bad or busy results folder is refused before any work
    and stays its own until the command has written it.

    Raises
    ------
    OutputError
        As :func:`check_target`, or :class:`FolderInUse`.
    """
    if target is None:
        yield None
        return
    check_target(target)
    with folder_lock(target) as folder:
        yield folder


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

    ``target`` is checked by :func:`check_target` and locked (:func:`folder_lock`) for the
    whole block. The scratch folder gets the marker
    file and ordinary permissions (0777 less the umask, 0755 with the usual umask 022). On an
    exception, interruption included, the scratch folder is removed and ``target`` is left as it
    was.

    Raises
    ------
    OutputError
        If ``target`` must not be replaced (see :func:`check_target`), or another process
        holds it (:class:`FolderInUse`).
    """
    with claimed_target(target) as target:
        _remove_stale(target.parent, target.name)  # the lock's holder writes them: a dead run's
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
