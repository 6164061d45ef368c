"""A results folder that cannot be written, or replaced, is refused before any work with exit 2
(issue 45 item 9): a read-only folder as a sweep's --out or its parent (it gave exit 1 and a raw
``[Errno 30]``), a mount point as any command's --out (the run completed, then the rename failed
with EBUSY and left its results in a hidden folder without a word); and a run whose folder cannot
be renamed into place says where its results are."""

from __future__ import annotations

import errno
import os
import subprocess
from pathlib import Path

import pytest
from conftest import MODELS

from cable_ocp import cli
from cable_ocp.simulation import run as simulation_run
from cable_ocp.sweep import runner


@pytest.fixture
def read_only_mount(tmp_path):
    """An empty read-only tmpfs mounted at ``tmp_path / "mnt"`` (root only; skipped otherwise)."""
    mount = tmp_path / "mnt"
    mount.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(mount)],
                          capture_output=True)  # fmt: skip
    if done.returncode != 0:
        pytest.skip("cannot mount a read-only file system here (needs root)")
    try:
        yield mount
    finally:
        subprocess.run(["umount", str(mount)], check=True)


@pytest.fixture
def no_work(monkeypatch):
    """Fail the test if a simulation or a sweep's cases start."""

    def forbidden(*args, **kwargs):
        pytest.fail("a results folder that cannot be written must be refused before any work")

    monkeypatch.setattr(simulation_run, "simulate", forbidden)
    monkeypatch.setattr(runner, "_run", forbidden)


def _main(args, capsys) -> tuple[int, str]:
    code = cli.main([str(a) for a in args])
    return code, capsys.readouterr().err


@pytest.mark.parametrize("inside", [False, True])
def test_a_sweep_into_a_read_only_file_system_is_exit_2(read_only_mount, capsys, no_work, inside):
    out = read_only_mount / "sweep" if inside else read_only_mount
    code, err = _main(["sweep", "tow_speeds", "--out", out, "--quiet"], capsys)
    assert code == 2, err
    assert "not writable; nothing was written" in err and "Errno" not in err


@pytest.mark.parametrize("command", [["simulate", MODELS / "hanging.toml"], ["bench"]])
@pytest.mark.parametrize("linked", [False, True])
def test_a_mount_point_as_out_is_refused_before_any_work(
    read_only_mount, capsys, no_work, command, linked
):
    out = read_only_mount
    if linked:  # a symbolic link to it, which the results folder would resolve to
        out = read_only_mount.parent / "link"
        out.symlink_to(read_only_mount)
    code, err = _main([*command, "--out", out], capsys)
    assert code == 2, err
    assert "is a mount point, which cannot be replaced as a whole" in err
    assert sorted(p.name for p in read_only_mount.parent.iterdir()) == ["link", "mnt"][1 - linked :]


def test_a_read_only_folder_is_refused_by_the_sweep_before_its_lock(tmp_path, capsys, no_work,
                                                                    monkeypatch):  # fmt: skip
    """Without root: the folder's write permission as the system reports it, as a read-only
    mount reports it to root."""
    out = tmp_path / "sweep"
    out.mkdir()
    access = os.access
    monkeypatch.setattr(os, "access", lambda path, mode: Path(path) != out and access(path, mode))
    code, err = _main(["sweep", "tow_speeds", "--out", out, "--quiet"], capsys)
    assert code == 2 and f"--out {out}: the folder is not writable" in err
    assert list(tmp_path.iterdir()) == [out] and not any(out.iterdir())  # no lock file either


def test_results_that_cannot_be_moved_into_place_are_named(tmp_path, capsys, monkeypatch):
    out = tmp_path / "run"
    rename = Path.rename

    def busy(self, target):
        if Path(target) == out:
            raise OSError(errno.EBUSY, os.strerror(errno.EBUSY))
        return rename(self, target)

    monkeypatch.setattr(Path, "rename", busy)
    args = ["simulate", MODELS / "hanging.toml", "--set", "numerics.duration=1.0", "--quiet"]
    code, err = _main([*args, "--out", out], capsys)
    assert code == 1
    kept = [p for p in tmp_path.iterdir() if p.name.startswith(".run.cable_ocp-tmp-")]
    assert len(kept) == 1 and (kept[0] / "trajectory.nc").is_file()
    assert f"the results could not be moved to {out}; they are in {kept[0]}" in err
