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
    assert entities["/diff/cmg_removed"].static_rows == 1
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
