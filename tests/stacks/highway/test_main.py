"""``python -m rocas.stacks.highway``: list, record, and one clear line for bad input."""

import pytest

pytest.importorskip("highway_env")

from rocas.recording.formats import open_recording  # noqa: E402
from rocas.stacks.highway.__main__ import main  # noqa: E402


def test_list_names_every_entry_with_its_ground_truth(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert "h01_crawling_car_weak_brakes" in out and "no configuration fix" in out


def test_record_writes_the_accident_and_the_fix(tmp_path, capsys):
    assert main(["record", "h01", str(tmp_path / "a.mcap")]) == 0
    assert main(["record", "h01", str(tmp_path / "b.mcap"), "--fixed"]) == 0
    out = capsys.readouterr().out
    assert "collision at 7.2 s" in out and "no accident" in out
    meta = dict(open_recording(tmp_path / "b.mcap").scan().metadata)
    assert meta["rocas.run"]["collided"] == "false"


def test_an_unknown_entry_is_one_error_line(capsys):
    assert main(["record", "h99", "x.mcap"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rocas: error: no highway catalog entry 'h99'") and err.count("\n") == 1
