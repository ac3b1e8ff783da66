"""The engine drives whatever stack the caller gives it (rocas.sim.protocol), no ADS needed."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rocas.msgs import control_pb2
from rocas.recording.formats import open_recording
from rocas.scenarios import scenario_from_dict
from rocas.sim.engine import simulate, simulate_batch
from rocas.sim.protocol import Actuation, Observation, StackRun

ROAD = {
    "scenario": {"name": "brake_and_hold", "duration_s": 8.0},
    "lanes": [{"id": "a", "points": [[0, 0], [300, 0]]}],
    "ego": {"route": ["a"], "start_s_m": 40.0, "start_speed_mps": 6.0},
}


@dataclass(frozen=True)
class _Channel:
    topic: str = "/cmd"
    message_type: type[Any] = control_pb2.ControlCommand
    writer: str = "brake"
    readers: tuple[str, ...] = ("car",)
    period_s: float = 0.05
    role: str | None = "control"


class BrakeAndHold:
    """Brakes at 3 m/s^2 until standing, then holds; says per variant whether it has a traffic
    reason to stand (``justified``, (N,) bool)."""

    def __init__(self, justified: np.ndarray) -> None:
        self.justified = justified
        self.seen: list[Observation] = []
        self.last = np.zeros(0)

    def step(self, obs: Observation) -> Actuation:
        self.seen.append(obs)
        self.last = np.where(obs.ego_speed > 0.0, -3.0, 0.0)
        n = obs.ego_x.shape[0]
        return Actuation(self.last, np.zeros(n), np.zeros(n, dtype=bool), self.justified)

    def publish(self, sink, tick: int, t_ns: int) -> None:
        msg = control_pb2.ControlCommand()
        msg.acceleration = float(self.last[0])
        sink("/cmd", msg, t_ns)

    def digest(self) -> dict[str, np.ndarray]:
        return {"brake": self.last.copy()}


def test_the_oracles_judge_a_stop_by_the_stacks_stop_justified():
    sc = scenario_from_dict(ROAD)
    runs: list[BrakeAndHold] = []

    def factory(world):
        runs.append(BrakeAndHold(np.array([False, True])))
        return runs[-1]

    res = simulate_batch([sc, sc], factory, digest_modules=("brake",))
    assert isinstance(runs[0], StackRun)
    assert res.ego[:, -1, 3].max() < 0.1  # both stand still at the end
    assert [o.unexpected_stop for o in res.outcomes] == [True, False]
    assert not any(o.hard_brake or o.collided for o in res.outcomes)
    # one observation per step, the ego as the engine integrated it
    assert len(runs[0].seen) == len(res.times) - 1
    assert np.array_equal(runs[0].seen[5].ego_x, res.ego[:, 5, 0])
    assert res.digests is not None and res.digests.shape == (2, 1)
    # the stack's digests summed over the steps: -3 for every step it braked
    assert np.array_equal(res.digests[:, 0], -3.0 * (res.ego[:, :-1, 3] > 0).sum(axis=1))


def test_recording_mode_writes_the_stacks_channels_and_messages(tmp_path):
    sc = scenario_from_dict(ROAD)
    path = tmp_path / "run.mcap"
    run = simulate(sc, lambda world: BrakeAndHold(np.array([True])), output=path,
                   channels=(_Channel(),), param_overrides={"brake.decel_mps2": 3.0})
    assert run.recording == str(path) and run.messages == len(run.times) - 1
    rec = open_recording(path)
    accels = [m.message.acceleration for m in rec.decoded()]
    assert len(accels) == run.messages and accels[0] == -3.0 and accels[-1] == 0.0
    (ch,) = rec.topics().values()
    assert ch.topic == "/cmd"
    assert ch.metadata["rocas.writers"] == "brake" and ch.metadata["rocas.role"] == "control"
    meta = dict(rec.metadata)
    assert meta["rocas.ego"]["params"] == '{"brake.decel_mps2": 3.0}'
    assert meta["rocas.run"]["unexpected_stop"] == "false"
    assert rec.attachment("rocas/world.json") is not None
