"""The external-process adapter: the LAV-like stack run as a separate program gives the same
recording and outcome as in-process, batches run as several processes, results are cached."""

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

from rocas.catalog import entry
from rocas.errors import UsageError
from rocas.recording.formats import open_recording
from rocas.rollout import rollout
from rocas.stacks.external import ExternalStack
from rocas.stacks.registry import get_stack

STACK_FILE = Path(__file__).with_name("lav-process.toml")


def _stack(tmp_path):
    ext = ExternalStack.from_file(STACK_FILE, tmp_path / "cache")
    return dataclasses.replace(ext, command=(sys.executable, *ext.command[1:]))


def _messages(path):
    return [(m.channel.topic, m.log_time_ns, m.data) for m in open_recording(str(path)).messages()]


@pytest.mark.slow
def test_the_external_process_gives_what_the_stack_gives_in_process(tmp_path):
    ext = _stack(tmp_path)
    assert {p.full_name for p in ext.parameters} == {
        p.full_name for p in get_stack("lav").parameters}
    s = dataclasses.replace(entry("A9").scenario, duration_s=3.0)
    params = {"brake.brake_threshold": 0.5}
    first = ext.run(s, params, 4)
    inproc = rollout(get_stack("lav"), s, params, 4, output=tmp_path / "in.mcap")
    assert not first.cached and first.outcome == inproc.outcome
    assert _messages(first.recording) == _messages(tmp_path / "in.mcap")
    again = ext.run(s, params, 4)
    assert again.cached and again.recording == first.recording
    batch = ext.run_batch([s, s], [params, None], [4, 5], processes=2)
    assert batch[0].cached and not batch[1].cached
    assert batch[1].outcome == rollout(get_stack("lav"), s, None, 5).outcome


def test_a_failing_command_is_reported_in_one_line(tmp_path):
    ext = dataclasses.replace(_stack(tmp_path), command=(sys.executable, "-c",
                                                         "import sys; sys.exit('boom')"))
    s = dataclasses.replace(entry("A9").scenario, duration_s=0.5)
    with pytest.raises(UsageError, match="exited 1: boom"):
        ext.run(s)


@pytest.mark.slow
def test_the_batch_mode_gives_the_in_process_rows_and_is_cached(tmp_path, monkeypatch):
    """What an analysis reads through the adapter (trajectories, gaps, outcomes of a batch)
    is bit-identical to the in-process batch, and a repeated batch starts no process."""
    from rocas.rollout import simulate_batch
    from rocas.stacks import external

    ext = dataclasses.replace(_stack(tmp_path), stack="lav")
    e = entry("L3", "lav")
    scenarios = [e.scenario, e.reference_scenario, e.scenario]
    params = [{}, {}, dict(e.truth.fix)]
    seeds = [3, 3, 7]
    inproc = simulate_batch(scenarios, params, seeds)
    calls = []
    real_call = external.ExternalStack._call
    monkeypatch.setattr(external.ExternalStack, "_call",
                        lambda self, args: calls.append(args) or real_call(self, args))
    got = ext.simulate_batch(scenarios, params, seeds)
    assert len(calls) == 1  # 3 variants: fewer than min_per_process, one process
    assert got.outcomes == inproc.outcomes and got.actor_ids == inproc.actor_ids
    for name in ("times", "ego", "actors", "min_gap"):
        assert np.array_equal(getattr(got, name), getattr(inproc, name)), name
    split = dataclasses.replace(ext, cache_dir=tmp_path / "split", min_per_process=1)
    assert split.simulate_batch(scenarios, params, seeds).outcomes == inproc.outcomes
    assert len(calls) == 3  # two more processes, two and one variants
    monkeypatch.setattr(external.ExternalStack, "_call",
                        lambda self, args: pytest.fail("ran the command for a cached batch"))
    again = ext.simulate_batch(scenarios, params, seeds)
    assert again.outcomes == inproc.outcomes


def test_a_registered_external_stack_simulates_itself_with_the_declarations_it_stands_for(
        tmp_path):
    from rocas.rollout import drive_with, simulate
    from rocas.stacks import registry
    from rocas.stacks.base import SelfSimulating

    ext = _stack(tmp_path)
    registry.register(ext, replace=True)
    assert registry.get_stack("lav-process") is ext and isinstance(ext, SelfSimulating)
    lav = registry.get_stack("lav")
    assert ext.modules == lav.modules and ext.pace_limits == lav.pace_limits
    assert not getattr(ext, "substitutable", ())  # not declared by lav: not taken
    s = dataclasses.replace(drive_with(entry("A9").scenario, "lav"), duration_s=1.0)
    mine = simulate(drive_with(s, "lav-process"), seed=0)
    theirs = simulate(s, seed=0)
    np.testing.assert_array_equal(mine.ego, theirs.ego)
    assert registry.portable()[-1] is ext


def test_analyze_refuses_a_stack_file_for_another_stack(rocas, tmp_path):
    other = tmp_path / "other.toml"
    other.write_text('name = "x"\ncommand = ["x-sim"]\nstack = "ads"\n'
                     '[parameters.planner]\n'
                     'a = { default = 1.0, range = [0.0, 2.0], unit = "", doc = "a" }\n')
    rec = Path(__file__).resolve().parents[2] / "recordings" / "lav" / \
        "l01_red_truck_roundabout.mcap"
    r = rocas("analyze", rec, "--out", tmp_path / "run", "--stack-file", other)
    assert r.code != 0 and "simulates stack 'ads', the accident's is 'lav'" in r.stderr
    assert "Traceback" not in r.stderr


def test_a_stack_file_whose_parameters_file_is_missing_or_not_toml_is_one_line(tmp_path):
    stack = tmp_path / "stack.toml"
    stack.write_text('command = ["sim"]\nparameters = "params.toml"\n')
    with pytest.raises(UsageError, match="its parameters file cannot be read: cannot read "
                                         "parameters file .*params.toml: no such"):
        ExternalStack.from_file(stack, tmp_path / "cache")
    (tmp_path / "params.toml").write_text("this is = not [toml")
    with pytest.raises(UsageError, match="its parameters file cannot be read: .*not valid TOML"):
        ExternalStack.from_file(stack, tmp_path / "cache")
    (tmp_path / "params.toml").unlink()
    (tmp_path / "params.toml").symlink_to("/dev/zero")
    with pytest.raises(UsageError, match="too large for a parameters file"):
        ExternalStack.from_file(stack, tmp_path / "cache")
    stack.write_text("[" * 2000)
    with pytest.raises(UsageError, match="cannot read the stack file"):
        ExternalStack.from_file(stack, tmp_path / "cache")
