"""Ground-truth substitutes of ADS modules (module substitution, a second opinion on blame).

Because rocas owns the simulator, a module's output can be replaced by what the module is
meant to report, computed from the simulation's true state, in the same message vocabulary:

- **perception**: every obstacle slot (actor m is slot m, map object e is slot A + e) published
  with its true pose, velocity, acceleration, size, class and colour, stable track ids; the
  brake signal is the classifier's own training truth (:func:`classifier.brake_worthy`: a body
  reaching into the ego's corridor close ahead), not a learned guess; the traffic light is the
  true colour of the light that governs the ego's route (its stop line on the route, not yet
  passed). Things perception has no vocabulary for (buildings, vegetation) stay unreported.
- **prediction**: for the obstacles perception published, their true future trajectories from
  the simulation's own actor model (:func:`rocas.sim.actors.step_actors`) rolled forward from
  the true state. Actors that do not react to traffic follow their route and speed profile
  whatever the ego does, so their forecast is exactly what will happen; actors that keep a
  distance (``reactive``) are rolled forward against a ghost ego that keeps its current speed
  and course, the one assumption a forecast cannot avoid. Current states (position, speed,
  class) pass through from perception, as the real module passes them.

Planning has no substitute: there is no ground truth of what a plan should be. An oracle that
searched the true future for a collision-free plan would be another ADS, and its success
would say only that the accident was avoidable.
"""

from __future__ import annotations

import numpy as np

from rocas.sim.actors import ActorState, step_actors
from rocas.sim.dynamics import VehicleState
from rocas.sim.geometry import clip, wrap_angle
from rocas.sim.world import (
    KIND_BOX,
    KIND_CONE,
    KIND_CYCLIST,
    KIND_PEDESTRIAN,
    BatchWorld,
    project_on_reference,
    road_friction,
)
from rocas.stacks.ads import classifier
from rocas.stacks.ads.localization import LocalizationOutput
from rocas.stacks.ads.perception import (
    ST_BOX,
    ST_CAR,
    ST_CONE,
    ST_CYCLIST,
    ST_PEDESTRIAN,
    T_BICYCLE,
    T_PEDESTRIAN,
    T_UNKNOWN_UNMOVABLE,
    T_VEHICLE,
    TL_UNKNOWN,
    ObstacleFrame,
    PerceptionOutput,
    no_lights,
    sim_light_to_tl,
)
from rocas.stacks.ads.prediction import (
    INTENT_STATIONARY,
    INTENT_UNKNOWN,
    MAX_POINTS,
    PredictionOutput,
    perceived_world_state,
)

#: Modules that have a ground-truth substitute, in data-flow order.
SUBSTITUTABLE = ("perception", "prediction")
#: A light stays the ego's until its front is this far past the stop line [m].
LIGHT_PASSED_M = 1.0
#: An obstacle whose true speed stays below this over the forecast horizon is static [m/s].
STILL_SPEED_MPS = 0.05
#: Margin around the region where a reactive actor takes the ego for a leader [m].
GHOST_MARGIN_M = 2.0
#: Reuse a reactive rollout while the ego cannot have influenced it (off: roll every step).
REUSE_ROLLOUTS = True


