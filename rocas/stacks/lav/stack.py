"""The LAV-like stack: five modules wired by their channels.

Per 0.05 s step gnss publishes the ego state and the controller a command; every 0.1 s the
joint perception-and-prediction model (pnp), the brake model and the waypoint planner run
first. Written independently of the built-in ADS: its own modules, channels, messages and
parameters (``config.toml``); it shares only the world it drives in.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from rocas.sim.world import COLOR_NAMES, BatchWorld
from rocas.stacks.base import Actuation, ChannelSpec, MessageSink, Observation, ParamSpec
from rocas.stacks.lav.brake import BrakeModel, BrakePrediction
from rocas.stacks.lav.controller import OVERRIDES, Command, Controller
from rocas.stacks.lav.gnss import EgoEstimate, Gnss
from rocas.stacks.lav.msgs import lav_pb2
from rocas.stacks.lav.params import MODULES, parameters
from rocas.stacks.lav.planner import EgoPlan, Planner
from rocas.stacks.lav.pnp import KIND_NAMES, Agents, PerceptionPrediction
from rocas.stacks.lav.replay_io import read_motion
from rocas.stacks.lav.topics import (
    TOPIC_AGENTS,
    TOPIC_BRAKE,
    TOPIC_COMMAND,
    TOPIC_EGO,
    TOPIC_PLAN,
)

PERIOD_S = 0.1

CHANNELS = (
    ChannelSpec(TOPIC_EGO, lav_pb2.EgoState, "gnss", ("pnp", "planner", "controller"), 0.05),
    ChannelSpec(TOPIC_AGENTS, lav_pb2.AgentForecasts, "pnp", ("planner",), PERIOD_S),
    ChannelSpec(TOPIC_BRAKE, lav_pb2.BrakePrediction, "brake", ("controller",), PERIOD_S),
    ChannelSpec(TOPIC_PLAN, lav_pb2.EgoPlan, "planner", ("controller",), PERIOD_S),
    ChannelSpec(TOPIC_COMMAND, lav_pb2.VehicleCommand, "controller", (), 0.05, role="control"),
)


class LavStack:
    """The registered stack ``lav``."""

    name = "lav"
    modules: tuple[str, ...] = MODULES
    channels: tuple[ChannelSpec, ...] = CHANNELS
    catalog = "lav"

    #: a cyber search may not lower these (a "fix" that brakes or senses less hides the accident)
    braking_limits: tuple[str, ...] = ("controller.max_brake_decel_mps2",)
    sensing_limits: tuple[str, ...] = ("pnp.lidar_range_m", "brake.camera_range_m",
                                       "brake.camera_fov_deg", "pnp.forecast_horizon_s")
    #: ... nor raise these (a "fix" that drives faster wins a race)
    pace_limits: tuple[str, ...] = ("planner.max_speed_kmh", "planner.max_lateral_accel_mps2",
                                    "controller.max_throttle_accel_mps2")

    @property
    def parameters(self) -> tuple[ParamSpec, ...]:
        return parameters()

    def read_motion(self, recording: Any) -> tuple[list[Any], list[Any]]:
        """Replay's input from a recording of this stack (:mod:`rocas.stacks.lav.replay_io`)."""
        return read_motion(recording)

    def build(self, world: BatchWorld, params: Mapping[str, np.ndarray]) -> LavRun:
        return LavRun(world, params)


def lav_stack() -> LavStack:
    return LavStack()


