"""The files of result format 1 (cable_ocp 0.1): a JSON object and an ``.npz`` of arrays.

Each result's loader turns what they hold into its present fields; this module reads them, and
makes whatever is wrong in them one ``ValueError`` that names the file (:func:`blame`): a file
that is missing, truncated, not JSON, nested too deeply for Python, or whose fields do not fit.
"""

from __future__ import annotations

import zipfile
import zlib
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from cable_ocp.scene.records import parse_json

# What a damaged or foreign file raises on reading or checking it.
UNREADABLE = (OSError, ValueError, KeyError, TypeError, RecursionError, EOFError,
              zipfile.BadZipFile, zlib.error)  # fmt: skip


@contextmanager
def blame(path: Path, what: str) -> Iterator[None]:
    """Turn an error of reading or checking ``path`` into one ``ValueError``.

    Its message is one line: ``PATH: not a readable WHAT (ErrorType: message)``.
    """
    try:
        yield
    except UNREADABLE as error:
        raise ValueError(
            f"{path}: not a readable {what} ({type(error).__name__}: {error})"
        ) from None


def read_json(path: Path, what: str):
    """The JSON value of ``path`` (a ValueError naming the file if it is not JSON)."""
    with blame(path, what):
        return parse_json(Path(path).read_text())


def read_arrays(path: Path, what: str) -> dict[str, np.ndarray]:
    """The arrays of the ``.npz`` file ``path`` by name, loaded (the file is closed)."""
    with blame(path, what), np.load(path) as data:
        return {name: np.asarray(data[name]) for name in data.files}
