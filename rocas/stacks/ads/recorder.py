"""The built-in ADS's messages: each module's output of one variant (variant 0 unless told) as
its channel's protobuf.

:class:`AdsPublisher` turns one step's :class:`rocas.stacks.ads.stack.TickOutputs` into messages
(headers with module name and per-topic sequence numbers) and hands them to a message sink: in
recording mode the engine's :class:`rocas.sim.recorder.RunRecorder`, which writes the topology,
the world attachment and the run's metadata around them.
"""

from __future__ import annotations

import math

import numpy as np

from rocas.msgs import (
    chassis_pb2,
    control_pb2,
    localization_pb2,
    perception_pb2,
    planning_pb2,
    prediction_pb2,
)
from rocas.sim.protocol import MessageSink
from rocas.sim.world import COLOR_NAMES, BatchWorld
from rocas.stacks.ads.planning import REASONS
from rocas.stacks.ads.stack import TickOutputs
from rocas.stacks.ads.topics import (
    CANBUS,
    CONTROL,
    LOCALIZATION,
    PERCEPTION,
    PLANNING,
    PREDICTION,
    TOPIC_BRAKE_SIGNAL,
    TOPIC_CHASSIS,
    TOPIC_CONTROL,
    TOPIC_OBSTACLES,
    TOPIC_PLANNING,
    TOPIC_POSE,
    TOPIC_PREDICTION,
    TOPIC_TRAFFIC_LIGHT,
)

_NS = 1_000_000_000


