"""A run directory someone else made: whatever is wrong in it, ``rocas analyze --resume`` ends
in one line (damaged: exit 3; other settings or input: exit 2), never an internal error."""

from __future__ import annotations

import importlib
import json
import shutil

import pytest

SMALL = ("--budget", "16", "--population", "8", "--validation", "2", "--workers", "1")


@pytest.fixture(scope="module")
def replayed(tmp_path_factory):
    """A run directory whose replay finished (the analysis stopped as phase II started)."""
    from rocas.cli.console import Env
    from rocas.cli.main import main

    pipeline = importlib.import_module("rocas.pipeline.analyze")
    out = tmp_path_factory.mktemp("hostile_rundir") / "run"
    saved = pipeline.phase_physical

    def stop(*args, **kwargs):
        raise KeyboardInterrupt

    pipeline.phase_physical = stop
    try:
        import io

        code = main(["analyze", "roundabout_red_truck", "--scenario", "--out", str(out), *SMALL],
                    env=Env(stdout=io.StringIO(), stderr=io.StringIO()))
    finally:
        pipeline.phase_physical = saved
    assert code == 130 and json.loads((out / "state.json").read_text())["done"]["replay"]
    return out


def _set(state, path, value):
    d = state
    for k in path[:-1]:
        d = d[k]
    if value is KeyError:
        del d[path[-1]]
    else:
        d[path[-1]] = value


CASES = [
    (["done", "replay", "reproduced"], "yes", 3),
    (["done", "replay"], [], 3),
    (["done", "replay", "reproduced"], KeyError, 3),
    (["done", "diff"], {"deviating_module": 7}, 3),
    (["done", "cyber"], {"fix": {"perception.x": "big"}}, 3),
    (["done", "bogus"], {}, 3),
    (["timings_s", "replay"], [1], 3),
    (["config", "seed"], {"x": 1}, 3),
    (["config", "seed"], 99, 2),  # another run's settings: a usage error, as before
    (["source_sha256"], 5, 3),
    (["source_sha256"], "0" * 64, 2),  # another input
]


@pytest.mark.parametrize("path,value,code", CASES)
def test_a_hostile_state_json_is_one_line(rocas, replayed, tmp_path, monkeypatch, path, value, code):
    run = tmp_path / "run"
    shutil.copytree(replayed, run)
    state = json.loads((run / "state.json").read_text())
    _set(state, path, value)
    (run / "state.json").write_text(json.dumps(state))
    pipeline = importlib.import_module("rocas.pipeline.analyze")
    monkeypatch.setattr(pipeline, "phase_physical", lambda *a, **k: (_ for _ in ()).throw(
        KeyboardInterrupt))
    res = rocas("analyze", "roundabout_red_truck", "--scenario", "--out", run, *SMALL, "--resume")
    assert res.code == code, res.stderr
    assert "internal error" not in res.stderr and len(res.stderr.strip().splitlines()) == 1
    if code == 3:
        assert f"run directory {run} is damaged" in res.stderr


@pytest.mark.parametrize("content", ["", "{", "[" * 100000, '{"done": 1}', "\xff\xfe"])
def test_a_hostile_state_or_scenario_file_is_damage(rocas, replayed, tmp_path, content):
    for name in ("state.json", "scenario.json"):
        run = tmp_path / name
        shutil.copytree(replayed, run)
        (run / name).write_bytes(content.encode("latin-1"))
        res = rocas("analyze", "roundabout_red_truck", "--scenario", "--out", run, *SMALL, "--resume")
        assert res.code == 3, (name, content[:5], res.stderr)
        assert f"is damaged: {name}" in res.stderr and "internal error" not in res.stderr
