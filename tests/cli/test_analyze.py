import json

import pytest

from rocas.pipeline.bench import score


@pytest.mark.slow  # two analyses as processes, about 20 s
def test_analyze_json_report_and_resume(rocas, tmp_path):
    out = tmp_path / "run"
    args = ["analyze", "roundabout_red_truck", "--scenario", "--out", out, "--budget", "16",
            "--population", "8", "--validation", "4", "--workers", "1", "--json"]
    res = rocas(*args)
    assert res.code == 0, res.stderr
    report = json.loads(res.stdout)
    for key in ("verdict", "accident", "triggering_entity", "deviating_module", "misconfiguration",
                "validation", "evaluations", "timings_s"):
        assert key in report
    assert report["accident"]["kind"] == "emergency"
    again = rocas(*args)
    assert again.code == 2 and "--resume" in again.stderr and "Traceback" not in again.stderr
    resumed = rocas(*args, "--resume")
    assert resumed.code == 0
    assert {k: v for k, v in json.loads(resumed.stdout).items() if k != "timings_s"} == \
        {k: v for k, v in report.items() if k != "timings_s"}


def test_analyze_bad_input(rocas, tmp_path):
    res = rocas("analyze", tmp_path / "nope.mcap", "--out", tmp_path / "r")
    assert res.code == 3 and "no such file" in res.stderr
    res = rocas("analyze", "roundabout_red_truck", "--scenario", "--budget", "2", "--out", tmp_path / "r")
    assert res.code == 2 and "--budget" in res.stderr


def test_bench_scoring():
    exp = {"verdict": "misconfiguration", "deviating_module": "perception",
           "parameters": ["perception.brake_threshold", "perception.fov_deg"],
           "fixes": [{"perception.brake_threshold": 0.99}, {"perception.fov_deg": 60.0}]}
    up = {"parameter": "perception.brake_threshold", "original": 0.8, "mutated": 0.855}
    hit = {"verdict": "misconfiguration", "deviating_module": "perception",
           "parameters": ["perception.brake_threshold"], "changes": [up]}
    assert score(exp, hit)["hit"]
    # the documented parameter moved the other way is a different fix, not the misconfiguration
    down = {**up, "mutated": 0.7}
    assert not score(exp, {**hit, "changes": [down]})["hit"]
    # an alternative counts, in its own direction (60 is below fov_deg's 90 here)
    fov = {"parameter": "perception.fov_deg", "original": 90.0, "mutated": 75.0}
    assert score(exp, {**hit, "parameters": ["perception.fov_deg"], "changes": [fov]})["hit"]
    assert not score(exp, {**hit, "parameters": ["perception.fov_deg"],
                           "changes": [{**fov, "mutated": 100.0}]})["hit"]
    assert not score(exp, {**hit, "changes": [{**up, "parameter": "perception.max_range_m"}]})["hit"]
    assert not score(exp, {**hit, "deviating_module": "planning"})["hit"]
    no_fix = {"verdict": "no_configuration_fix", "deviating_module": "perception", "parameters": [],
              "fixes": [], "changes": []}
    assert score(no_fix, {**no_fix})["hit"]


def test_progress_bars_finish_each_phase_when_the_next_starts():
    import io

    from rocas.cli.analyze import _Progress
    from rocas.cli.console import Env

    err = io.StringIO()
    with _Progress(Env(stdout=io.StringIO(), stderr=err), {"physical": 240, "validation": 8}) as p:
        p("replay", {})
        p("physical", {})
        p("physical", {"generation": 3, "evaluations": 72, "feasible": 5})
        p("diff", {})
        tasks = {t.description: t for t in p._p.tasks}
        assert tasks["replay"].finished and tasks["physical"].finished
        assert tasks["physical"].fields["count"] == "72 sims" and not tasks["diff"].finished
        # what phase V sends: 4 variants with the original and the minimal fix, 5 stronger values
        # on the accident and the 4
        p("validation", {"variants": 4, "simulations": 33})
    tasks = {t.description: t for t in p._p.tasks}
    assert all(t.finished for t in tasks.values())
    assert tasks["validation"].fields["count"] == "33 sims" and tasks["diff"].fields["count"] == "done"
    assert "0/?" not in err.getvalue()


