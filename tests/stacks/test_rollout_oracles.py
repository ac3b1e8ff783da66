"""The rollout's oracles judge a stop by the stack's own stop_justified."""

from __future__ import annotations

import numpy as np

from rocas.rollout import rollout_batch
from rocas.scenarios import scenario_from_dict
from rocas.stacks.base import Actuation, Observation

ROAD = {
    "scenario": {"name": "brake_and_hold", "duration_s": 8.0},
    "lanes": [{"id": "a", "points": [[0, 0], [300, 0]]}],
    "ego": {"route": ["a"], "start_s_m": 40.0, "start_speed_mps": 6.0},
}


class _Run:
    def __init__(self, justified: bool) -> None:
        self.justified = justified

    def step(self, obs: Observation) -> Actuation:
        n = obs.ego_x.shape[0]
        return Actuation(np.where(obs.ego_speed > 0.0, -3.0, 0.0), np.zeros(n),
                         np.zeros(n, dtype=bool), np.full(n, self.justified))

    def publish(self, sink, tick: int, t_ns: int) -> None:
        pass

    def digest(self) -> dict[str, np.ndarray]:
        return {}


class BrakeAndHold:
    """Brakes at 3 m/s^2 to a stand and holds it, with or without a traffic reason."""

    modules = ("brake",)
    parameters = ()
    channels = ()

    def __init__(self, justified: bool) -> None:
        self.name = f"hold-{justified}"
        self.justified = justified

    def build(self, world, params):
        return _Run(self.justified)


def test_standing_with_the_stacks_traffic_reason_is_no_unexpected_stop():
    sc = scenario_from_dict(ROAD)
    out = {j: rollout_batch(BrakeAndHold(j), sc, seeds=[0]).outcomes[0] for j in (False, True)}
    assert out[False].unexpected_stop and out[False].emergency
    assert not out[True].unexpected_stop and not out[True].emergency
