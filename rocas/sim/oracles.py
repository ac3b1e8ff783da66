"""Oracles: collision, emergency braking, safety margin and route completion, per variant.

Each oracle is updated once per step with batched states and keeps only (N,) summaries, so the
same code serves the recording mode (N = 1) and the batch mode.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rocas.sim.dynamics import VehicleState
from rocas.sim.geometry import box_corners, box_gap, clip, points_in_polygons
from rocas.sim.world import LIGHT_CODES, BatchWorld, light_state, project_on_reference

HARD_BRAKE_MPS2 = 4.0          # [m/s^2] deceleration that counts as emergency braking
STANDSTILL_MPS = 0.1           # [m/s]
UNEXPECTED_STOP_S = 2.0        # [s] standing this long for no traffic reason is an anomaly
MOVED_MPS = 1.0                # [m/s] the ego must have moved before a stop is unexpected
#: [m] standing this close before the stop line of a red or yellow light on the ego's route is
#: waiting at that light (in a queue, behind cars that wait too), whatever the planner's reason
QUEUE_AT_LIGHT_M = 50.0
COLLIDER_ACTOR, COLLIDER_OBJECT, COLLIDER_AREA = 0, 1, 2


@dataclass(frozen=True)
class Outcome:
    """What happened in one run.

    Attributes:
        collided: the ego touched an actor, a map object or an enabled building/vegetation.
        collision_time_s, collision_with, collision_kind ("actor", "object", "area"),
        collision_position: first collision (None when none).
        hard_brake: deceleration beyond 4 m/s^2 before any collision; hard_brake_time_s.
        estop: an estop was raised without a collision having happened; estop_time_s.
        unexpected_stop: the ego stood still >= 2 s after moving, for no traffic reason (the
            stack named none, and it was not queueing at a red or yellow light).
        emergency: hard_brake or estop or unexpected_stop.
        max_decel_mps2: hardest realised deceleration [m/s^2].
        min_separation_m: smallest box-to-box gap to any actor or object over the run [m]
            (negative: penetration), a graded safety constraint.
        route_completion: share of the ego route driven, in [0, 1].
    """

    collided: bool
    collision_time_s: float | None
    collision_with: str | None
    collision_kind: str | None
    collision_position: tuple[float, float] | None
    hard_brake: bool
    hard_brake_time_s: float | None
    estop: bool
    estop_time_s: float | None
    unexpected_stop: bool
    emergency: bool
    max_decel_mps2: float
    min_separation_m: float
    route_completion: float

    def summary(self) -> str:
        """One line for the terminal."""
        if self.collided:
            x, y = self.collision_position or (0.0, 0.0)
            return (f"collision with {self.collision_with} ({self.collision_kind}) at "
                    f"t={self.collision_time_s:.2f} s, x={x:.1f} y={y:.1f}")
        parts = []
        if self.hard_brake:
            parts.append(f"hard brake at t={self.hard_brake_time_s:.2f} s "
                         f"({self.max_decel_mps2:.1f} m/s^2)")
        if self.estop:
            parts.append(f"estop at t={self.estop_time_s:.2f} s")
        if self.unexpected_stop:
            parts.append("unexpected full stop")
        if parts:
            return "emergency: " + ", ".join(parts) + \
                f"; min separation {self.min_separation_m:.2f} m"
        return (f"clean run: route {100 * self.route_completion:.0f} % completed, "
                f"min separation {self.min_separation_m:.2f} m")


class Oracles:
    """Batched oracle state (N variants)."""

    def __init__(self, world: BatchWorld, start_s: np.ndarray) -> None:
        n = world.batch_size
        self.world = world
        self.collided = np.zeros(n, dtype=bool)
        self.collision_tick = np.full(n, -1)
        self.collision_kind = np.full(n, -1)
        self.collision_index = np.full(n, -1)
        self.collision_xy = np.zeros((n, 2))
        self.hard_brake_tick = np.full(n, -1)
        self.estop_tick = np.full(n, -1)
        self.unexpected = np.zeros(n, dtype=bool)
        self.stand_time = np.zeros(n)
        self.moved = np.zeros(n, dtype=bool)
        self.max_decel = np.zeros(n)
        self.min_sep = np.full(n, np.inf)
        self.start_s = start_s
        self.progress = np.zeros(n)
        self.last_gap = np.full(n, np.inf)
        self.half_length = np.concatenate([world.actor_dims[..., 0], world.object_dims[..., 0]], 1) / 2
        self.half_width = np.concatenate([world.actor_dims[..., 1], world.object_dims[..., 1]], 1) / 2

    def update(self, tick: int, ego: VehicleState, accel: np.ndarray, actors: VehicleState,
               estop: np.ndarray, stop_justified: np.ndarray) -> None:
        """Judge step ``tick``: ego and actors after it, the ego's (N,) acceleration
        [m/s^2], and what the stack said: (N,) estop raised, and (N,) ``stop_justified``, its
        plan names a traffic reason to stand still (:class:`rocas.sim.protocol.Actuation`)."""
        w = self.world
        hl, hw = w.ego_dims[0] / 2, w.ego_dims[1] / 2
        ex, ey, eyaw = ego.x[:, None], ego.y[:, None], ego.yaw[:, None]
        na = actors.x.shape[1]
        cat = np.concatenate
        gaps = box_gap(ex, ey, eyaw, hl, hw, cat([actors.x, w.object_pos[..., 0]], 1),
                       cat([actors.y, w.object_pos[..., 1]], 1), cat([actors.yaw, w.object_yaw], 1),
                       self.half_length, self.half_width)
        n = ego.x.shape[0]
        if gaps.shape[1]:
            g = gaps.min(axis=1)
            j = gaps.argmin(axis=1)
        else:
            g = np.full(n, np.inf)
            j = np.zeros(n, dtype=np.int64)
        self.last_gap = g
        self.min_sep = np.minimum(self.min_sep, g)
        hit = g < 0.0
        kind = np.where(j < na, COLLIDER_ACTOR, COLLIDER_OBJECT)
        index = np.where(j < na, j, j - na)
        if w.area_edges.shape[0]:
            corners = box_corners(ego.x, ego.y, ego.yaw, hl, hw)  # (N, 4, 2)
            inside = points_in_polygons(corners[..., 0], corners[..., 1], w.area_edges,
                                        w.area_edge_owner, len(w.area_ids))  # (N, 4, G)
            area_hit = (inside.any(axis=1) & w.area_enabled)
            a_any = area_hit.any(axis=1)
            kind = np.where(hit, kind, np.where(a_any, COLLIDER_AREA, kind))
            index = np.where(hit, index, np.where(a_any, area_hit.argmax(axis=1), index))
            hit = hit | a_any
        first = hit & ~self.collided
        self.collision_tick = np.where(first, tick, self.collision_tick)
        self.collision_kind = np.where(first, kind, self.collision_kind)
        self.collision_index = np.where(first, index, self.collision_index)
        self.collision_xy = np.where(first[:, None], np.stack([ego.x, ego.y], 1),
                                     self.collision_xy)
        self.collided |= hit
        clean = ~self.collided
        self.max_decel = np.where(clean, np.maximum(self.max_decel, -accel), self.max_decel)
        hard = clean & (-accel > HARD_BRAKE_MPS2) & (self.hard_brake_tick < 0)
        self.hard_brake_tick = np.where(hard, tick, self.hard_brake_tick)
        est = clean & estop & (self.estop_tick < 0)
        self.estop_tick = np.where(est, tick, self.estop_tick)
        self.moved |= ego.speed > MOVED_MPS
        standing = (ego.speed < STANDSTILL_MPS) & self.moved & ~stop_justified
        if standing.any() and w.light_ids:
            standing &= ~self._waiting_at_light(tick, ego)
        self.stand_time = np.where(standing, self.stand_time + w.dt_s, 0.0)
        self.unexpected |= clean & (self.stand_time >= UNEXPECTED_STOP_S)

    def _waiting_at_light(self, tick: int, ego: VehicleState) -> np.ndarray:
        """(N,) bool: the ego's front is within QUEUE_AT_LIGHT_M before the stop line of a
        red or yellow light on its route. The planner may give another reason (it stops
        behind the car in front, not at the line), but a queue at a light is traffic."""
        w = self.world
        color = light_state(w, tick * w.dt_s)  # (N, L)
        stopping = (color == LIGHT_CODES["red"]) | (color == LIGHT_CODES["yellow"])
        _, s, _ = project_on_reference(w.road, ego.x, ego.y)
        ahead = w.light_stop_route_s[None, :] - (s + w.ego_dims[0] / 2)[:, None]  # (N, L)
        near = np.isfinite(ahead) & (ahead >= -0.5) & (ahead <= QUEUE_AT_LIGHT_M)
        return (stopping & near).any(axis=1)

    def finish_route(self, ego_xy: np.ndarray) -> None:
        """Route completion from the ego trajectory (N, T, 2): the farthest point reached."""
        w = self.world
        _, s, _ = project_on_reference(w.road, ego_xy[..., 0], ego_xy[..., 1])
        total = max(w.road.destination_s_m - float(w.road.start_s_m), 1e-6)
        self.progress = clip((s.max(axis=1) - self.start_s) / total, 0.0, 1.0)

    def outcomes(self) -> list[Outcome]:
        w = self.world
        dt = w.dt_s
        out = []
        names = {COLLIDER_ACTOR: w.actor_ids, COLLIDER_OBJECT: w.object_ids,
                 COLLIDER_AREA: w.area_ids}
        kinds = {COLLIDER_ACTOR: "actor", COLLIDER_OBJECT: "object", COLLIDER_AREA: "area"}
        for i in range(w.batch_size):
            col = bool(self.collided[i])
            k = int(self.collision_kind[i])
            hb = self.hard_brake_tick[i] >= 0
            es = self.estop_tick[i] >= 0
            un = bool(self.unexpected[i])
            out.append(Outcome(
                collided=col,
                collision_time_s=float(self.collision_tick[i] * dt) if col else None,
                collision_with=names[k][int(self.collision_index[i])] if col else None,
                collision_kind=kinds[k] if col else None,
                collision_position=(float(self.collision_xy[i, 0]), float(self.collision_xy[i, 1]))
                if col else None,
                hard_brake=bool(hb), hard_brake_time_s=float(self.hard_brake_tick[i] * dt)
                if hb else None,
                estop=bool(es), estop_time_s=float(self.estop_tick[i] * dt) if es else None,
                unexpected_stop=un, emergency=bool(hb or es or un),
                max_decel_mps2=float(self.max_decel[i]),
                min_separation_m=float(self.min_sep[i]) if np.isfinite(self.min_sep[i])
                else float("inf"),
                route_completion=float(self.progress[i]),
            ))
        return out