def test_the_validation_bar_counts_the_finished_simulations():
    import io

    from rocas.cli.analyze import _Progress
    from rocas.cli.console import Env

    with _Progress(Env(stdout=io.StringIO(), stderr=io.StringIO()), {"validation": 1405}) as p:
        bar = lambda: next(t for t in p._p.tasks if t.description == "validation")  # noqa: E731
        # phase V reports after each slice; 1405 is the most it can need, 1390 what it runs
        p("validation", {"variants": 200, "simulations": 1390, "evaluations": 0})
        assert bar().fields["count"] == "0/1390" and bar().fields["info"] == "variants 200"
        p("validation", {"variants": 200, "simulations": 1390, "evaluations": 256})
        assert (bar().completed, bar().total, bar().fields["count"]) == (256, 1390, "256/1390")
    assert bar().finished and bar().fields["count"] == "1390 sims"


def test_progress_shows_the_best_accident_free_value_so_far():
    import io

    from rocas.cli.analyze import _Progress
    from rocas.cli.console import Env

    with _Progress(Env(stdout=io.StringIO(), stderr=io.StringIO()), {"cyber": 240}) as p:
        p("cyber", {"generation": 0, "evaluations": 60, "feasible": 0, "best_feasible": None,
                    "best_objective": "h2"})
        info = lambda: next(t for t in p._p.tasks if t.description == "cyber").fields["info"]  # noqa: E731
        assert info() == "gen 0, feasible 0"
        p("cyber", {"generation": 1, "evaluations": 84, "feasible": 3, "best_feasible": 1.25,
                    "best_objective": "h2"})
        assert info() == "gen 1, feasible 3, best h2 1.250"
        # a later generation without a better fix keeps the best so far
        p("cyber", {"generation": 2, "evaluations": 108, "feasible": 2, "best_feasible": 1.4,
                    "best_objective": "h2"})
        assert info() == "gen 2, feasible 2, best h2 1.250"


def test_the_generation_record_has_its_best_accident_free_second_objective():
    import numpy as np

    from rocas.pipeline.common import gen_info as _gen_info
    from rocas.search.ga import GenerationStats

    objs = np.array([[0.1, 3.0], [0.2, 1.5], [0.0, 0.5]])
    g = GenerationStats(1, 3, 2, -1.0, objs, np.array([-1.0, 0.0, 0.7]))
    assert _gen_info(g, "h2")["best_feasible"] == 1.5  # 0.5 belongs to a member that still crashes
    assert _gen_info(g, "h2")["best_objective"] == "h2"
    none = GenerationStats(1, 3, 0, 0.7, objs, np.array([0.7, 0.7, 0.7]))
    assert _gen_info(none, "f2")["best_feasible"] is None


def test_bench_prints_the_scope_ratio_from_when_the_first_fix_is_known():
    import io

    from rocas.cli.bench import render
    from rocas.cli.console import Env

    side = {"first_fix_evaluation": 1, "first_fix_batch_evaluations": 82, "parameters": 42,
            "parameter_hit": True}
    plain = {"module": {**side, "first_fix_evaluation": 3, "first_fix_batch_evaluations": 24,
                        "parameter_hit": False},
             "all": {**side, "first_fix_evaluation": 13, "first_fix_batch_evaluations": 48,
                     "parameters": 129, "parameter_hit": False}}
    res = {"hits": 0, "total": 0, "entries": [], "time_breakdown": {"cyber": 1.0},
           "time_total_s": 1.0, "search_space_reduction_mean": None, "instances": [],
           "scope_comparison": [{"id": "a05", "module": side, "all": {
               **side, "first_fix_evaluation": 6, "first_fix_batch_evaluations": 246,
               "parameters": 129, "parameter_hit": False}, "plain": plain}]}
    out = io.StringIO()
    render(res, Env(stdout=out, stderr=io.StringIO()))
    row = next(x for x in out.getvalue().splitlines() if "a05" in x)
    cells = [c.strip() for c in row.strip("│ ").split("│")]
    # batch-known counts (positions), a hit mark each, and the all/module ratio per search
    assert cells == ["a05", "82 (1) ✓", "246 (6) ✗", "3.0x", "24 (3) ✗", "48 (13) ✗", "2.0x"]


