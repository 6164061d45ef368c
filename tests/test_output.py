"""Results folders (never delete what the program did not write) and the files written in them."""

import json
import os
import stat

import numpy as np
import pytest

from cable_ocp.scene.output import MARKER, OutputError, atomic_directory, check_target, json_text


def _listing(folder):
    return sorted(p.name for p in folder.iterdir())


@pytest.fixture
def umask():
    """Set the process umask for one test and restore it afterwards."""
    saved = os.umask(0o022)
    yield os.umask
    os.umask(saved)


def test_new_folder_has_the_marker_and_umask_permissions(tmp_path, umask):
    umask(0o022)
    with atomic_directory(tmp_path / "res") as folder:
        (folder / "a.txt").write_text("a")
    assert _listing(tmp_path / "res") == [MARKER, "a.txt"]
    assert stat.S_IMODE((tmp_path / "res").stat().st_mode) == 0o755
    umask(0o027)
    with atomic_directory(tmp_path / "other"):
        pass
    assert stat.S_IMODE((tmp_path / "other").stat().st_mode) == 0o750
    assert _listing(tmp_path) == ["other", "res"]  # no scratch or backup left


def test_previous_results_folder_is_replaced(tmp_path):
    with atomic_directory(tmp_path / "res") as folder:
        (folder / "old.txt").write_text("old")
    with atomic_directory(tmp_path / "res") as folder:
        (folder / "new.txt").write_text("new")
    assert _listing(tmp_path / "res") == [MARKER, "new.txt"]
    assert _listing(tmp_path) == ["res"]


def test_empty_folder_is_accepted(tmp_path):
    (tmp_path / "res").mkdir()
    with atomic_directory(tmp_path / "res") as folder:
        (folder / "a.txt").write_text("a")
    assert _listing(tmp_path / "res") == [MARKER, "a.txt"]


def test_unmarked_folder_with_files_is_refused_and_kept(tmp_path):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("precious")
    with pytest.raises(OutputError, match=r"'.*mine'.*not empty and has no \.cable_ocp-results"):
        with atomic_directory(mine):
            pytest.fail("the block must not run")
    assert _listing(mine) == ["thesis.tex"]
    assert _listing(tmp_path) == ["mine"]


@pytest.mark.parametrize("where", ["cwd", "parent of cwd", "home"])
def test_working_and_home_folders_are_refused(tmp_path, monkeypatch, where):
    work = tmp_path / "work"
    work.mkdir()
    (work / MARKER).write_text("")  # even a marked folder: it is where the user stands
    monkeypatch.chdir(work)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    (tmp_path / "home").mkdir()
    target = {"cwd": ".", "parent of cwd": "..", "home": str(tmp_path / "home")}[where]
    reason = "home or root" if where == "home" else "working directory or one of its parents"
    with pytest.raises(OutputError, match=reason):
        check_target(target)
    assert _listing(work) == [MARKER]


def test_a_file_and_a_file_as_parent_are_refused(tmp_path):
    (tmp_path / "f.txt").write_text("x")
    with pytest.raises(OutputError, match="exists and is not a folder"):
        check_target(tmp_path / "f.txt")
    with pytest.raises(OutputError, match="is not a folder"):
        check_target(tmp_path / "f.txt" / "res")
    assert (tmp_path / "f.txt").read_text() == "x"


def test_new_nested_folder_is_created(tmp_path):
    assert check_target(tmp_path / "a" / "b") == tmp_path / "a" / "b"
    with atomic_directory(tmp_path / "a" / "b") as folder:
        (folder / "x").write_text("x")
    assert _listing(tmp_path / "a" / "b") == [MARKER, "x"]


@pytest.mark.parametrize("error", [RuntimeError("boom"), KeyboardInterrupt()])
def test_failure_or_interrupt_keeps_the_old_folder_and_leaves_no_scratch(tmp_path, error):
    with atomic_directory(tmp_path / "res") as folder:
        (folder / "old.txt").write_text("old")
    with pytest.raises(type(error)):
        with atomic_directory(tmp_path / "res") as folder:
            (folder / "new.txt").write_text("new")
            raise error
    assert _listing(tmp_path / "res") == [MARKER, "old.txt"]
    assert _listing(tmp_path) == ["res"]


def test_stale_scratch_of_a_killed_run_is_removed_on_the_next_run(tmp_path):
    for name in (".res.cable_ocp-tmp-1a2b3c4d", ".res.cable_ocp-old-5e6f7a8b"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "half.png").write_text("half")
    (tmp_path / ".res.notes").mkdir()  # not a name we create: kept
    (tmp_path / ".other.cable_ocp-tmp-00000000").mkdir()  # another target's: kept
    with atomic_directory(tmp_path / "res"):
        pass
    assert _listing(tmp_path) == [".other.cable_ocp-tmp-00000000", ".res.notes", "res"]


def test_json_text_is_strict_json_with_null_for_nan():
    text = json_text({"a": float("nan"), "b": [1.0, float("inf")], "c": np.float64(2.5),
                      "d": np.array([np.nan, 3.0]), "e": "x"})  # fmt: skip
    assert json.loads(text) == {"a": None, "b": [1.0, None], "c": 2.5, "d": [None, 3.0], "e": "x"}
    assert "NaN" not in text and "Infinity" not in text


def test_a_symlink_loop_or_a_name_too_long_is_refused_before_any_work(tmp_path):
    (tmp_path / "loop").symlink_to(tmp_path / "loop")
    with pytest.raises(OutputError, match="loop"):
        check_target(tmp_path / "loop" / "res")
    with pytest.raises(OutputError, match="its name is too long"):
        check_target(tmp_path / ("r" * 240))  # fits alone, not with the scratch folder's tag
    assert _listing(tmp_path) == ["loop"]
