"""The pipeline on another stack: scenarios naming their stack, simulation dispatch, replay
from the stack's own channels, the cyber space from its inventory, ``--stack`` on the CLI."""

import dataclasses
import json

import numpy as np
import pytest

from rocas.errors import ScenarioError, UsageError
from rocas.pipeline.cyber import cyber_space
from rocas.pipeline.evaluate import VariantTask, run_batch
from rocas.rollout import check_params, rollout_batch, simulate, with_stack
from rocas.scenarios import load_example
from rocas.scenarios.loader import scenario_from_dict, scenario_to_dict
from rocas.stacks.registry import get_stack


def _lav(duration=9.0):
    s = load_example("roundabout_red_truck")
    return dataclasses.replace(with_stack(s, "lav"), duration_s=duration)


def test_a_scenario_names_its_stack_and_its_overrides_are_that_stacks():
    s = _lav()
    d = scenario_to_dict(s)
    assert d["ego"]["stack"] == "lav"
    assert "stack" not in scenario_to_dict(load_example("roundabout_red_truck"))["ego"]
    d["ego"]["params"] = {"brake": {"brake_threshold": 0.5}}
    back = scenario_from_dict(d)
    assert back.ego.stack == "lav" and back.ego.overrides == {"brake.brake_threshold": 0.5}
    d["ego"]["params"] = {"perception": {"brake_threshold": 0.5}}  # the ADS's name
    with pytest.raises(ScenarioError, match="ego.params: perception.brake_threshold: unknown"):
        check_params(scenario_from_dict(d))
    d["ego"]["params"], d["ego"]["stack"] = {}, "nope"
    with pytest.raises(ScenarioError, match="ego.stack: unknown stack 'nope'"):
        check_params(scenario_from_dict(d))


def test_with_stack_refuses_another_stacks_overrides():
    s = load_example("roundabout_red_truck")
    s = dataclasses.replace(s, ego=dataclasses.replace(s.ego, params=(("planning.cruise_speed_mps", 8.0),)))
    with pytest.raises(UsageError, match="sets parameters of stack 'ads'"):
        with_stack(s, "lav")


def test_run_batch_simulates_with_the_scenarios_stack_and_its_overrides():
    s = _lav(6.0)
    s = dataclasses.replace(s, ego=dataclasses.replace(s.ego, params=(("planner.max_speed_kmh", 25.0),)))
    tasks = [VariantTask(s, (), 1), VariantTask(s, (("brake.brake_threshold", 0.9),), 2)]
    got = run_batch(tasks)
    want = rollout_batch(get_stack("lav"), [s, s], [{"planner.max_speed_kmh": 25.0},
                                                     {"planner.max_speed_kmh": 25.0,
                                                      "brake.brake_threshold": 0.9}], [1, 2])
    for i, r in enumerate(got):
        assert np.array_equal(r.ego_xy, want.ego[i, :, :2])
        assert r.outcome == want.outcomes[i]
    # the scenario's own override is in force: at most 25 km/h, not the default 35
    assert want.ego[0, -20:, 3].max() < 25.0 / 3.6 + 0.3  # starts at 9 m/s, settles below


def test_replay_reads_a_lav_recording_from_its_own_channels(tmp_path):
    from rocas.replay.reconstruction import reconstruct
    from rocas.replay.source import read_recording

    s = _lav()
    res = simulate(s, output=tmp_path / "lav.mcap")
    rec = read_recording(tmp_path / "lav.mcap")
    assert rec.stack == "lav"
    assert len(rec.ego_times) == s.num_ticks
    assert np.abs(rec.ego_track[:, :2] - res.ego[:-1, :2]).max() < 0.2  # gnss noise only
    assert set(rec.detections.color) <= {"red", "silver"} and len(rec.detections) > 0
    recon = reconstruct(tmp_path / "lav.mcap")
    assert recon.scenario.ego.stack == "lav"
    assert sorted(a.color for a in recon.scenario.actors) == sorted(a.color for a in s.actors)
    assert recon.original is not None and recon.original.kind == "emergency"


def test_the_cyber_space_of_another_stack_is_its_own_inventory_within_its_limits():
    brake = cyber_space("brake", {"brake.brake_threshold": 0.2}, "lav")
    names = [v.name for v in brake.variables]
    assert names == [p.full_name for p in get_stack("lav").parameters if p.module == "brake"]
    assert brake.variable("brake.brake_threshold").original == 0.2
    assert brake.variable("brake.camera_range_m").low == 60.0  # sensing may only grow
    controller = [v.name for v in cyber_space("controller", {}, "lav").variables]
    assert "controller.max_brake_decel_mps2" not in controller  # braking less hides accidents
    with pytest.raises(UsageError, match="no parameters for module 'perception'"):
        cyber_space("perception", {}, "lav")


@pytest.mark.slow
def test_analyze_runs_on_a_lav_recording_with_the_lav_stack(tmp_path):
    from rocas.pipeline.analyze import analyze
    from rocas.pipeline.config import AnalyzeConfig

    simulate(_lav(12.0), output=tmp_path / "acc.mcap")
    rep = analyze(tmp_path / "acc.mcap", tmp_path / "run",
                  AnalyzeConfig(budget=24, population=12, validation_variants=4,
                                alternate_references=0)).to_json()
    assert rep["stack"] == "lav"
    state = json.loads((tmp_path / "run" / "state.json").read_text())
    assert state["done"]["replay"]["reproduced"] and state["done"]["replay"]["stack"] == "lav"
    assert state["done"]["diff"]["deviating_module"] in get_stack("lav").modules
    assert rep["search_space"]["parameters_total"] == len(get_stack("lav").parameters) - 1  # less braking


def test_cli_simulate_with_stack_and_its_own_set(tmp_path, capsys):
    from rocas.cli.main import main

    out = tmp_path / "x.mcap"
    assert main(["simulate", "roundabout_red_truck", "--stack", "lav", "--duration", "2",
                 "--set", "brake.brake_threshold=0.5", "-o", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["overrides"] == {"brake.brake_threshold": 0.5}
    assert main(["simulate", "roundabout_red_truck", "--stack", "lav", "--duration", "2",
                 "--set", "perception.brake_threshold=0.5", "-o", str(out)]) == 2
    assert "did you mean brake.brake_threshold" in capsys.readouterr().err
