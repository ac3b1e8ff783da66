"""The analysis .rrd: three executions, diff, searches, verdict and the default blueprint."""

import dataclasses
import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from rrd import read_rrd

from rocas.analysis.diff import diff
from rocas.rollout import simulate
from rocas.scenarios.loader import load_example
from rocas.search.ga import GenerationStats
from rocas.viz.analysis import log_run_dir, run_dir_contents, write_analysis_rrd, write_run_dir_rrd
from rocas.viz.stream import rrd_recording


def _gens(n, pop=6, seed=0):
    rng = np.random.default_rng(seed)
    return [
        GenerationStats(
            g, pop * (g + 1), g, 0.5 - 0.3 * g, rng.random((pop, 3)), np.linspace(-0.2, 1.0, pop) - 0.3 * g
        )
        for g in range(n)
    ]


def _gen_json(s):
    return {
        "generation": s.generation,
        "evaluations": s.evaluations,
        "feasible": s.feasible,
        "best_constraint": s.best_constraint,
        "objectives": s.objectives.tolist(),
        "constraints": s.constraints.tolist(),
    }


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    d = tmp_path_factory.mktemp("analysis")
    scn = dataclasses.replace(load_example("roundabout_red_truck"), duration_s=12.0)
    simulate(scn, output=d / "accident.mcap")
    white = tuple(dataclasses.replace(a, color="white") if a.id == "red_truck" else a for a in scn.actors)
    simulate(dataclasses.replace(scn, actors=white), output=d / "reference.mcap")
    return d, diff(d / "accident.mcap", d / "reference.mcap")


def test_analysis_rrd_has_every_part_and_a_blueprint(pair, tmp_path):
    d, result = pair
    out = tmp_path / "analysis.rrd"
    write_analysis_rrd(
        out,
        accident=d / "accident.mcap",
        reference=d / "reference.mcap",
        fixed=d / "reference.mcap",
        diff_result=result,
        searches={"physical": _gens(3), "cyber": _gens(2, seed=1)},
        verdict_md="# Verdict\n\n**perception**\n",
        highlight="red_truck",
    )
    e, blueprints = read_rrd(out)
    assert blueprints == 1
    for name in ("accident", "reference", "fixed"):
        p = f"/executions/{name}"
        assert e[f"{p}/ego/box"].rows > 0 and e[f"{p}/actors/boxes"].rows > 0
        assert e[f"{p}/signals/speed"].timelines == {"sim_time"}
        assert e[f"{p}/world/roads"].static_rows == 1
    # the mutated truck is highlighted in the reference (and outlined in the accident), not in fixed
    assert e["/executions/reference/actors/highlight"].rows > 0
    assert "/executions/fixed/actors/highlight" not in e
    mdr = [k for k in e if k.startswith("/diff/mdr/")]
    assert mdr and all(e[k].timelines == {"time", "sim_time"} for k in mdr)
    assert e["/diff/cmg"].static_rows == 1
    assert e["/search/physical/feasible"].rows == 3 and e["/search/cyber/feasible"].rows == 2
    assert e["/verdict"].static_rows == 1


def test_rrd_verify_accepts_the_analysis_file(pair, tmp_path):
    exe = shutil.which("rerun")
    if exe is None:
        pytest.skip("the rerun CLI is not on PATH")
    d, result = pair
    out = tmp_path / "analysis.rrd"
    write_analysis_rrd(
        out,
        accident=d / "accident.mcap",
        reference=d / "reference.mcap",
        diff_result=result,
        searches={"physical": _gens(2)},
        verdict_md="# ok\n",
    )
    proc = subprocess.run([exe, "rrd", "verify", str(out)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr


def _run_dir(pair, tmp_path, *, reference=True):
    d, result = pair
    run = tmp_path / "run"
    run.mkdir()
    shutil.copy(d / "accident.mcap", run / "accident.mcap")
    if reference:
        shutil.copy(d / "reference.mcap", run / "reference.mcap")
    (run / "diff.json").write_text(json.dumps(result.to_json()))
    (run / "physical.json").write_text(
        json.dumps(
            {
                "generations": [_gen_json(g) for g in _gens(3)],
                "triggering_entity": {"entity": "red_truck", "entities": ["red_truck"]},
            }
        )
    )
    (run / "report.md").write_text("# rocas analysis\n\nroot cause: perception\n")
    return run


def test_run_dir_shows_what_exists(pair, tmp_path):
    run = _run_dir(pair, tmp_path)
    out = tmp_path / "run.rrd"
    contents = write_run_dir_rrd(out, run)
    assert contents["highlight"] == ["red_truck"] and "fixed" not in contents
    e, blueprints = read_rrd(out)
    assert blueprints == 1
    assert "/executions/accident/ego/box" in e and "/executions/reference/ego/box" in e
    assert not any(k.startswith("/executions/fixed") for k in e)
    assert any(k.startswith("/diff/mdr/") for k in e)
    assert e["/search/physical/objectives/f1"].rows == 3 and not any(k.startswith("/search/cyber") for k in e)
    assert e["/verdict"].static_rows == 1
    assert e["/executions/reference/actors/highlight"].rows > 0


#: reports rocas analyze wrote (tests/pipeline/data): A6 with the default 200 variants, A7
#: without a validation (no configuration fix)
REPORTS = Path(__file__).parents[1] / "pipeline" / "data"


def test_run_dir_shows_the_validation_sweep(pair, tmp_path):
    from rocas.pipeline.report import Report, markdown

    run = _run_dir(pair, tmp_path)
    text = (REPORTS / "a06_validated" / "report.json").read_text()
    (run / "report.json").write_text(text)
    out = tmp_path / "run.rrd"
    contents = write_run_dir_rrd(out, run)
    report = Report.from_json(json.loads(text))
    assert contents["validation"] == report.validation and report.validation.variants == 200
    assert contents["verdict_md"] == markdown(report)
    e, _ = read_rrd(out)
    assert e["/validation/original"].static_rows == 1 and e["/validation/fix"].static_rows == 1
    assert e["/validation/summary"].static_rows == 1


def test_run_dir_without_a_validation_logs_none(pair, tmp_path):
    run = _run_dir(pair, tmp_path)
    (run / "report.json").write_text((REPORTS / "a07_rear_ended_at_red" / "report.json").read_text())
    out = tmp_path / "run.rrd"
    assert "validation" not in write_run_dir_rrd(out, run)
    e, _ = read_rrd(out)
    assert not any(k.startswith("/validation") for k in e)


def test_a_report_json_of_another_shape_is_one_clear_error(pair, tmp_path):
    from rocas.errors import InputError

    run = _run_dir(pair, tmp_path)
    (run / "report.json").write_text(json.dumps({"validation": {"variants": 0}}))
    with pytest.raises(InputError, match="report.json: not a rocas report"):
        run_dir_contents(run)


def test_run_dir_without_reference_logs_the_diff_json(pair, tmp_path):
    run = _run_dir(pair, tmp_path, reference=False)
    out = tmp_path / "partial.rrd"
    with rrd_recording(out) as rec:
        log_run_dir(rec, run)
    e, _ = read_rrd(out)
    assert e["/diff/report"].static_rows == 1
    assert not any(k.startswith("/diff/mdr") for k in e)
