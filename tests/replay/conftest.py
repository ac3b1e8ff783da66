"""Recordings of shipped examples, simulated once per test session into a temporary folder.

Durations are cut to just past each example's accident to keep the suite fast.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from rocas.rollout import RunResult, simulate
from rocas.scenarios import load_example

#: example -> simulated seconds (enough to include its accident)
DURATIONS = {"left_turn_oncoming": 18.5, "roundabout_red_truck": 9.0, "foggy_crossing": 7.0}


@dataclasses.dataclass(frozen=True)
class Recorded:
    name: str
    path: Path
    run: RunResult


@pytest.fixture(scope="session")
def recorded(tmp_path_factory: pytest.TempPathFactory):
    """recorded(name) -> Recorded (the recording and the original run), cached."""
    folder = tmp_path_factory.mktemp("replay_recordings")
    cache: dict[str, Recorded] = {}

    def get(name: str) -> Recorded:
        if name not in cache:
            scenario = dataclasses.replace(load_example(name), duration_s=DURATIONS[name])
            path = folder / f"{name}.mcap"
            cache[name] = Recorded(name, path, simulate(scenario, output=path))
        return cache[name]

    return get