def test_bench_shows_the_robust_value_beside_the_minimal_fix():
    import io

    from rocas.cli.bench import render
    from rocas.cli.console import Env

    found = {"verdict": "misconfiguration", "deviating_module": "perception", "trigger_entity": None,
             "trigger_property": None, "parameters": ["perception.brake_threshold"],
             "changes": [{"parameter": "perception.brake_threshold", "original": 0.8, "mutated": 0.855}],
             "robust": {"perception.brake_threshold": 0.8887}}
    row = {"type": "A9", "expected": {"deviating_module": "perception",
                                      "fixes": [{"perception.brake_threshold": 0.99}]},
           "found": found, "marks": {"module": True, "parameter": True, "verdict": True}, "seconds": 1.0}
    res = {"hits": 1, "total": 1, "entries": [row], "time_breakdown": {"cyber": 1.0},
           "time_total_s": 1.0, "search_space_reduction_mean": None, "instances": [],
           "scope_comparison": []}
    out = io.StringIO()
    render(res, Env(stdout=out, stderr=io.StringIO()))
    assert "robust 0.889" in out.getvalue()


def test_the_shared_search_options_default_to_the_analysis_defaults():
    import argparse

    from rocas.cli.analyze import add_search_arguments
    from rocas.pipeline.config import AnalyzeConfig

    p = argparse.ArgumentParser()
    add_search_arguments(p)
    args, cfg = p.parse_args([]), AnalyzeConfig()
    assert (args.seed, args.budget, args.workers, args.validation, args.screening) == \
        (cfg.seed, cfg.budget, cfg.workers, cfg.validation_variants, cfg.screening)


SMALL = ("--budget", "16", "--population", "8", "--validation", "2", "--workers", "1")


def test_analyze_help_lists_the_executors_and_what_the_seed_seeds(rocas, capsys):
    from rocas.search.executor import executor_names

    assert rocas("analyze", "--help").code == 0
    text = " ".join(capsys.readouterr().out.split())  # argparse prints help itself
    assert f"where simulations run: {', '.join(executor_names())} (default local)" in text
    assert "generated instances" not in text


def test_a_catalog_file_is_a_scenario_and_the_report_shows_replay_and_settings(rocas, tmp_path):
    from importlib import resources

    toml = resources.files("rocas.catalog") / "ads" / "a10_skewed_junction_light.toml"
    res = rocas("analyze", str(toml), "--scenario", "--out", tmp_path / "run", *SMALL)
    assert res.code == 0, res.stderr
    assert "replay             simulated scenario (emergency at " in res.stdout
    assert "settings           seed 0, budget 16, population 8, scope module" in res.stdout


@pytest.mark.slow  # about 20 s
def test_the_interrupt_message_says_what_is_on_disk(rocas, monkeypatch, tmp_path):
    import importlib

    cli = importlib.import_module("rocas.cli.analyze")
    pipeline = importlib.import_module("rocas.pipeline.analyze")  # the package exports analyze()

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    # complete, then stopped while the .rrd is written
    with monkeypatch.context() as m:
        m.setattr(cli, "_write_rrd", interrupt)
        res = rocas("analyze", "roundabout_red_truck", "--scenario", "--out", tmp_path / "run",
                    *SMALL, "--rrd", tmp_path / "a.rrd")
    assert res.code == 130
    assert f"the analysis is complete in {tmp_path / 'run'}" in res.stderr
    assert "--resume --rrd" in res.stderr and "no output was written" not in res.stderr
    # stopped before a phase finished: the folder it made is gone, and the message says so
    with monkeypatch.context() as m:
        m.setattr(pipeline, "phase_replay", interrupt)
        res = rocas("analyze", "roundabout_red_truck", "--scenario", "--out", tmp_path / "new", *SMALL)
    assert res.code == 130 and "nothing was kept" in res.stderr
    assert not (tmp_path / "new").exists()
    # stopped in a search: the finished phases and the checkpoint
    run = tmp_path / "partial"
    run.mkdir()
    (run / "state.json").write_text(json.dumps({"done": {"replay": {}}}))
    (run / "physical.ckpt").write_bytes(b"x")
    assert cli.kept_after_interrupt(run, None) == (
        f"finished phases (replay) and checkpoints of the phase under way (physical.ckpt) are kept in {run}; "
        "continue with --resume")


