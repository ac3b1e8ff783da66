"""The highway stack's bench (:mod:`rocas.stacks.highway.bench`): the same answer whatever the
executor and its number of workers, and the seconds and simulations of every phase carried in
each row and summed per seed."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("highway_env")

from rocas.errors import UsageError  # noqa: E402
from rocas.stacks.highway.bench import bench  # noqa: E402
from rocas.stacks.highway.comutation import Budget  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]
#: a search of a few simulations per generation: the answer need not be the catalog's, only
#: the same on every executor
TINY = Budget(physical_population=6, physical_generations=1, cyber_population=6,
              cyber_generations=1, validation_variants=2)
PHASES = ["physical", "diff", "cyber", "validation"]


def _answer(res: dict) -> list[dict]:
    """Each row without its wall times (the only part an executor may change)."""
    return [{k: v for k, v in r.items() if k not in ("seconds", "timings_s")}
            for run in res["runs"] for r in run["entries"]]


def _same_on_serial_and_two_workers(ids: list[str]) -> dict:
    serial = bench(ids, [0], workers=1, executor="serial", budget=TINY)
    pool = bench(ids, [0], workers=2, executor="local", budget=TINY)
    assert (serial["executor"], pool["executor"]) == ("serial", "local")
    assert _answer(serial) == _answer(pool)
    assert serial["runs"][0]["simulations_per_phase"] == pool["runs"][0]["simulations_per_phase"]
    return serial


def test_the_answer_is_the_same_in_this_process_and_on_two_workers():
    res = _same_on_serial_and_two_workers(["h06"])
    run = res["runs"][0]
    row = run["entries"][0]
    assert row["hit"] and row["found"]["verdict"] == "no_configuration_fix"
    # every phase's seconds and simulations, in the row and summed for the seed
    assert list(row["timings_s"]) == PHASES and list(row["simulations"]) == PHASES
    assert run["simulations_per_phase"] == row["simulations"]
    assert row["simulations"]["physical"] > 1 and row["simulations"]["cyber"] > 0
    assert run["time_per_phase_s"] == {k: round(v, 2) for k, v in row["timings_s"].items()}


@pytest.mark.slow  # about 20 s: a fix, so the diff and the validation run too
def test_a_fix_is_the_same_in_this_process_and_on_two_workers():
    res = _same_on_serial_and_two_workers(["h01"])
    row = res["runs"][0]["entries"][0]
    assert row["found"]["parameters"] == ["control.ACC_MAX"]
    # the accident and each reference recorded, and module substitution's ideal-control run
    runs = row["confidence"]["runs"]
    assert runs >= 1 and row["simulations"]["diff"] == runs + 2
    assert row["simulations"]["validation"] > 0


@pytest.mark.parametrize("kwargs, message", [
    ({"seeds": [0, 0]}, "distinct seeds"),
    ({"seeds": [0], "executor": "nope"}, "unknown executor 'nope'"),
    ({"seeds": [0], "workers": 0}, "--workers must be at least 1"),
])
def test_bad_settings_are_refused_before_any_simulation(kwargs, message):
    with pytest.raises(UsageError, match=message):
        bench(["h06"], **kwargs)


def _ray_child(out: Path) -> subprocess.CompletedProcess[str]:
    """``rocas bench --stack highway h06 --executor ray --workers 2`` in a child process: one
    local Ray of two CPUs, started and ended there (Ray ends its driver's process when its
    cluster dies, which must not end the test run)."""
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    return subprocess.run([sys.executable, "-m", "rocas", "bench", "--stack", "highway", "h06",
                           "--executor", "ray", "--workers", "2", "--json", "--out", str(out)],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)


@pytest.mark.slow  # starts a local Ray, about 10 s
def test_the_answer_is_the_same_on_ray(tmp_path):
    pytest.importorskip("ray")
    deaths = []
    for attempt in range(2):
        done = _ray_child(tmp_path / f"ray-{attempt}")
        if done.returncode == 0:
            break
        # rocas's own error (after its progress lines) is a failure, not Ray dying
        assert not any(line.startswith("rocas: error")
                       for line in done.stderr.splitlines()), done.stderr
        deaths.append(done.stderr.strip().splitlines()[-5:])
    else:
        pytest.skip(f"Ray's local cluster ended the child twice on this machine: {deaths[-1]}")
    on_ray = json.loads(done.stdout)
    assert on_ray["executor"] == "ray"
    serial = bench(["h06"], [0], workers=1, executor="serial")
    assert _answer(on_ray) == _answer(serial)
