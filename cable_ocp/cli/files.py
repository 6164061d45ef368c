"""A results folder whose files cannot be written is a file-system error that names its cause.

netCDF reports a write that the operating system refused (a full disk, a file-size limit) as
``RuntimeError("NetCDF: HDF error")``, without the system's reason. :func:`results_folder` writes
as :func:`cable_ocp.scene.output.atomic_directory` does and turns that error into an ``OSError``
(exit 1) that says which limit was hit, found from the file system.
"""

from __future__ import annotations

import os
import re
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from cable_ocp.result_files import netcdf
from cable_ocp.scene.output import atomic_directory

try:
    import resource
except ImportError:  # Windows: no file-size limit to ask about
    resource = None

FULL_DISK = 1 << 20  # bytes free below which a failed write is put down to a full disk
# This process's mounts, one a line, the mount point in the fifth field (Linux, proc(5)).
MOUNTINFO = Path("/proc/self/mountinfo")


def _size_limit() -> int | None:
    """The file-size limit of this process in bytes (None: unlimited)."""
    if resource is None:
        return None
    limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
    return None if limit == resource.RLIM_INFINITY else limit


def _cause(folder: Path, error: RuntimeError) -> str:
    """Why writing into ``folder`` failed with netCDF's ``error``, as the file system tells it."""
    if isinstance(error, netcdf.WriteFailed):  # its scratch file is gone: the error says
        name, size = error.path.name, error.size
    else:
        files = sorted(folder.rglob("*.nc"), key=lambda p: p.stat().st_mtime)
        name = files[-1].name if files else "the results"
        size = files[-1].stat().st_size if files else 0
    limit = _size_limit()
    # A write that would cross the limit fails whole, so the file may stop short of it.
    if limit is not None:
        return (
            f"writing {name}: the file is too large for this process's file-size limit of "
            f"{limit} bytes (ulimit -f, prlimit --fsize; it got to {size} bytes); raise the "
            "limit or write less (numerics.output_every)"
        )
    free = shutil.disk_usage(folder).free
    if free < FULL_DISK:
        return (
            f"writing {name}: the disk is full ({free} bytes free on the file system of "
            f"{folder.parent}); free some space and run again"
        )
    return f"writing {name} failed ({error}); check the file system of {folder.parent}"


@contextmanager
def results_folder(target: str | os.PathLike) -> Iterator[Path]:
    """:func:`~cable_ocp.scene.output.atomic_directory`, with netCDF's write errors as OSError.

    Raises
    ------
    OSError
        netCDF could not write a file: the disk is full, a file outgrew the file-size limit, or
        the file system failed otherwise (the message says which). Nothing is left of the
        folder's new contents; a previous results folder stays as it was.
    """
    scratch = None
    try:
        with atomic_directory(target) as folder:
            scratch = folder
            try:
                yield folder
            except RuntimeError as error:
                if not str(error).startswith("NetCDF:"):
                    raise
                raise OSError(f"{_cause(folder, error)}; nothing was written") from error
    except OSError as error:
        if scratch is None or not scratch.is_dir():
            raise
        # Written, but not renamed into place: say where the results are, never hide them.
        raise OSError(
            f"{error.strerror or error}: the results could not be moved to {target}; they are "
            f"in {scratch}: move them before the next run into {target}, which removes it"
        ) from error


def mount_points() -> set[Path]:
    """The mount points of this process, bind mounts included (empty without :data:`MOUNTINFO`).

    ``os.path.ismount`` compares devices, so it misses a folder bind-mounted from the same
    file system; the kernel's mount table names every one.
    """
    try:
        lines = MOUNTINFO.read_text().splitlines()
    except OSError:
        return set()
    # Spaces, tabs, newlines and backslashes in a mount point are octal escapes (\040).
    return {
        Path(re.sub(r"\\([0-7]{3})", lambda m: chr(int(m[1], 8)), line.split()[4]))
        for line in lines
        if len(line.split()) > 4
    }


def check_replaceable(target: str | os.PathLike) -> None:
    """Refuse a results folder that cannot be replaced as a whole: a mount point.

    A results folder is written beside its target and renamed onto it
    (:func:`~cable_ocp.scene.output.atomic_directory`); a mount point (a bind mount of a folder
    included, :func:`mount_points`) cannot be renamed (EBUSY), so a run into one would end after
    all its work with its results in a hidden folder.

    Raises
    ------
    ValueError
        Naming the folder, before any work.
    """
    try:
        path = Path(target).expanduser().resolve()  # a link to a mount point is one too
    except (OSError, RuntimeError):  # a loop: check_target names it
        return
    if path.is_dir() and (os.path.ismount(path) or path in mount_points()):
        raise ValueError(
            f"results folder {str(target)!r}: is a mount point, which cannot be replaced as a "
            "whole (results are written beside it and renamed onto it): give a new subfolder "
            "of it; nothing was written"
        )