def test_the_answer_is_said_before_the_validation_checks_it():
    import io

    from rocas.cli.analyze import _Progress
    from rocas.cli.console import Env

    err = io.StringIO()
    with _Progress(Env(stdout=io.StringIO(), stderr=err), {"validation": 8}) as p:
        p("cyber", {})
        p("answer", {"module": "perception", "fix": "perception.brake_threshold 0.8 -> 0.8564"})
        assert "found: perception misconfigured, perception.brake_threshold 0.8 -> 0.8564" in err.getvalue()
        assert [t.description for t in p._p.tasks] == ["cyber"]  # not a phase with a bar of its own


def test_analyze_joins_the_ray_cluster_at_address(rocas, monkeypatch, tmp_path):
    """--address reaches the Ray executor the analysis runs on (a stand-in records it), and
    without --executor ray it is a usage error."""
    import rocas.search.ray_executor as ray_executor
    from rocas.errors import RocasError

    joined = []

    class Unreachable:
        def __init__(self, workers=None, address=None):
            joined.append((workers, address))
            raise RocasError(f"cannot start or join {address}: stand-in")

    monkeypatch.setattr(ray_executor, "RayExecutor", Unreachable)
    r = rocas("analyze", "roundabout_red_truck", "--scenario", "--out", tmp_path / "r",
              "--executor", "ray", "--address", "head.example:6379", "--workers", "3")
    assert r.code != 0 and "cannot start or join head.example:6379" in r.stderr
    assert joined == [(3, "head.example:6379")]
    r = rocas("analyze", "roundabout_red_truck", "--scenario", "--out", tmp_path / "r",
              "--address", "head.example:6379")
    assert r.code == 2 and "--address is for --executor ray" in r.stderr


@pytest.mark.parametrize("hostile", ["../../escaped", "/tmp/rocas-abs-escape", "..", "a/../../b"])
def test_a_scenario_name_is_never_a_path(rocas, monkeypatch, tmp_path, hostile):
    import importlib
    from pathlib import Path

    from rocas.errors import InputError

    pipeline = importlib.import_module("rocas.pipeline.analyze")
    src = Path(importlib.import_module("rocas.scenarios").__file__).parent / "examples" / \
        "roundabout_red_truck.toml"
    text = src.read_text()
    line = next(ln for ln in text.splitlines() if ln.startswith("name = "))
    scenario = tmp_path / "hostile.toml"
    scenario.write_text(text.replace(line, f"name = {json.dumps(hostile)}", 1))
    seen = []

    def stop(run, *args, **kwargs):
        seen.append(run.out)
        raise InputError("stopped here")

    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    monkeypatch.setattr(pipeline, "phase_replay", stop)
    res = rocas("analyze", scenario, "--scenario", *SMALL)
    assert res.code == 3 and "stopped here" in res.stderr
    (out,) = seen
    assert out.parent == Path("runs") and len(out.parts) == 2
    assert not out.is_absolute() and ".." not in out.name and "/" not in out.name
    assert not Path("/tmp/rocas-abs-escape").exists() and not (tmp_path / "escaped").exists()


def test_two_analyses_of_one_run_directory_at_once_are_refused(rocas, tmp_path):
    import os
    import subprocess
    import sys
    from pathlib import Path

    run = tmp_path / "run"
    run.mkdir()
    root = Path(__file__).resolve().parents[2]
    holder = subprocess.Popen(
        [sys.executable, "-c", "import sys, time\nfrom rocas._lock import locked_directory\n"
         "with locked_directory(sys.argv[1]):\n    print('held', flush=True)\n    time.sleep(60)",
         str(run)], stdout=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": str(root)})
    try:
        assert holder.stdout.readline().strip() == "held"
        res = rocas("analyze", "roundabout_red_truck", "--scenario", "--out", run, *SMALL)
    finally:
        holder.kill()
        holder.wait()
    assert res.code == 2
    assert res.stderr.strip().splitlines() == [
        f"rocas: error: run directory {run} is in use by process {holder.pid} (wait for it to "
        "finish, or choose another --out)"]
    assert list(run.iterdir()) == []
