"""Two runs, one folder (cable_ocp.scene.output.folder_lock): the second is refused before any work.

The lock is held for real: by a helper process that waits on a pipe (no sleeps, no race), or by
this process through the API.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest

from cable_ocp.cli import main
from cable_ocp.scene.output import (
    MARKER,
    FolderInUse,
    atomic_directory,
    folder_lock,
    lock_path,
)

MODELS = os.path.join(os.path.dirname(__file__), "..", "models")
# Holds atomic_directory(sys.argv[1]) with a file in its scratch (or, with a second argument, a
# sweep's lock of it), prints the scratch folder, and waits for a line on stdin.
HOLDER = textwrap.dedent(
    """
    import sys
    from cable_ocp.scene.output import atomic_directory
    from cable_ocp.sweep.store import folder_lock
    if len(sys.argv) > 2:
        with folder_lock(sys.argv[1], "cable-ocp sweep grid.toml"):
            print(sys.argv[1], flush=True)
            sys.stdin.readline()
    else:
        with atomic_directory(sys.argv[1]) as folder:
            (folder / "half.png").write_text("being written")
            print(folder, flush=True)
            sys.stdin.readline()
    """
)


def _hold(*args):
    """A process holding a folder's lock until it reads a line; (process, what it printed)."""
    command = [sys.executable, "-c", HOLDER, *map(str, args)]
    process = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    printed = process.stdout.readline().strip()
    assert printed, "the holder did not start"
    return process, printed


@pytest.fixture
def holder(tmp_path):
    """Start a process holding ``tmp_path/res`` mid-write; yield (process, its scratch folder)."""
    process, scratch = _hold(tmp_path / "res")
    yield process, scratch
    if process.poll() is None:
        process.communicate("done\n", timeout=60)


def test_a_command_into_a_folder_another_process_writes_is_refused_naming_it(
    tmp_path, holder, capsys
):
    process, scratch = holder
    code = main(["validate", "--elements", "3", "--out", str(tmp_path / "res")])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert f"is in use by another process (pid {process.pid} on" in err
    assert "catenary" not in capsys.readouterr().out  # refused before any work
    assert os.path.isfile(os.path.join(scratch, "half.png"))  # its live scratch is kept
    process.communicate("done\n", timeout=60)
    assert sorted(os.listdir(tmp_path / "res")) == [MARKER, "half.png"]
    assert sorted(os.listdir(tmp_path)) == ["res"]  # no scratch, no lock file left


def test_a_folder_a_sweep_holds_is_refused_to_another_command(tmp_path, capsys):
    out = tmp_path / "sweep_out"
    process, _ = _hold(out, "sweep")
    try:
        code = main(["study", "step", os.path.join(MODELS, "catenary.toml"), "--out", str(out)])
        err = capsys.readouterr().err
        assert code == 2 and f"pid {process.pid}" in err and "grid.toml" in err
        assert not out.exists()
    finally:
        process.communicate("done\n", timeout=60)
    with atomic_directory(out):  # free again
        pass


def test_a_sweep_into_a_folder_another_command_writes_is_refused(tmp_path, holder):
    from cable_ocp.sweep.store import folder_lock as sweep_lock

    process, _ = holder
    with pytest.raises(ValueError, match=rf"in use by another run \(pid {process.pid} "):
        with sweep_lock(tmp_path / "res"):
            pytest.fail("the block must not run")


def test_the_lock_is_taken_again_by_its_own_process_and_released_at_the_end(tmp_path):
    with folder_lock(tmp_path / "res") as folder:
        with atomic_directory(folder) as scratch:
            (scratch / "a.txt").write_text("a")
        assert lock_path(folder).is_file()
    assert sorted(os.listdir(tmp_path)) == ["res"]


def test_a_lock_whose_owner_died_is_taken_over(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    import socket

    path = lock_path(tmp_path / "res")
    path.write_text(f"pid {dead.stdout.strip()} on {socket.gethostname()} since then, killed\n")
    (tmp_path / ".res.cable_ocp-tmp-0badf00d").mkdir()  # its scratch
    with atomic_directory(tmp_path / "res"):
        pass
    assert sorted(os.listdir(tmp_path)) == ["res"]


def test_a_lock_left_to_a_child_of_a_dead_owner_is_broken(tmp_path):
    """flock is held while the descriptor lives: a child that kept it must not block forever."""
    import fcntl
    import socket

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    path = lock_path(tmp_path / "res")
    path.write_text(f"pid {dead.stdout.strip()} on {socket.gethostname()} since then\n")
    orphan = os.open(path, os.O_RDWR)
    fcntl.flock(orphan, fcntl.LOCK_EX | fcntl.LOCK_NB)  # as the dead owner's child would
    try:
        with atomic_directory(tmp_path / "res"):
            pass
    finally:
        os.close(orphan)
    assert sorted(os.listdir(tmp_path)) == ["res"]


def test_in_use_is_an_output_error_with_the_holder():
    assert issubclass(FolderInUse, ValueError)
