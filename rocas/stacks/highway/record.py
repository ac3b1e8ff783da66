"""Recording a highway-env run: the driver's seams as protobuf channels with their topology.

Per simulation tick (``1 / frequency_hz``) five messages share one log time: the traffic
(every other vehicle, ground truth), the ego's state, the neighbours the driver considered,
MOBIL's and IDM's decision, and the commands. The recording also carries the scene
(``rocas.highway.scene`` attachment, JSON) so one file is enough to run it again, the stack's
name (``rocas.stack``), the parameter overrides and seed (``rocas.ego``), and the outcome
(``rocas.run``).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from typing import Any

from rocas.recording.writer import RecordingWriter
from rocas.stacks.base import EGO_METADATA, RUN_METADATA, STACK_METADATA, ChannelSpec
from rocas.stacks.highway.driver import DecisionFrame, Neighbour
from rocas.stacks.highway.msgs import highway_pb2 as pb
from rocas.stacks.highway.scene import Scene, lane_text, scene_to_dict
from rocas.stacks.highway.world import RunResult, Simulation, simulate

STACK_NAME = "highway"
SCENE_ATTACHMENT = "rocas.highway.scene"
TOPIC_TRAFFIC = "/highway/world/traffic"
TOPIC_EGO = "/highway/ego/state"
TOPIC_NEIGHBOURS = "/highway/perception/neighbours"
TOPIC_DECISION = "/highway/planning/decision"
TOPIC_COMMAND = "/highway/control/command"


def channels(period_s: float = 1 / 15) -> tuple[ChannelSpec, ...]:
    """The stack's channels and topology (one message per tick on each)."""
    return (
        # ground truth for the view and for replay: the driver reads the road itself, so the
        # traffic is no input edge of the module graph (the walk ends at perception)
        ChannelSpec(TOPIC_TRAFFIC, pb.Traffic, "world", (), period_s),
        ChannelSpec(TOPIC_EGO, pb.EgoState, "vehicle", ("perception", "planning", "control"),
                    period_s),
        ChannelSpec(TOPIC_NEIGHBOURS, pb.Neighbours, "perception", ("planning",), period_s),
        ChannelSpec(TOPIC_DECISION, pb.Decision, "planning", ("control",), period_s),
        ChannelSpec(TOPIC_COMMAND, pb.Command, "control", ("vehicle",), period_s,
                    role="control"),
    )


def _state(msg: Any, v: Any, vid: int, kind: str) -> None:
    msg.id = vid
    msg.x_m, msg.y_m = float(v.position[0]), float(v.position[1])
    msg.heading_rad, msg.speed_mps = float(v.heading), float(v.speed)
    s, lat = v.lane.local_coordinates(v.position)
    msg.lane, msg.lane_s_m, msg.lane_lateral_m = lane_text(v.lane_index), float(s), float(lat)
    msg.length_m, msg.width_m = float(v.LENGTH), float(v.WIDTH)
    msg.crashed, msg.kind = bool(v.crashed), kind


def _neighbour(msg: Any, n: Neighbour) -> None:
    msg.present = n.vid >= 0
    if msg.present:
        msg.id, msg.gap_m, msg.speed_mps = n.vid, n.gap_m, n.speed_mps


class _Publisher:
    """Turns each tick's state and decision into the five messages."""

    def __init__(self, writer: RecordingWriter, scene: Scene) -> None:
        self.writer = writer
        self.kinds = ["ego", *(o.kind for o in scene.others)]
        self.seq: dict[str, int] = {}

    def _stamp(self, msg: Any, topic: str, module: str, t_s: float) -> None:
        seq = self.seq.get(topic, 0)
        self.seq[topic] = seq + 1
        msg.stamp.time_s, msg.stamp.seq, msg.stamp.module = t_s, seq, module

    def __call__(self, tick: int, t_s: float, sim: Simulation, f: DecisionFrame) -> None:
        t_ns = int(round(t_s * 1e9))
        traffic = pb.Traffic()
        self._stamp(traffic, TOPIC_TRAFFIC, "world", t_s)
        for v in sim.others:
            _state(traffic.vehicles.add(), v, v.rocas_id, self.kinds[v.rocas_id])
        ego = pb.EgoState()
        self._stamp(ego, TOPIC_EGO, "vehicle", t_s)
        _state(ego.state, sim.ego, 0, "ego")
        ego.on_road = bool(sim.ego.on_road)
        nb = pb.Neighbours()
        self._stamp(nb, TOPIC_NEIGHBOURS, "perception", t_s)
        nb.lane = lane_text(f.lane)
        for field, n in (("front", f.front), ("rear", f.rear), ("left_front", f.left_front),
                         ("left_rear", f.left_rear), ("right_front", f.right_front),
                         ("right_rear", f.right_rear)):
            _neighbour(getattr(nb, field), n)
        dec = pb.Decision()
        self._stamp(dec, TOPIC_DECISION, "planning", t_s)
        dec.target_lane, dec.lane_change = lane_text(f.target_lane), f.target_lane[2] - f.lane[2]
        dec.idm_accel_mps2, dec.idm_accel_target_mps2 = f.idm_accel_mps2, f.idm_accel_target_mps2
        dec.desired_gap_m, dec.target_speed_mps = f.desired_gap_m, f.target_speed_mps
        cmd = pb.Command()
        self._stamp(cmd, TOPIC_COMMAND, "control", t_s)
        cmd.steering_rad, cmd.acceleration_mps2 = f.steering_rad, f.acceleration_mps2
        for topic, msg in ((TOPIC_TRAFFIC, traffic), (TOPIC_EGO, ego),
                           (TOPIC_NEIGHBOURS, nb), (TOPIC_DECISION, dec), (TOPIC_COMMAND, cmd)):
            self.writer.write(topic, msg, log_time_ns=t_ns)


def outcome_record(run: RunResult) -> dict[str, str]:
    """The ``rocas.run`` metadata of a run."""
    def opt(v: float | None) -> str:
        return "" if v is None else repr(float(v))
    what = ("collision" if run.collided else "off road" if run.off_road else "no accident")
    return {"outcome": what, "collided": str(run.collided).lower(),
            "collision_with": "" if run.collided_with < 0 else str(run.collided_with),
            "collision_time_s": opt(run.collision_t_s), "off_road": str(run.off_road).lower(),
            "off_road_time_s": opt(run.off_road_t_s), "min_ttc_s": repr(run.min_ttc_s),
            "min_separation_m": repr(run.min_margin_m), "digest": run.digest()}


def record(scene: Scene, path: str | os.PathLike[str],
           params: Mapping[str, float] | None = None, seed: int = 0) -> RunResult:
    """Simulate ``scene`` and write it to the MCAP file ``path`` (atomically)."""
    with RecordingWriter(path) as writer:
        for ch in channels(1.0 / scene.frequency_hz):
            writer.add_channel(ch.topic, ch.message_type, writers=[ch.writer],
                               readers=list(ch.readers), role=ch.role,
                               metadata={"rocas.period_s": f"{ch.period_s:g}"})
        writer.add_attachment(SCENE_ATTACHMENT, json.dumps(scene_to_dict(scene)).encode(),
                              media_type="application/json")
        run = simulate(scene, params, seed, observer=_Publisher(writer, scene))
        writer.add_metadata(STACK_METADATA, {"name": STACK_NAME})
        writer.add_metadata(EGO_METADATA, {"scenario": scene.name, "seed": str(seed),
                                           "params": json.dumps(run.params.overrides(),
                                                                sort_keys=True)})
        writer.add_metadata(RUN_METADATA, outcome_record(run))
    return run
