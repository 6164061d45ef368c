"""A results folder that is a bind mount is refused before any work (issue 45, O10).

``os.path.ismount`` misses a folder bind-mounted from its own file system (same device); the
kernel's mount table (:data:`cable_ocp.cli.files.MOUNTINFO`) names it. Mounting needs root, so
the table is a written one here.
"""

from __future__ import annotations

import pytest

from cable_ocp.cli import files, main


@pytest.fixture
def bound(tmp_path, monkeypatch):
    """A folder ``results here`` (a space: escaped as \\040 in the table) listed as a mount."""
    folder = tmp_path / "results here"
    folder.mkdir()
    table = tmp_path / "mountinfo"
    escaped = str(folder.resolve()).replace(" ", "\\040")
    table.write_text(
        "22 27 0:21 / /proc rw,relatime - proc proc rw\n"
        f"90 27 8:1 /data/x {escaped} ro,relatime - ext4 /dev/sda1 rw\n"
    )
    monkeypatch.setattr(files, "MOUNTINFO", table)
    return folder


def test_the_table_names_a_bind_mount_with_its_escapes(bound):
    assert bound.resolve() in files.mount_points()


def test_a_bind_mounted_results_folder_exits_2_before_any_work(bound, capsys):
    code = main(["simulate", "hanging", "--out", str(bound), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2
    assert "is a mount point" in err
    assert list(bound.parent.glob(".results here.*")) == []  # no scratch folder: no work
    assert list(bound.iterdir()) == []


def test_a_folder_beside_it_is_no_mount_point(bound):
    other = bound.parent / "other"
    other.mkdir()
    files.check_replaceable(other)  # no error
    assert other.resolve() not in files.mount_points()
