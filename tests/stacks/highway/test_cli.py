"""``rocas bench --stack highway`` and ``rocas analyze`` of a highway recording: reached through
the stack's declared ``bench`` and ``analyze_recording``, printed as the built-in bench and
analysis are, with rocas's error boundary and exit codes."""

import json

import pytest

pytest.importorskip("highway_env")

from rocas.stacks.highway.__main__ import main as highway_main  # noqa: E402


def test_bench_scores_the_entry_without_a_fix_as_a_hit(rocas, tmp_path):
    res = rocas("bench", "--stack", "highway", "h06", "--workers", "1", "--out", tmp_path,
                "--json")
    assert res.code == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["stack"] == "highway" and out["seeds"] == [0]
    row = out["runs"][0]["entries"][0]
    assert row["id"] == "h06" and row["found"]["verdict"] == "no_configuration_fix"
    assert row["hit"] and out["hits_per_seed"] == {"0": 1}
    assert json.loads((tmp_path / "bench.json").read_text())["every_seed"] == 1


def test_bench_prints_the_table(rocas, tmp_path):
    res = rocas("bench", "--stack", "highway", "h06", "--workers", "1", "--out", tmp_path)
    assert res.code == 0, res.stderr
    assert "Table 4 for stack highway: 1 of 1 hit" in res.stdout and "h06" in res.stdout


@pytest.mark.parametrize("option", [["--budget", "10"], ["--instances", "2"],
                                    ["--no-second-opinion"]])
def test_a_pipeline_only_option_is_one_error_line(rocas, tmp_path, option):
    res = rocas("bench", "--stack", "highway", "h06", "--out", tmp_path, *option)
    assert res.code == 2 and "Traceback" not in res.stderr
    assert res.stderr.startswith("rocas: error: stack highway benches in its own world")


def test_an_unknown_entry_is_one_error_line(rocas, tmp_path):
    res = rocas("bench", "--stack", "highway", "h99", "--out", tmp_path)
    assert res.code != 0 and res.stderr.startswith("rocas: error: no highway catalog entry")
    assert "Traceback" not in res.stderr


def test_analyze_a_recording_without_a_fix(rocas, tmp_path, capsys):
    assert highway_main(["record", "h06", str(tmp_path / "h06.mcap")]) == 0
    capsys.readouterr()
    res = rocas("analyze", tmp_path / "h06.mcap", "--workers", "1", "--out", tmp_path / "run",
                "--json")
    assert res.code == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["stack"] == "highway" and out["verdict"] == "no_configuration_fix"
    assert out["misconfiguration"] == []
    assert json.loads((tmp_path / "run" / "report.json").read_text())["verdict"] == out["verdict"]


def test_analyze_a_recording_without_an_accident_exits_4(rocas, tmp_path, capsys):
    assert highway_main(["record", "h01", str(tmp_path / "fixed.mcap"), "--fixed"]) == 0
    capsys.readouterr()
    res = rocas("analyze", tmp_path / "fixed.mcap", "--workers", "1", "--out", tmp_path / "run")
    assert res.code == 4 and res.stderr.startswith("rocas: error: ") and "no accident" in res.stderr


def test_analyze_refuses_a_pipeline_only_option(rocas, tmp_path, capsys):
    assert highway_main(["record", "h06", str(tmp_path / "h06.mcap")]) == 0
    capsys.readouterr()
    res = rocas("analyze", tmp_path / "h06.mcap", "--scope", "all", "--out", tmp_path / "run")
    assert res.code == 2 and "does not take --scope" in res.stderr


def test_the_trigger_is_the_references_largest_change():
    from rocas.search.executor import SerialExecutor
    from rocas.stacks.highway.accidents import entry
    from rocas.stacks.highway.analysis import trigger
    from rocas.stacks.highway.comutation import analyze

    e = entry("h01")
    a = analyze(e.scene, e.params, e.seed, executor=SerialExecutor())
    assert a.reference is not None and a.reference_change
    who, prop = trigger(a)
    assert f"{who}.{prop}" in a.reference_change
