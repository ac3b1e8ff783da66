import shutil
import subprocess

import pytest
from foreign_stack import make_pair
from rrd import read_rrd

from rocas.analysis import diff
from rocas.viz.diff import entity_name, write_diff_rrd


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    pair = make_pair(tmp_path_factory.mktemp("rrd"), deviating="behaviour")
    return diff(pair.accident, pair.reference)


def test_rrd_has_series_change_points_graph_report_and_blueprint(result, tmp_path):
    out = tmp_path / "diff.rrd"
    write_diff_rrd(result, out)
    entities, blueprints = read_rrd(out)
    assert blueprints == 1
    for c in result.channels:
        info = entities[f"/diff/mdr/{entity_name(c.topic)}"]
        assert info.rows == len(c.series.mdr)
        assert "time" in info.timelines
        if c.change_points.times_s:
            cp = entities[f"/diff/change_points/{entity_name(c.topic)}"]
            assert cp.rows == len(c.change_points.times_s)
    assert entities["/diff/events"].rows == sum(len(c.change_points.times_s) for c in result.channels)
    graph = entities["/diff/cmg"]
    assert graph.static_rows == 1 and any("GraphEdges" in col for col in graph.columns)
    assert "GraphNodes:positions" in " ".join(graph.columns)  # laid out in code
    assert entities["/diff/cmg/marks"].static_rows == 1  # the walk's and removed edges' dots
    assert entities["/diff/removed_edges"].static_rows == 1
    assert entities["/diff/t_star"].rows == sum(1 for c in result.channels if c.change_point_s is not None)
    assert entities["/diff/report"].static_rows == 1


def test_rrd_verify_accepts_the_file(result, tmp_path):
    exe = shutil.which("rerun")
    if exe is None:
        pytest.skip("the rerun CLI is not on PATH")
    out = tmp_path / "diff.rrd"
    write_diff_rrd(result, out)
    proc = subprocess.run([exe, "rrd", "verify", str(out)], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr


def test_cli_writes_the_rrd(rocas, result, tmp_path):
    out = tmp_path / "cli.rrd"
    res = rocas("diff", result.accident, result.reference, "--rrd", out)
    assert res.code == 0 and out.exists()
    assert "Rerun recording" in res.stdout


def test_every_rrd_has_its_own_recording_id(result, tmp_path):
    from rerun.chunk import RrdReader

    ids = []
    for name in ("one.rrd", "two.rrd"):
        write_diff_rrd(result, tmp_path / name)
        (store,) = RrdReader(tmp_path / name).recordings()
        ids.append(store.recording_id)
    assert ids[0] != ids[1]  # opened together, they stay two recordings
    assert all(i.startswith("rocas-diff-") for i in ids)


@pytest.mark.skipif(not hasattr(__import__("resource"), "RLIMIT_FSIZE"), reason="POSIX limits")
def test_a_failed_rrd_write_is_one_line_exit_5_and_no_rust_log(result, tmp_path):
    # a file-size limit makes the write fail as a full disk does; Rerun's own file sink printed
    # Rust log lines and then waited forever for its dead writer thread
    import os
    import resource
    import signal
    import sys

    def small_files():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails (EFBIG)
        resource.setrlimit(resource.RLIMIT_FSIZE, (16 << 10, 16 << 10))

    out = tmp_path / "diff.rrd"
    env = {k: v for k, v in os.environ.items() if k != "RUST_LOG"}
    proc = subprocess.run(
        [sys.executable, "-m", "rocas.cli.main", "diff", str(result.accident),
         str(result.reference), "--rrd", str(out)],
        capture_output=True, text=True, timeout=120, preexec_fn=small_files, env=env)
    assert proc.returncode == 5, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert all(ln.startswith("rocas: ") for ln in lines), lines  # the pair's warning, the error
    errors = [ln for ln in lines if ln.startswith("rocas: error:")]
    assert len(errors) == 1 and errors[0].startswith(f"rocas: error: cannot write {out}"), lines
    assert os.listdir(tmp_path) == []  # no .rrd, no temporary left behind


def test_rerun_logs_are_off_for_rocas_only():
    import os
    import sys

    code = ("import os, rocas.viz\n"
            "import rerun_bindings\n"
            "print('RUST_LOG' in os.environ)\n")
    env = {k: v for k, v in os.environ.items() if k != "RUST_LOG"}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, env=env)
    assert proc.stdout.strip() == "False", proc.stderr  # a viewer rocas starts logs as usual
