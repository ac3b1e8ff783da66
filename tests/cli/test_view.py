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


def test_native_view_leaves_the_file_to_the_viewer(rocas, red_truck_recording, monkeypatch,
                                                   fake_viewer):
    viewer = fake_viewer()
    monkeypatch.setattr("rocas.cli.view.has_display", lambda: True)
    monkeypatch.setattr("subprocess.Popen", viewer)
    res = rocas("view", red_truck_recording)
    assert res.code == 0, res.stderr
    assert "Started the Rerun viewer (process 4242)" in res.stdout
    from pathlib import Path

    shown = Path(viewer.argv[-1])
    assert shown.suffix == ".rrd" and shown.stat().st_size > 0  # not removed under the viewer
    assert str(shown) in res.stdout
    shown.unlink()
    shown.parent.rmdir()


def test_native_view_reports_a_viewer_that_fails(rocas, red_truck_recording, monkeypatch, tmp_path,
                                                  fake_viewer):
    monkeypatch.setattr("rocas.cli.view.has_display", lambda: True)
    monkeypatch.setattr("subprocess.Popen", fake_viewer(1, b"starting\nError: no GPU adapter\n"))
    res = rocas("view", red_truck_recording, "--rrd", tmp_path / "v.rrd")
    assert res.code != 0 and "exited at once with status 1: Error: no GPU adapter" in res.stderr
    assert "Opened" not in res.stdout and "Started" not in res.stdout


def test_view_web_serves_on_loopback_only(red_truck_recording, serve_view):
    import signal

    from test_serve import listening, on_loopback

    proc, line = serve_view([red_truck_recording, "--web", "--web-port", "0", "--grpc-port", "0"])
    try:
        assert line.startswith("Rerun web viewer: http://127.0.0.1:"), (line, proc.stderr.read())
        assert "?url=rerun%2Bhttp://127.0.0.1:" in line
        found = listening(proc.pid)
        assert len(found) >= 2 and all(on_loopback(ip) for ip, _ in found), found
    finally:
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    assert "Traceback" not in err and "warning" not in err


def test_view_bind_elsewhere_warns_and_a_name_is_refused(rocas, red_truck_recording, tmp_path):
    import socket

    res = rocas("view", red_truck_recording, "--web", "--bind", "evil.example")
    assert res.code == 2 and "not an IP address" in res.stderr
    res = rocas("view", red_truck_recording, "--web", "--web-port", "70000")
    assert res.code == 2 and "not a port" in res.stderr
    with socket.socket() as s:  # bound, never listening: the server stops at its port check
        s.bind(("0.0.0.0", 0))
        port = s.getsockname()[1]
        res = rocas("view", red_truck_recording, "--web", "--bind", "0.0.0.0", "--web-port", port)
    assert res.code == 5
    assert res.stderr.startswith("rocas: warning: serving on 0.0.0.0: anyone who can reach this "
                                 "machine")


def test_view_web_port_in_use_is_one_line(rocas, red_truck_recording):
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        res = rocas("view", red_truck_recording, "--web", "--web-port", port, "--grpc-port", "0")
    assert res.code == 5, res.stderr
    assert res.stderr.strip().splitlines() == [
        f"rocas: error: cannot listen on 127.0.0.1:{port}: already in use (choose another port "
        "with --web-port, or stop what listens there)"]