class LavRun:
    """The five modules for N variants."""

    def __init__(self, world: BatchWorld, params: Mapping[str, np.ndarray]) -> None:
        self.world = world
        self.period_ticks = max(1, int(round(PERIOD_S / world.dt_s)))
        self.gnss = Gnss(world, params)
        self.pnp = PerceptionPrediction(world, params, self.period_ticks * world.dt_s)
        self.brake_model = BrakeModel(world, params)
        self.planner = Planner(world, params, self.period_ticks * world.dt_s)
        self.controller = Controller(params, world.dt_s, world.batch_size)
        self.ego: EgoEstimate | None = None
        self.agents: Agents | None = None
        self.brake: BrakePrediction | None = None
        self.plan: EgoPlan | None = None
        self.command: Command | None = None
        self.ran_slow = False
        self._seq: dict[str, int] = {}

    def step(self, obs: Observation) -> Actuation:
        ego = self.gnss.step(obs.tick, obs.ego_x, obs.ego_y, obs.ego_yaw, obs.ego_speed,
                             obs.ego_accel)
        self.ego = ego
        self.ran_slow = obs.tick % self.period_ticks == 0 or self.plan is None
        if self.ran_slow:
            self.agents = self.pnp.step(obs.tick, ego.x, ego.y, obs.actor_x, obs.actor_y,
                                        obs.actor_yaw, obs.actor_speed)
            self.brake = self.brake_model.step(obs.t_s, ego.x, ego.y, ego.heading, obs.actor_x,
                                               obs.actor_y, obs.actor_yaw)
            self.plan = self.planner.step(ego, self.agents)
        cmd = self.controller.step(ego, self.plan, self.brake)
        self.command = cmd
        n = obs.ego_x.shape[0]
        return Actuation(cmd.accel, cmd.curvature, np.zeros(n, dtype=bool),
                         self.plan.collide.copy())

    def digest(self) -> dict[str, np.ndarray]:
        e, c = self.ego, self.command
        d = {"gnss": e.x + 0.7 * e.y + e.speed,
             "controller": c.steer + 2.0 * c.throttle + 3.0 * c.brake + c.override}
        if self.ran_slow:
            a, p, b = self.agents, self.plan, self.brake
            d["pnp"] = (np.where(a.seen[..., None], a.forecast.sum(-1), 0.0).sum((1, 2))
                        + a.is_static.sum(1))
            d["brake"] = b.probability + b.brake
            d["planner"] = p.waypoints.sum((1, 2)) + p.target_speed + p.collide + p.collide_in_s
        return d

    # -- recording (variant 0) -------------------------------------------------------------
    def _stamp(self, msg: Any, topic: str, module: str, t_ns: int) -> None:
        seq = self._seq.get(topic, 0)
        self._seq[topic] = seq + 1
        msg.stamp.time_s = t_ns / 1e9
        msg.stamp.seq = seq
        msg.stamp.module = module

    def publish(self, sink: MessageSink, tick: int, t_ns: int) -> None:
        e = self.ego
        m = lav_pb2.EgoState()
        self._stamp(m, TOPIC_EGO, "gnss", t_ns)
        m.position.x, m.position.y = float(e.x[0]), float(e.y[0])
        m.heading_rad, m.speed_mps = float(e.heading[0]), float(e.speed[0])
        m.accel_mps2, m.route_s_m = float(e.accel[0]), float(e.route_s[0])
        sink(TOPIC_EGO, m, t_ns)
        if self.ran_slow:
            sink(TOPIC_AGENTS, self._agents_msg(t_ns), t_ns)
            b = lav_pb2.BrakePrediction()
            self._stamp(b, TOPIC_BRAKE, "brake", t_ns)
            b.probability = float(self.brake.probability[0])
            b.brake = bool(self.brake.brake[0])
            b.features.extend(float(v) for v in self.brake.features[0])
            sink(TOPIC_BRAKE, b, t_ns)
            sink(TOPIC_PLAN, self._plan_msg(t_ns), t_ns)
        c = self.command
        cmd = lav_pb2.VehicleCommand()
        self._stamp(cmd, TOPIC_COMMAND, "controller", t_ns)
        cmd.steer, cmd.throttle = float(c.steer[0]), float(c.throttle[0])
        cmd.brake, cmd.override = float(c.brake[0]), OVERRIDES[int(c.override[0])]
        sink(TOPIC_COMMAND, cmd, t_ns)

    def _agents_msg(self, t_ns: int) -> lav_pb2.AgentForecasts:
        a = self.agents
        msg = lav_pb2.AgentForecasts()
        self._stamp(msg, TOPIC_AGENTS, "pnp", t_ns)
        for j in np.flatnonzero(a.seen[0]):
            g = msg.agents.add()
            g.id = int(j) + 1
            g.kind = KIND_NAMES.get(int(a.kind[0, j]), "static")
            g.position.x, g.position.y = float(a.x[0, j]), float(a.y[0, j])
            g.heading_rad, g.speed_mps = float(a.heading[0, j]), float(a.speed[0, j])
            g.length_m, g.width_m = float(a.length[0, j]), float(a.width[0, j])
            g.height_m, g.is_static = float(a.height[0, j]), bool(a.is_static[0, j])
            g.color = COLOR_NAMES[int(a.color[0, j])] if a.color[0, j] >= 0 else ""
            for k in np.flatnonzero(a.forecast_valid[0]):
                w = g.forecast.add()
                w.t_s = float(a.forecast_t[0, k])
                w.position.x, w.position.y = (float(v) for v in a.forecast[0, j, k])
        return msg

    def _plan_msg(self, t_ns: int) -> lav_pb2.EgoPlan:
        p = self.plan
        msg = lav_pb2.EgoPlan()
        self._stamp(msg, TOPIC_PLAN, "planner", t_ns)
        for k in range(p.waypoints.shape[1]):
            w = msg.waypoints.add()
            w.t_s = float(p.waypoint_t[0, k])
            w.position.x, w.position.y = (float(v) for v in p.waypoints[0, k])
        msg.target_speed_mps = float(p.target_speed[0])
        msg.collide = bool(p.collide[0])
        msg.collide_in_s = float(p.collide_in_s[0])
        msg.collide_agent = int(p.collide_agent[0]) + 1 if p.collide[0] else 0
        return msg
