"""``rocas view FILE.rrd``: any Rerun recording, natively or served to the browser (issue 40)."""

import signal
import sys

import pytest


@pytest.fixture(scope="module")
def rrd(tmp_path_factory, red_truck_recording):
    import io

    from rocas.cli.console import Env
    from rocas.cli.main import main

    path = tmp_path_factory.mktemp("rrd") / "made.rrd"
    err = io.StringIO()
    assert main(["view", str(red_truck_recording), "--rrd", str(path), "--no-viewer"],
                env=Env(stdout=io.StringIO(), stderr=err)) == 0, err.getvalue()
    return path


def test_a_native_viewer_is_given_the_file_itself(rocas, rrd, monkeypatch, fake_viewer):
    viewer = fake_viewer()
    monkeypatch.setattr("rocas.cli.view.has_display", lambda: True)
    monkeypatch.setattr("subprocess.Popen", viewer)
    res = rocas("view", rrd)
    assert res.code == 0, res.stderr
    assert "Started the Rerun viewer (process 4242)" in res.stdout
    assert viewer.argv[-1] == str(rrd.resolve())


def test_rrd_copies_it_and_a_file_that_is_not_one_is_refused(rocas, rrd, tmp_path):
    res = rocas("view", rrd, "--rrd", tmp_path / "copy.rrd", "--no-viewer")
    assert res.code == 0, res.stderr
    assert (tmp_path / "copy.rrd").read_bytes() == rrd.read_bytes()
    fake = tmp_path / "fake.rrd"
    fake.write_bytes(b"PK\x03\x04 a zip file renamed")
    res = rocas("view", fake, "--no-viewer", "--rrd", tmp_path / "x.rrd")
    assert res.code == 3 and res.stderr.count("\n") == 1
    assert "not a Rerun recording" in res.stderr and "ROS" not in res.stderr


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child")
def test_without_a_display_it_is_served_to_the_browser(rrd, serve_view):
    proc, line = serve_view([rrd, "--web-port", "0", "--grpc-port", "0"])
    try:
        assert line.startswith("Rerun web viewer: http://127.0.0.1:"), (line, proc.stderr.read())
    finally:
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    assert proc.returncode == 0 and "Traceback" not in err, err
