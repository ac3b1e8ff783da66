import sys

import pytest
from rrd import read_rrd

from rocas.cli.view import has_display


def test_view_writes_the_rrd_of_a_recording(rocas, red_truck_recording, tmp_path):
    out = tmp_path / "v.rrd"
    res = rocas("view", red_truck_recording, "--rrd", out, "--no-viewer")
    assert res.code == 0, res.stderr
    assert "Rerun recording" in res.stdout and "pose from /localization/pose" in res.stdout
    e, blueprints = read_rrd(out)
    assert blueprints == 1 and e["/executions/accident/ego/box"].rows > 0
    # raw channels come from Rerun's own MCAP importer, not re-plotted by rocas
    assert e["/canbus/chassis"].rows > 0 and "message_log_time" in e["/canbus/chassis"].timelines
    assert not any(p.startswith("/executions/accident/channels/") for p in e)


def test_view_of_a_run_dir(rocas, red_truck_recording, tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    (run / "accident.mcap").write_bytes(red_truck_recording.read_bytes())
    (run / "report.md").write_text("# verdict\n")
    out = tmp_path / "run.rrd"
    res = rocas("view", run, "--rrd", out, "--no-viewer")
    assert res.code == 0, res.stderr
    assert "executions: accident" in res.stdout and "verdict" in res.stdout
    e, _ = read_rrd(out)
    assert e["/verdict"].static_rows == 1


def test_view_warns_about_a_truncated_recording(rocas, red_truck_recording, tmp_path):
    data = red_truck_recording.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    res = rocas("view", cut, "--rrd", tmp_path / "v.rrd", "--no-viewer")
    assert res.code == 0 and "Rerun recording" in res.stdout
    assert res.stderr.startswith("rocas: warning: cut.mcap: recording is truncated (")
    run = tmp_path / "run"
    run.mkdir()
    (run / "accident.mcap").write_bytes(cut.read_bytes())
    res = rocas("view", run, "--rrd", tmp_path / "run.rrd", "--no-viewer")
    assert res.code == 0
    assert res.stderr.startswith("rocas: warning: accident.mcap: recording is truncated (")


def test_view_errors(rocas, tmp_path):
    res = rocas("view", tmp_path / "missing.mcap", "--no-viewer", "--rrd", tmp_path / "x.rrd")
    assert res.code != 0 and "no such file" in res.stderr
    res = rocas("view", tmp_path, "--no-viewer", "--rrd", tmp_path / "x.rrd")
    assert res.code != 0 and "no accident.mcap" in res.stderr
    res = rocas("view", tmp_path, "--no-viewer")
    assert res.code == 2 and "--rrd" in res.stderr and "(see 'rocas view --help')" in res.stderr
    assert not (tmp_path / "x.rrd").exists()


def test_has_display():
    if sys.platform in ("darwin", "win32"):
        pytest.skip("always a display")
    assert not has_display({})
    assert has_display({"DISPLAY": ":0"}) and has_display({"WAYLAND_DISPLAY": "wayland-0"})