class PerfectPerception:
    """Publishes the true obstacles, brake signal and traffic light (see the module doc)."""

    def __init__(self, world: BatchWorld, params: dict[str, np.ndarray]) -> None:
        self.world = world
        self.brake_threshold = params["perception.brake_threshold"]
        n, a = world.actor_kind.shape
        self.velocity: tuple[np.ndarray, np.ndarray] | None = None
        self.accel = (np.zeros((n, a)), np.zeros((n, a)))

    def observe(self, actors: VehicleState) -> None:
        """Called every simulation step: the true accelerations are the change of the true
        velocity over the last step."""
        vx = actors.speed * np.cos(actors.course)
        vy = actors.speed * np.sin(actors.course)
        if self.velocity is not None:
            dt = self.world.dt_s
            self.accel = ((vx - self.velocity[0]) / dt, (vy - self.velocity[1]) / dt)
        self.velocity = (vx, vy)

    def step(self, t: float, ego: VehicleState, actors: VehicleState, gt: ObstacleFrame,
             light_colors: np.ndarray, loc: LocalizationOutput) -> PerceptionOutput:
        n, m = gt.x.shape
        na = actors.x.shape[1]
        zeros_obj = np.zeros((n, m - na))
        vx = np.concatenate([self.velocity[0], zeros_obj], 1)
        vy = np.concatenate([self.velocity[1], zeros_obj], 1)
        ax = np.concatenate([self.accel[0], zeros_obj], 1)
        ay = np.concatenate([self.accel[1], zeros_obj], 1)
        # the ego frame of the localization estimate, as the real module publishes
        lc, ls = np.cos(loc.heading)[:, None], np.sin(loc.heading)[:, None]
        dx, dy = gt.x - loc.x[:, None], gt.y - loc.y[:, None]
        static_obj = (gt.kind == KIND_CONE) | (gt.kind == KIND_BOX)
        is_ped = gt.kind == KIND_PEDESTRIAN
        is_bike = gt.kind == KIND_CYCLIST
        typ = np.where(static_obj, T_UNKNOWN_UNMOVABLE, np.where(
            is_ped, T_PEDESTRIAN, np.where(is_bike, T_BICYCLE, T_VEHICLE)))
        sub = np.where(gt.kind == KIND_CONE, ST_CONE, np.where(
            gt.kind == KIND_BOX, ST_BOX, np.where(is_ped, ST_PEDESTRIAN, np.where(
                is_bike, ST_CYCLIST, clip(gt.model, 0, 3) + ST_CAR))))
        # brake signal: the classifier's training truth in the true ego frame
        ce, se = np.cos(ego.yaw)[:, None], np.sin(ego.yaw)[:, None]
        ex, ey = gt.x - ego.x[:, None], gt.y - ego.y[:, None]
        brake = classifier.brake_worthy(ex * ce + ey * se, -ex * se + ey * ce, gt.length,
                                        gt.width, gt.yaw - ego.yaw[:, None]).any(axis=1)
        return PerceptionOutput(
            published=np.ones((n, m), dtype=bool),
            track_id=np.broadcast_to(np.arange(1, m + 1), (n, m)).copy(),
            type=typ, sub_type=sub, color=gt.color.copy(),
            x=dx * lc + dy * ls, y=-dx * ls + dy * lc,
            theta=wrap_angle(gt.yaw - loc.heading[:, None]),
            vx=vx * lc + vy * ls, vy=-vx * ls + vy * lc,
            ax=ax * lc + ay * ls, ay=-ax * ls + ay * lc,
            length=gt.length, width=gt.width, height=gt.height,
            confidence=np.ones((n, m)), tracking_time=np.full((n, m), t),
            ego_x=loc.x, ego_y=loc.y, ego_heading=loc.heading,
            brake_probability=brake.astype(np.float64), brake_threshold=self.brake_threshold,
            brake=brake, **self._lights(ego, light_colors),
        )

    def _lights(self, ego: VehicleState, colors: np.ndarray) -> dict[str, np.ndarray]:
        """The light governing the ego: its stop line on the ego route, the nearest one the
        ego's front has not passed by more than LIGHT_PASSED_M."""
        w = self.world
        n, nl = colors.shape
        if nl == 0:
            return no_lights(n)
        _, s, _ = project_on_reference(w.road, ego.x, ego.y)
        ahead = w.light_stop_route_s[None, :] - (s + w.ego_dims[0] / 2)[:, None]  # (N, L)
        governs = np.isfinite(ahead) & (ahead > -LIGHT_PASSED_M)
        selected = np.where(governs.any(axis=1),
                            np.argmin(np.where(governs, ahead, np.inf), axis=1), -1)
        detected = governs & (np.arange(nl)[None, :] == selected[:, None])
        true_color = sim_light_to_tl(colors)
        sx = w.light_stop_xy[:, 0] - ego.x[:, None]
        sy = w.light_stop_xy[:, 1] - ego.y[:, None]
        return {"tl_detected": detected,
                "tl_color": np.where(detected, true_color, TL_UNKNOWN),
                "tl_confidence": detected.astype(np.float64),
                "tl_distance": np.hypot(sx, sy), "tl_selected": selected}


