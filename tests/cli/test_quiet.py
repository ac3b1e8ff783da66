"""``--quiet`` for analyze and triage, progress counts that are the report's, and JSON output
without float noise (issue 40)."""

import io
import json
import re

import pytest

from rocas.cli.console import Env

SMALL = ("--budget", "16", "--population", "8", "--validation", "2", "--workers", "1")
#: a float literal with more than 12 significant digits (accumulated error such as
#: 0.30470000000000003 or 10.200000000000001)
NOISY = re.compile(r"(?<![\w.])-?(\d+)\.(\d+)(?:e-?\d+)?")


def _noisy_floats(text: str) -> list[str]:
    found = []
    for m in NOISY.finditer(text):
        digits = (m.group(1) + m.group(2)).lstrip("0")
        if len(digits) > 12:
            found.append(m.group())
    return found


@pytest.fixture(scope="module")
def quiet_json(tmp_path_factory):
    from rocas.cli.main import main

    out = tmp_path_factory.mktemp("quiet") / "run"
    stdout, stderr = io.StringIO(), io.StringIO()
    code = main(["analyze", "roundabout_red_truck", "--scenario", "--out", str(out), *SMALL,
                 "--json", "--quiet"], env=Env(stdout=stdout, stderr=stderr))
    return code, stdout.getvalue(), stderr.getvalue(), out


def test_quiet_analyze_writes_only_the_result(quiet_json):
    code, out, err, _ = quiet_json
    assert code == 0 and err == ""
    assert json.loads(out)["verdict"] in ("misconfiguration", "no_configuration_fix", "no_reference")


def test_the_report_and_json_output_carry_no_float_noise(quiet_json):
    _, out, _, run = quiet_json
    assert _noisy_floats(out) == []
    assert _noisy_floats((run / "report.json").read_text()) == []
    # the internal state keeps the exact values a resumed run computes with
    assert json.loads(out)["evaluations"] == json.loads((run / "state.json").read_text())["evaluations"]


def test_the_noise_check_sees_noise():
    assert _noisy_floats('{"a": 0.30470000000000003, "b": 10.200000000000001, "c": 0.3047}') == \
        ["0.30470000000000003", "10.200000000000001"]


def test_every_bar_ends_on_the_count_of_the_simulations_line(rocas, tmp_path):
    res = rocas("analyze", "roundabout_red_truck", "--scenario", "--out", tmp_path / "run", *SMALL)
    assert res.code == 0, res.stderr
    line = next(ln for ln in res.stdout.splitlines() if ln.strip().startswith("simulations"))
    summary = {k: int(n) for k, n in re.findall(r"(\w+) (\d+)", line.split("simulations", 1)[1])}
    bars = {m.group(1): int(m.group(2))
            for m in re.finditer(r"^(\w+)\s+\S*\s+(\d+) sims", res.stderr, re.MULTILINE)}
    assert summary and {k: bars[k] for k in summary} == summary
    if bars.get("minimise"):  # the cyber bar counts its search and the minimisation
        assert f"+ minimise {bars['minimise']}" in res.stderr


def test_settle_ends_each_bar_on_the_reports_count():
    from rocas.cli.analyze import _Progress

    with _Progress(Env(stdout=io.StringIO(), stderr=io.StringIO()), {"cyber": 240}) as p:
        p("cyber", {"generation": 0, "evaluations": 125, "feasible": 3})
        p("minimise", {"parameters": 2})
        p("validation", {"variants": 200, "simulations": 655, "evaluations": 600})
        p.settle({"cyber": 144, "validation": 655})
    tasks = {t.description: t for t in p._p.tasks}
    assert tasks["cyber"].fields["count"] == "144 sims"
    assert "search 125 + minimise 19" in tasks["cyber"].fields["info"]
    assert tasks["minimise"].fields["count"] == "19 sims"
    assert tasks["validation"].fields["count"] == "655 sims" and tasks["validation"].finished


def test_quiet_triage_writes_only_the_result(rocas, tmp_path):
    (tmp_path / "broken.toml").write_text("this is = not [a scenario\n")
    loud = rocas("triage", tmp_path / "broken.toml", "--out", tmp_path / "c1")
    quiet = rocas("triage", tmp_path / "broken.toml", "--out", tmp_path / "c2", "--quiet")
    assert loud.code == quiet.code == 0, loud.stderr
    assert "triage" in loud.stderr and quiet.stderr == ""
    assert "failed: broken" in quiet.stdout


def test_diff_json_carries_no_float_noise(rocas, tmp_path):
    from foreign_stack import make_pair

    pair = make_pair(tmp_path, deviating="forecaster")
    res = rocas("diff", pair.accident, pair.reference, "--json")
    assert res.code == 0, res.stderr
    assert json.loads(res.stdout)["deviating_module"] == "forecaster"
    assert _noisy_floats(res.stdout) == []
