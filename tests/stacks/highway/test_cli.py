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


def test_catalog_list_shows_the_ground_truth(rocas):
    res = rocas("catalog", "list", "--stack", "highway")
    assert res.code == 0, res.stderr
    lines = res.stdout.splitlines()
    h01 = next(x for x in lines if "h01" in x)
    assert "control.ACC_MAX" in h01 and "highway-v0" in h01
    h06 = next(x for x in lines if "h06" in x)
    assert "none exists" in h06


def test_catalog_list_json_is_the_stacks_catalog(rocas):
    from rocas.stacks.highway.accidents import entries

    res = rocas("catalog", "list", "--stack", "highway", "--json")
    assert res.code == 0, res.stderr
    rows = json.loads(res.stdout)
    assert [r["key"] for r in rows] == [e.key for e in entries()]
    h01 = rows[0]
    assert (h01["id"], h01["module"], h01["parameters"], h01["fix"], h01["fixable"]) == \
        ("h01", "control", ["control.ACC_MAX"], {"control.ACC_MAX": 6.0}, True)
    h06 = next(r for r in rows if r["id"] == "h06")
    assert h06["fixable"] is False and h06["fix"] == {}


def test_catalog_record_writes_the_accidents_and_they_analyse(rocas, tmp_path):
    res = rocas("catalog", "record", tmp_path / "rec", "--stack", "highway", "--only", "h01",
                "--only", "h06")
    assert res.code == 0, res.stderr
    assert res.stdout.splitlines() == [
        f"h01: collision at 7.2 s -> {tmp_path / 'rec' / 'h01_crawling_car_weak_brakes.mcap'}",
        f"h06: collision at 0.3 s -> {tmp_path / 'rec' / 'h06_stopped_car_too_close.mcap'}"]
    from rocas.stacks.highway.accidents import entry
    from rocas.stacks.highway.analysis import read_accident

    scene, params, seed = read_accident(tmp_path / "rec" / "h01_crawling_car_weak_brakes.mcap")
    e = entry("h01")
    assert (scene, params, seed) == (e.scene, dict(e.params), e.seed)


def test_catalog_record_of_an_unknown_entry_writes_nothing(rocas, tmp_path):
    res = rocas("catalog", "record", tmp_path, "--stack", "highway", "--only", "h99")
    assert res.code != 0 and res.stderr.startswith("rocas: error: no highway catalog entry")
    assert list(tmp_path.iterdir()) == []


def test_catalog_generate_is_refused_in_one_line(rocas):
    res = rocas("catalog", "generate", "--stack", "highway", "--instances", "2")
    assert res.code == 2 and res.stderr.count("\n") == 1
    assert res.stderr.startswith("rocas: error: stack highway's catalog drives in highway-env's")


def test_bench_takes_an_executor_and_prints_the_split_per_phase(rocas, tmp_path):
    res = rocas("bench", "--stack", "highway", "h06", "--executor", "serial", "--out", tmp_path)
    assert res.code == 0, res.stderr
    text = " ".join(res.stdout.split())
    assert "Time per phase: physical " in text and " s (" in text
    assert "Simulations per phase: physical " in text and "cyber " in text
    saved = json.loads((tmp_path / "bench.json").read_text())
    assert saved["executor"] == "serial"
    assert set(saved["runs"][0]["simulations_per_phase"]) == {"physical", "diff", "cyber",
                                                               "validation"}


def test_bench_of_an_unknown_executor_is_one_error_line(rocas, tmp_path):
    res = rocas("bench", "--stack", "highway", "h06", "--executor", "nope", "--out", tmp_path)
    assert res.code == 2 and res.stderr.startswith("rocas: error: unknown executor 'nope'")


def test_analyze_prints_the_split_per_phase(rocas, tmp_path, capsys):
    assert highway_main(["record", "h06", str(tmp_path / "h06.mcap")]) == 0
    capsys.readouterr()
    res = rocas("analyze", tmp_path / "h06.mcap", "--executor", "serial", "--out",
                tmp_path / "run")
    assert res.code == 0, res.stderr
    lines = res.stdout.splitlines()
    split = next(x for x in lines if x.lstrip().startswith("time physical "))
    assert "validation " in split and "simulations " in " ".join(lines)
    assert "\\n" not in res.stdout  # the summary's lines are lines, not an escaped newline
