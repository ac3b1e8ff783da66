"""Atomic outputs (rocas._fs): failures become OutputError and leave nothing behind."""

from __future__ import annotations

import errno

import pytest

from rocas._fs import atomic_path, check_writable, write_text_atomic
from rocas.errors import OutputError


def test_a_directory_or_a_path_under_a_file_is_an_output_error(tmp_path):
    (tmp_path / "dir").mkdir()
    (tmp_path / "file").write_text("keep")
    for bad in (tmp_path / "dir", tmp_path / "file" / "x.json"):
        with pytest.raises(OutputError, match=f"cannot write {bad}"):
            write_text_atomic(bad, "{}")
        with pytest.raises(OutputError):
            check_writable(bad)
    assert (tmp_path / "file").read_text() == "keep"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dir", "file"]


def test_a_full_disk_while_writing_is_an_output_error_and_the_old_file_stays(tmp_path):
    target = tmp_path / "report.json"
    target.write_text("old")
    with pytest.raises(OutputError, match="free some space"), atomic_path(target) as tmp:
        tmp.write_text("half")
        raise OSError(errno.ENOSPC, "No space left on device")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["report.json"]


def test_check_writable_leaves_no_file(tmp_path):
    check_writable(tmp_path / "out.rrd")
    assert list(tmp_path.iterdir()) == []


def test_a_missing_folder_is_refused_not_created(tmp_path):
    target = tmp_path / "nonexistent" / "dir" / "out.rrd"
    with pytest.raises(OutputError, match="the folder .*dir does not exist") as info:
        check_writable(target)
    assert "mkdir -p" in info.value.hint
    assert not (tmp_path / "nonexistent").exists()
