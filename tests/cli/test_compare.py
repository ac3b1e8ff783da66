"""``rocas compare RUN_A RUN_B``: the terminal, --json, the .rrd, and one-line errors."""

import json
import shutil

import pytest

SMALL = ("--budget", "16", "--population", "8", "--validation", "2", "--workers", "1")


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    """A real small analysis, and a copy whose report says another seed found another value."""
    import io

    from rocas.cli.console import Env
    from rocas.cli.main import main

    root = tmp_path_factory.mktemp("compare")
    a = root / "a"
    err = io.StringIO()
    code = main(["analyze", "roundabout_red_truck", "--scenario", "--out", str(a), *SMALL, "-q"],
                env=Env(stdout=io.StringIO(), stderr=err))
    assert code == 0, err.getvalue()
    b = root / "b"
    shutil.copytree(a, b)
    report = json.loads((b / "report.json").read_text())
    report["settings"]["seed"] = 7
    if report["misconfiguration"]:
        report["misconfiguration"][0]["mutated"] = 0.123
    else:
        report["deviating_module"] = "nowhere"
    (b / "report.json").write_text(json.dumps(report))
    return a, b


def test_compare_prints_what_differs_and_the_costs(rocas, two_runs):
    a, b = two_runs
    res = rocas("compare", a, b)
    assert res.code == 0, res.stderr
    assert "different answers" in res.stdout and "setting seed" in res.stdout
    assert "differs" in res.stdout and "total" in res.stdout and "seconds A" in res.stdout
    same = rocas("compare", a, a)
    assert same.code == 0 and "same answer" in same.stdout
    assert "every field and setting agrees" in same.stdout


def test_compare_json_and_rrd(rocas, two_runs, tmp_path):
    from rrd import read_rrd  # tests/viz helper

    a, b = two_runs
    res = rocas("compare", a, b, "--json", "--rrd", tmp_path / "c.rrd")
    assert res.code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["same_answer"] is False and "setting seed" in doc["differs"]
    assert doc["fields"]["setting seed"] == {"a": "0", "b": "7", "same": False}
    assert doc["costs"]["total"]["simulations_a"] == doc["costs"]["total"]["simulations_b"]
    entities, blueprints = read_rrd(tmp_path / "c.rrd")
    assert {"/compare/summary", "/compare/a", "/compare/b"} <= set(entities) and blueprints == 1


def test_a_directory_that_is_not_an_analysis_is_one_line(rocas, two_runs, tmp_path):
    a, _ = two_runs
    for other, code in ((tmp_path, 3), (tmp_path / "missing", 3)):
        res = rocas("compare", a, other)
        assert res.code == code
        lines = res.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("rocas: error: ") and "Traceback" not in res.stderr
