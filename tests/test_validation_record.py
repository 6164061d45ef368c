"""The validation record is the same whether the run is one process or pytest-xdist's workers.

The default run has two workers (pyproject.toml); the rows travel to the main process in the
reports (tests/conftest.py, ``ValidationRecord``), which alone writes the record.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# Two files of validation rows, so that both workers of a parallel run record some.
CASES = ["tests/test_statics.py::test_catenary_elastic_error_n15",
         "tests/test_statics.py::test_hanging_top_tension_is_submerged_weight",
         "tests/test_statics.py::test_catenary_tensions"]  # fmt: skip


def record(tmp_path: Path, workers: str) -> str:
    path = tmp_path / f"record_{workers}.md"
    command = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-n", workers,
               "--dist", "load", f"--validation-report={path}", *CASES]  # fmt: skip
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    return path.read_text()


def test_two_workers_write_the_record_of_one_process(tmp_path):
    one, two = record(tmp_path, "0"), record(tmp_path, "2")
    rows = [line for line in one.splitlines() if line.startswith("| ") and "`tests/" in line]
    # The catenary's error and tensions, the hanging top tension with and without torsion.
    assert len(rows) >= 4 and all(line.endswith("| passed |") for line in rows)
    assert two == one
