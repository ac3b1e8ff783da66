"""A run directory is someone's data: state.json is checked before it is used, and a directory
being written is locked against a second rocas."""

from __future__ import annotations

import copy
import json
import subprocess
import sys

import pytest

from rocas._lock import locked_directory
from rocas.errors import InputError, UsageError
from rocas.pipeline.rundir import read_state

GOOD = {
    "version": 2, "source": "/r/a.mcap", "config": {"seed": 0, "scope": "module"},
    "done": {"replay": {"source": "scenario", "reproduced": True, "recorded_accident": None,
                        "accident": {"kind": "collision", "time_s": 4.5, "other": "car_1"},
                        "ego_rmse_m": 0.0, "stack": "ads"},
             "diff": {"deviating_module": "perception", "path": ["/control", "control"],
                      "control_channel": "/control", "fallback": None, "entries": None,
                      "warnings": []},
             "cyber": {"module": "perception", "scope": "module", "parameters": 3, "generations": [],
                       "evaluations": 24, "feasible": 1, "first_fix_evaluation": 3,
                       "first_fix_batch_evaluations": 8, "fix": {"perception.x": 1.5}}},
    "timings_s": {"replay": 1.5}, "evaluations": {"replay": 1}, "source_sha256": "00",
}


def _with(path, value):
    """GOOD with the entry at ``path`` (keys) set to ``value``."""
    state = copy.deepcopy(GOOD)
    d = state
    for k in path[:-1]:
        d = d[k]
    d[path[-1]] = value
    return state


@pytest.mark.parametrize("state", [
    [1, 2],
    _with(["done"], []),
    _with(["config"], "x"),
    _with(["source"], 5),
    _with(["done", "bogus"], {}),
    _with(["done", "replay"], "yes"),
    _with(["done", "replay", "reproduced"], "yes"),
    _with(["done", "diff", "deviating_module"], ["planning"]),
    _with(["done", "cyber", "fix"], {"perception.x": "1.5"}),
    _with(["done", "cyber", "fix"], {"perception.x": True}),
    _with(["done", "diff", "surprise"], 1),
    _with(["done", "replay", "accident"], {"kind": "collision"}),
    _with(["version"], 1),  # the layout before phase results were typed
    {k: v for k, v in GOOD.items() if k != "version"},
    _with(["timings_s", "replay"], "fast"),
    _with(["config", "seed"], {"nested": 1}),
])
def test_wrong_types_in_state_json_are_damage(tmp_path, state):
    (tmp_path / "state.json").write_text(json.dumps(state))
    with pytest.raises(InputError, match=r"run directory .* is damaged: state.json") as e:
        read_state(tmp_path)
    assert f"delete {tmp_path}" in e.value.hint


def test_a_good_state_is_read_and_deep_or_huge_ones_are_damage(tmp_path):
    (tmp_path / "state.json").write_text(json.dumps(GOOD))
    assert read_state(tmp_path).to_json() == GOOD
    (tmp_path / "state.json").write_text("[" * 100000 + "]" * 100000)
    with pytest.raises(InputError, match="damaged: state.json is not valid JSON"):
        read_state(tmp_path)
    (tmp_path / "state.json").unlink()
    (tmp_path / "state.json").symlink_to("/dev/zero")
    with pytest.raises(InputError, match="damaged: state.json cannot be read .*too large"):
        read_state(tmp_path)


def test_a_directory_in_use_is_refused_with_the_holders_pid(tmp_path):
    holder = subprocess.Popen(
        [sys.executable, "-c", "import sys, time\nfrom rocas._lock import locked_directory\n"
         "with locked_directory(sys.argv[1]):\n    print('held', flush=True)\n    time.sleep(60)",
         str(tmp_path)], stdout=subprocess.PIPE, text=True,
        env={**__import__("os").environ, "PYTHONPATH": str(__import__("pathlib").Path(__file__).parents[2])})
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(UsageError, match=rf"run directory {tmp_path} is in use by process "
                                             rf"{holder.pid}") as e:
            with locked_directory(tmp_path):
                pass
        assert "wait for it to finish" in e.value.hint
    finally:
        holder.kill()
        holder.wait()
    with locked_directory(tmp_path):  # released when its holder ended
        pass
    assert list(tmp_path.iterdir()) == []  # no lock file left behind


def test_a_state_of_the_untyped_layout_is_refused_in_one_line(tmp_path):
    old = {"version": 1, "source": "/r/a.mcap", "config": {}, "timings_s": {}, "evaluations": {},
           "done": {"replay": {"reproduced": True}}}
    (tmp_path / "state.json").write_text(json.dumps(old))
    with pytest.raises(InputError) as e:
        read_state(tmp_path)
    assert e.value.message.splitlines() == [
        f"run directory {tmp_path} is damaged: state.json has layout 1 of another rocas version, "
        "not layout 2"]