class PerfectPrediction:
    """Forecasts the perceived obstacles with their true futures (see the module doc)."""

    def __init__(self, world: BatchWorld, params: dict[str, np.ndarray]) -> None:
        self.world = world
        self.horizon = params["prediction.horizon_s"]
        self.time_step = params["prediction.time_step_s"]
        self.probability = params["prediction.trajectory_probability"]
        self.friction = road_friction(world.weather[:, 1])
        k = np.arange(1, MAX_POINTS + 1)
        self.t = k[None, :] * self.time_step[:, None]  # (N, K) as the real module's grid
        self.valid = self.t <= self.horizon[:, None] + 1e-9
        last = float(np.where(self.valid, self.t, 0.0).max())
        #: simulation steps a forecast spans (the rollout window holds steps + 1 samples)
        self.steps = max(1, int(np.ceil(last / world.dt_s - 1e-9)))
        # (N, steps + 1) samples within each variant's horizon (for the static test)
        self.in_horizon = (np.arange(self.steps + 1)[None, :] * world.dt_s
                           <= self.horizon[:, None] + 1e-9)
        self.reactive = bool(world.actor_reactive.any())
        self._tick0 = 0
        self._states: list[ActorState] = []    # the rollout: state k is at step _tick0 + k
        self._touched: list[bool] = []         # step k's ghost was near a reactive actor

    def _ghost(self, ego: VehicleState, steps_ahead: int) -> VehicleState:
        """The ego ``steps_ahead`` steps on, had it kept its speed and course."""
        d = ego.speed * (steps_ahead * self.world.dt_s)
        return VehicleState(ego.x + d * np.cos(ego.course), ego.y + d * np.sin(ego.course),
                            ego.yaw, ego.course, ego.speed)

    def _near(self, state: ActorState, ghost: VehicleState) -> bool:
        """Whether the ghost ego is anywhere a reactive actor could take it for a leader
        (a region wider than :func:`step_actors` looks at, by GHOST_MARGIN_M)."""
        w = self.world
        b = state.body
        dx, dy = ghost.x[:, None] - b.x, ghost.y[:, None] - b.y
        c, s = np.cos(b.yaw), np.sin(b.yaw)
        lon, lat = dx * c + dy * s, -dx * s + dy * c
        reach = (w.actor_dims[..., 1] + w.ego_dims[1]) / 2 + GHOST_MARGIN_M
        return bool((w.actor_reactive & (lon > -GHOST_MARGIN_M) & (np.abs(lat) < reach)).any())

    def _extend(self, tick0: int, ego: VehicleState, ghost_from: int, count: int) -> None:
        """Step the cached rollout ``count`` more steps, the ghost counted from ``ghost_from``
        (the cache index where ``ego`` was taken)."""
        w = self.world
        for _ in range(count):
            k = len(self._states) - 1
            state = self._states[-1]
            ghost = self._ghost(ego, k - ghost_from)
            self._touched.append(self._near(state, ghost))
            self._states.append(step_actors(w, state, (tick0 + k) * w.dt_s, ghost,
                                            self.friction))

    @staticmethod
    def _same(a: ActorState, b: ActorState) -> bool:
        return all(np.array_equal(getattr(x, f), getattr(y, f))
                   for x, y in ((a.body, b.body), (a.guide, b.guide))
                   for f in ("x", "y", "yaw", "course", "speed")) and (
            np.array_equal(a.s, b.s) and np.array_equal(a.index, b.index))

    def _reactive_future(self, tick: int, actors: ActorState, ego: VehicleState
                         ) -> list[ActorState]:
        """States (steps + 1 of them) from this step, the ego a ghost that keeps its speed
        and course. The rollout of an earlier step is reused when the actors are where it put
        them and no ghost (its own or this step's) ever came near a reactive actor in the
        window: then no step of it depended on the ego, and a fresh rollout would give the
        same bits."""
        j = tick - self._tick0
        if REUSE_ROLLOUTS and self._states and 0 <= j < len(self._states) and self._same(
                self._states[j], actors):
            self._extend(self._tick0, ego, j, j + self.steps + 1 - len(self._states))
            window = range(j, j + self.steps)
            if not any(self._touched[k] or self._near(self._states[k], self._ghost(ego, k - j))
                       for k in window):
                return self._states[j:j + self.steps + 1]
        self._tick0, self._states, self._touched = tick, [actors], []
        self._extend(tick, ego, 0, self.steps)
        return self._states

    def _rollout(self, start: ActorState, tick: int, ego: VehicleState, steps: int
                 ) -> list[ActorState]:
        """States (steps + 1) from ``start`` at step ``tick``, the ego a ghost."""
        self._tick0, self._states, self._touched = tick, [start], []
        self._extend(tick, ego, 0, steps)
        return self._states

    def _future(self, tick: int, actors: ActorState, ego: VehicleState
                ) -> tuple[np.ndarray, ...]:
        """True actor bodies over the forecast window (N, A, steps + 1) x, y, yaw, speed.

        Actors that do not react to traffic move the same whatever the ego does, so one
        rollout from the first step serves the whole run (the sim steps them with the same
        operations on the same values: their forecast is bit-identical to what happens);
        with reactive actors in the batch, the rollout starts from the current state
        (:meth:`_reactive_future`)."""
        if self.reactive:
            states = self._reactive_future(tick, actors, ego)
        else:
            if not self._states:
                self._rollout(actors, tick, ego, self.world.num_ticks - tick + self.steps)
            j = tick - self._tick0
            states = self._states[j:j + self.steps + 1]
        return tuple(np.stack([getattr(st.body, f) for st in states], axis=-1)
                     for f in ("x", "y", "yaw", "speed"))

    def step(self, tick: int, per: PerceptionOutput, actors: ActorState, ego: VehicleState
             ) -> PredictionOutput:
        w = self.world
        n, m = per.x.shape
        na = actors.body.x.shape[1]
        x, y, vx, vy, _, _, heading, speed = perceived_world_state(per)
        fx, fy, fyaw, fv = self._future(tick, actors, ego)
        # sample the rollout at the forecast times (linear between simulation steps)
        f = clip(self.t / w.dt_s, 0.0, float(self.steps))  # (N, K)
        i = np.minimum(f.astype(np.int64), self.steps - 1)
        u = f - i
        rn = np.arange(n)[:, None, None]
        ra = np.arange(na)[None, :, None]
        ii, uu = i[:, None, :], u[:, None, :]

        def at(a: np.ndarray) -> np.ndarray:
            return a[rn, ra, ii] + uu * (a[rn, ra, ii + 1] - a[rn, ra, ii])

        moving = np.where(self.in_horizon[:, None, :], fv, 0.0).max(-1) >= STILL_SPEED_MPS
        kk = self.t.shape[1]
        traj_x = np.repeat(x[..., None], kk, axis=-1)
        traj_y = np.repeat(y[..., None], kk, axis=-1)
        traj_h = np.repeat(heading[..., None], kk, axis=-1)
        traj_v = np.zeros((n, m, kk))
        is_static = np.ones((n, m), dtype=bool)
        if na:
            is_static[:, :na] = ~moving
            mv = moving[..., None]
            traj_x[:, :na] = np.where(mv, at(fx), traj_x[:, :na])
            traj_y[:, :na] = np.where(mv, at(fy), traj_y[:, :na])
            traj_h[:, :na] = np.where(mv, wrap_angle(fyaw[rn, ra, ii]), traj_h[:, :na])
            traj_v[:, :na] = np.where(mv, at(fv), 0.0)
        return PredictionOutput(
            published=per.published, x=x, y=y, heading=heading, vx=vx, vy=vy, speed=speed,
            length=per.length, width=per.width, type=per.type, track_id=per.track_id,
            is_static=is_static, intent=np.where(is_static, INTENT_STATIONARY, INTENT_UNKNOWN),
            traj_x=traj_x, traj_y=traj_y, traj_heading=traj_h, traj_v=traj_v,
            traj_t=self.t, traj_valid=self.valid, probability=self.probability,
            horizon=self.horizon, perception=per,
        )
