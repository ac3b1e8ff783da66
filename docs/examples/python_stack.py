"""A complete Python stack for rocas: two modules, its own parameters and channels, registered
and driven by the rollout (docs/own-stack.md). Run it:

    python docs/examples/python_stack.py OUT_DIR

It records one run to OUT_DIR/follow.mcap and checks that a batch of variants equals the
single runs. ``tests/docs/test_python_stack_example.py`` runs it.
"""

from __future__ import annotations

import sys
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from google.protobuf import wrappers_pb2

from rocas.rollout import rollout, rollout_batch, with_stack
from rocas.scenarios import load_example
from rocas.sim.world import project_on_reference, reference_at
from rocas.stacks.base import Actuation, ChannelSpec, Observation, ParamSpec
from rocas.stacks.registry import get_stack, register


class FollowRun:
    """N variants: ``sensing`` finds the nearest actor ahead, ``control`` keeps a cruise speed,
    brakes for that actor inside ``control.gap_m`` and steers toward the route."""

    def __init__(self, world, params: Mapping[str, np.ndarray]) -> None:
        self.road = world.road
        self.range = params["sensing.range_m"]
        self.cruise = params["control.cruise_mps"]
        self.gap = params["control.gap_m"]
        self.ahead = self.accel = np.zeros(world.batch_size)

    def step(self, obs: Observation) -> Actuation:
        dx = obs.actor_x - obs.ego_x[:, None]
        dy = obs.actor_y - obs.ego_y[:, None]
        c, s = np.cos(obs.ego_yaw)[:, None], np.sin(obs.ego_yaw)[:, None]
        lon, lat = dx * c + dy * s, -dx * s + dy * c
        seen = (lon > 0) & (np.abs(lat) < 2.0) & (lon < self.range[:, None])
        self.ahead = np.where(seen, lon, np.inf).min(axis=1, initial=np.inf)  # sensing
        _, s_now, _ = project_on_reference(self.road, obs.ego_x, obs.ego_y)
        tx, ty, _, _ = reference_at(self.road, s_now + 8.0)  # pure pursuit, 8 m ahead
        tdx, tdy = tx - obs.ego_x, ty - obs.ego_y
        lateral = -tdx * np.sin(obs.ego_yaw) + tdy * np.cos(obs.ego_yaw)
        curvature = 2.0 * lateral / np.maximum(tdx * tdx + tdy * tdy, 1.0)
        blocked = self.ahead < self.gap
        self.accel = np.where(blocked, -6.0, np.clip(self.cruise - obs.ego_speed, -3.0, 2.0))
        n = obs.ego_x.shape[0]
        return Actuation(self.accel, curvature, np.zeros(n, dtype=bool), blocked)

    def publish(self, sink, tick: int, t_ns: int) -> None:
        sink("/follow/ahead", wrappers_pb2.DoubleValue(value=float(min(self.ahead[0], 1e9))), t_ns)
        sink("/follow/accel", wrappers_pb2.DoubleValue(value=float(self.accel[0])), t_ns)

    def digest(self) -> dict[str, np.ndarray]:
        return {"sensing": np.minimum(self.ahead, 1e9), "control": self.accel}


class FollowStack:
    name = "follow"
    modules = ("sensing", "control")
    parameters = (
        ParamSpec("sensing", "range_m", 40.0, 5.0, 100.0, "m", "actors farther are not seen"),
        ParamSpec("control", "cruise_mps", 8.0, 0.0, 20.0, "m/s", "speed kept on a free road"),
        ParamSpec("control", "gap_m", 6.0, 1.0, 30.0, "m", "brake for an actor closer than this"),
    )
    channels = (
        ChannelSpec("/follow/ahead", wrappers_pb2.DoubleValue, "sensing", ("control",), 0.05),
        ChannelSpec("/follow/accel", wrappers_pb2.DoubleValue, "control", (), 0.05, "control"),
    )

    def build(self, world, params: Mapping[str, np.ndarray]) -> FollowRun:
        return FollowRun(world, params)


def main(out: Path) -> None:
    register(FollowStack())
    scenario = with_stack(load_example("roundabout_red_truck"), "follow")
    one = rollout(get_stack("follow"), scenario, {"control.gap_m": 10.0}, seed=0,
                  output=out / "follow.mcap")
    print(f"{one.messages} messages, {one.outcome.summary()}")
    sets = [{"control.gap_m": g} for g in (4.0, 10.0, 20.0)]
    batch = rollout_batch(get_stack("follow"), scenario, sets, seeds=[0, 0, 0])
    assert np.array_equal(batch.ego[1], one.ego)  # variant i == its single run
    for p, o in zip(sets, batch.outcomes, strict=True):
        print(p, o.summary())


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "."))