class AdsPublisher:
    """Publishes one variant (``variant``, a row of the batch) of the ADS's step outputs, with
    per-topic sequence numbers."""

    def __init__(self, world: BatchWorld, variant: int = 0) -> None:
        self._variant = variant
        self._seq: dict[str, int] = {}
        self._lane_ids = world.road.lane_ids
        self._light_ids = world.light_ids
        self._sink: MessageSink | None = None

    # -- publishing -----------------------------------------------------------------------
    def _header(self, msg: object, module: str, topic: str, t: float, frame: int) -> None:
        seq = self._seq.get(topic, 0)
        self._seq[topic] = seq + 1
        h = msg.header  # type: ignore[attr-defined]
        h.timestamp_sec = t
        h.module_name = module
        h.sequence_num = seq
        h.frame_id = frame

    def _write(self, topic: str, msg: object, t_ns: int) -> None:
        assert self._sink is not None
        self._sink(topic, msg, t_ns)

    def publish(self, sink: MessageSink, tick: int, t_ns: int, out: TickOutputs) -> None:
        """Write step ``tick``'s messages (log time ``t_ns`` [ns]) to ``sink``."""
        row = self._variant
        self._sink = sink
        t = t_ns / _NS
        loc = out.localization
        m = localization_pb2.LocalizationEstimate()
        self._header(m, LOCALIZATION, TOPIC_POSE, t, tick)
        pose = m.pose
        pose.position.x, pose.position.y = float(loc.x[row]), float(loc.y[row])
        pose.heading = float(loc.heading[row])
        pose.linear_velocity.x, pose.linear_velocity.y = float(loc.vx[row]), float(loc.vy[row])
        pose.linear_acceleration.x = float(loc.ax[row])
        pose.linear_acceleration.y = float(loc.ay[row])
        pose.angular_velocity = float(loc.yaw_rate[row])
        lane = int(loc.lane[row])
        m.lane_id = self._lane_ids[lane] if lane >= 0 else ""
        m.lane_s = float(loc.lane_s[row])
        self._write(TOPIC_POSE, m, t_ns)

        ch = out.chassis
        c = chassis_pb2.Chassis()
        self._header(c, CANBUS, TOPIC_CHASSIS, t, tick)
        c.engine_started = True
        c.speed_mps = float(ch.speed[row])
        c.odometer_m = float(ch.odometer[row])
        c.throttle_percentage = float(ch.throttle[row])
        c.brake_percentage = float(ch.brake[row])
        c.steering_percentage = float(ch.steering[row])
        c.gear_location = chassis_pb2.Chassis.GEAR_DRIVE
        c.driving_mode = (chassis_pb2.Chassis.EMERGENCY_MODE if bool(ch.emergency[row])
                          else chassis_pb2.Chassis.COMPLETE_AUTO_DRIVE)
        self._write(TOPIC_CHASSIS, c, t_ns)

        if out.perception is not None:
            obstacles = self._perception(tick, t, t_ns, out)
            self._prediction(tick, t, t_ns, out, obstacles)
            self._planning(tick, t, t_ns, out)

        ctl = out.control
        cc = control_pb2.ControlCommand()
        self._header(cc, CONTROL, TOPIC_CONTROL, t, tick)
        cc.throttle = float(ctl.throttle[row])
        cc.brake = float(ctl.brake[row])
        cc.steering_target = float(ctl.steering_target[row])
        cc.steering_rate = float(ctl.steering_rate[row])
        cc.acceleration = float(ctl.acceleration[row])
        cc.estop = bool(ctl.estop[row])
        cc.lateral_error = float(ctl.lateral_error[row])
        cc.heading_error = float(ctl.heading_error[row])
        cc.station_error = float(ctl.station_error[row])
        cc.speed_error = float(ctl.speed_error[row])
        self._write(TOPIC_CONTROL, cc, t_ns)

    def _perception(self, tick: int, t: float, t_ns: int, out: TickOutputs
                    ) -> dict[int, perception_pb2.PerceptionObstacle]:
        row = self._variant
        per = out.perception
        assert per is not None
        msg = perception_pb2.PerceptionObstacles()
        self._header(msg, PERCEPTION, TOPIC_OBSTACLES, t, tick)
        msg.ego_position.x = float(per.ego_x[row])
        msg.ego_position.y = float(per.ego_y[row])
        msg.ego_heading = float(per.ego_heading[row])
        slots = np.flatnonzero(per.published[row])
        built: dict[int, perception_pb2.PerceptionObstacle] = {}
        if len(slots):
            cols = {f: getattr(per, f)[row, slots].tolist() for f in (
                "track_id", "type", "sub_type", "color", "x", "y", "theta", "vx", "vy", "ax", "ay",
                "length", "width", "height", "confidence", "tracking_time")}
            for k, slot in enumerate(slots.tolist()):
                o = msg.perception_obstacle.add()
                o.id = int(cols["track_id"][k])
                o.type = int(cols["type"][k])
                o.sub_type = int(cols["sub_type"][k])
                color = int(cols["color"][k])
                o.color = COLOR_NAMES[color] if color >= 0 else "unknown"
                x, y, th = cols["x"][k], cols["y"][k], cols["theta"][k]
                o.position.x, o.position.y = x, y
                o.theta = th
                o.velocity.x, o.velocity.y = cols["vx"][k], cols["vy"][k]
                o.acceleration.x, o.acceleration.y = cols["ax"][k], cols["ay"][k]
                ln, wd = cols["length"][k], cols["width"][k]
                o.length, o.width, o.height = ln, wd, cols["height"][k]
                cth, sth = math.cos(th), math.sin(th)
                for sx, sy in ((1, 1), (1, -1), (-1, -1), (-1, 1)):
                    px, py = sx * ln / 2, sy * wd / 2
                    pt = o.polygon_point.add()
                    pt.x, pt.y = x + px * cth - py * sth, y + px * sth + py * cth
                o.confidence = cols["confidence"][k]
                o.tracking_time = cols["tracking_time"][k]
                built[slot] = o
        self._write(TOPIC_OBSTACLES, msg, t_ns)

        tl = perception_pb2.TrafficLightDetection()
        self._header(tl, PERCEPTION, TOPIC_TRAFFIC_LIGHT, t, tick)
        det = per.tl_detected[row]
        for i in np.flatnonzero(det).tolist():
            light = tl.traffic_light.add()
            light.id = self._light_ids[i]
            light.color = int(per.tl_color[row, i])
            light.confidence = float(per.tl_confidence[row, i])
            light.distance_m = float(per.tl_distance[row, i])
        sel = int(per.tl_selected[row])
        tl.selected_light_id = self._light_ids[sel] if sel >= 0 else ""
        tl.contain_lights = bool(det.any())
        self._write(TOPIC_TRAFFIC_LIGHT, tl, t_ns)

        b = perception_pb2.BrakeSignal()
        self._header(b, PERCEPTION, TOPIC_BRAKE_SIGNAL, t, tick)
        b.brake_probability = float(per.brake_probability[row])
        b.brake_threshold = float(per.brake_threshold[row])
        b.brake = bool(per.brake[row])
        self._write(TOPIC_BRAKE_SIGNAL, b, t_ns)
        return built

    def _prediction(self, tick: int, t: float, t_ns: int, out: TickOutputs,
                    obstacles: dict[int, perception_pb2.PerceptionObstacle]) -> None:
        row = self._variant
        pred = out.prediction
        assert pred is not None
        msg = prediction_pb2.PredictionObstacles()
        self._header(msg, PREDICTION, TOPIC_PREDICTION, t, tick)
        horizon = float(pred.horizon[row])
        msg.start_timestamp = t
        msg.end_timestamp = t + horizon
        valid = pred.traj_valid[row]
        times = pred.traj_t[row, valid].tolist()
        prob = float(pred.probability[row])
        for slot, obstacle in obstacles.items():
            po = msg.prediction_obstacle.add()
            po.perception_obstacle.CopyFrom(obstacle)
            po.timestamp = t
            po.predicted_period = horizon
            static = bool(pred.is_static[row, slot])
            po.is_static = static
            po.intent = int(pred.intent[row, slot])
            if static:
                continue
            tr = po.trajectory.add()
            tr.probability = prob
            xs = pred.traj_x[row, slot, valid].tolist()
            ys = pred.traj_y[row, slot, valid].tolist()
            hs = pred.traj_heading[row, slot, valid].tolist()
            vs = pred.traj_v[row, slot, valid].tolist()
            for x, y, h, v, tt in zip(xs, ys, hs, vs, times, strict=True):
                pt = tr.trajectory_point.add()
                pt.position.x, pt.position.y = x, y
                pt.theta, pt.v, pt.relative_time = h, v, tt
        self._write(TOPIC_PREDICTION, msg, t_ns)

    def _planning(self, tick: int, t: float, t_ns: int, out: TickOutputs) -> None:
        row = self._variant
        plan = out.planning
        per = out.perception
        assert plan is not None and per is not None
        msg = planning_pb2.ADCTrajectory()
        self._header(msg, PLANNING, TOPIC_PLANNING, t, tick)
        valid = plan.valid[row]
        cols = [getattr(plan, f)[row, valid].tolist() for f in ("x", "y", "theta", "kappa", "s",
                                                                "v", "a", "t")]
        s0 = cols[4][0]
        for x, y, th, kp, s, v, a, tt in zip(*cols, strict=True):
            pt = msg.trajectory_point.add()
            pt.x, pt.y, pt.theta, pt.kappa = x, y, th, kp
            pt.s, pt.v, pt.a, pt.relative_time = s - s0, v, a, tt
        msg.total_path_length = cols[4][-1] - s0
        msg.total_path_time = cols[7][-1]
        md = msg.main_decision
        md.type = int(plan.main[row])
        md.stop_distance = float(plan.stop_distance[row])
        md.reason = REASONS[int(plan.reason[row])]
        tracks = per.track_id[row]
        for slot in np.flatnonzero(plan.decision[row]).tolist():
            d = msg.object_decision.add()
            d.id = str(int(tracks[slot]))
            d.type = int(plan.decision[row, slot])
            d.distance_s = float(plan.decision_s[row, slot])
            if d.type == planning_pb2.ObjectDecision.NUDGE:
                d.lateral_offset = float(plan.nudge_offset[row])
        msg.estop = bool(plan.estop[row])
        msg.estop_reason = int(plan.estop_reason[row])
        lane = int(plan.lane[row])
        msg.lane_id = self._lane_ids[lane] if lane >= 0 else ""
        msg.cruise_speed = float(plan.cruise_speed[row])
        self._write(TOPIC_PLANNING, msg, t_ns)

