"""Prediction: forecast trajectories per perceived obstacle (world frame).

Intents: STATIONARY (slower than the still-obstacle threshold, unmovable, too far: no
forecast), LANE_FOLLOW (along the matched lane and its successors), CONSTANT_VELOCITY, and
CUT_IN for a cyclist close beside the ego (predicted to cross the ego's path).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rocas import numerics
from rocas.sim.geometry import clip, nearest_on, wrap_angle
from rocas.sim.world import BatchWorld
from rocas.stacks.ads.localization import LocalizationOutput
from rocas.stacks.ads.perception import (
    T_BICYCLE,
    T_PEDESTRIAN,
    T_UNKNOWN_UNMOVABLE,
    PerceptionOutput,
)

#: Cyclists are matched to a lane this much farther from its centre than vehicles [m].
CYCLIST_EXTRA_LANE_DISTANCE_M = 1.0
#: Largest number of forecast points (8 s horizon at 0.5 s).
MAX_POINTS = 16
INTENT_UNKNOWN, INTENT_LANE_FOLLOW, INTENT_CONSTANT_VELOCITY, INTENT_CUT_IN, INTENT_STATIONARY = (
    0, 1, 2, 3, 4)


@dataclass(frozen=True, eq=False)
class PredictionOutput:
    """Forecasts, world frame. Obstacle fields (N, M); trajectories (N, M, K).

    Attributes:
        published: (N, M) bool (mirrors perception).
        x, y [m], heading [rad] (perceived), vx, vy [m/s], speed [m/s]: current state, world.
        length, width [m]; type (proto Type); track_id.
        is_static: (N, M) bool; intent: (N, M) code.
        traj_x, traj_y [m], traj_heading [rad] (path tangent), traj_v [m/s]: (N, M, K).
        traj_t: (N, K) relative times [s]; traj_valid: (N, K) bool (within the horizon).
        probability: (N,) probability published with each forecast; horizon: (N,) [s].
        perception: the perception output the forecast was made from.
    """

    published: np.ndarray
    x: np.ndarray
    y: np.ndarray
    heading: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    speed: np.ndarray
    length: np.ndarray
    width: np.ndarray
    type: np.ndarray
    track_id: np.ndarray
    is_static: np.ndarray
    intent: np.ndarray
    traj_x: np.ndarray
    traj_y: np.ndarray
    traj_heading: np.ndarray
    traj_v: np.ndarray
    traj_t: np.ndarray
    traj_valid: np.ndarray
    probability: np.ndarray
    horizon: np.ndarray
    perception: PerceptionOutput


def perceived_world_state(per: PerceptionOutput) -> tuple[np.ndarray, ...]:
    """Perceived obstacles in the world frame, each (N, M): x, y [m], vx, vy [m/s], ax, ay
    [m/s^2], heading [rad], speed [m/s]."""
    c, s = np.cos(per.ego_heading)[:, None], np.sin(per.ego_heading)[:, None]
    x = per.ego_x[:, None] + per.x * c - per.y * s
    y = per.ego_y[:, None] + per.x * s + per.y * c
    vx = per.vx * c - per.vy * s
    vy = per.vx * s + per.vy * c
    ax = per.ax * c - per.ay * s
    ay = per.ax * s + per.ay * c
    heading = wrap_angle(per.theta + per.ego_heading[:, None])
    return x, y, vx, vy, ax, ay, heading, np.hypot(vx, vy)


class Prediction:
    def __init__(self, world: BatchWorld, params: dict[str, np.ndarray]) -> None:
        self.world = world
        self.p = p = {k.split(".", 1)[1]: v for k, v in params.items()
                      if k.startswith("prediction.")}
        # the forecast's time grid (N, K) and its fading factors (N, 1, K): fixed for a run
        self.t = np.arange(1, MAX_POINTS + 1)[None, :] * p["time_step_s"][:, None]
        self.valid = self.t <= p["horizon_s"][:, None] + 1e-9
        tt = self.t[:, None, :]
        self.accel_tau = p["accel_decay_s"][:, None, None]
        self.accel_fade = 1.0 - numerics.exp(-tt / self.accel_tau)
        self.lane_fade = numerics.exp(-tt / p["lane_follow_convergence_s"][:, None, None])

    def step(self, per: PerceptionOutput, loc: LocalizationOutput) -> PredictionOutput:
        p = self.p
        road = self.world.road
        n, m = per.x.shape
        x, y, vx, vy, ax, ay, heading, speed = perceived_world_state(per)
        # relative to the ego now (localization)
        lc, ls = np.cos(loc.heading)[:, None], np.sin(loc.heading)[:, None]
        ex, ey = x - loc.x[:, None], y - loc.y[:, None]
        rel_x = ex * lc + ey * ls
        rel_y = -ex * ls + ey * lc
        ped = per.type == T_PEDESTRIAN
        still = np.where(ped, p["pedestrian_still_speed_mps"][:, None],
                         p["still_obstacle_speed_mps"][:, None])
        is_static = ((speed < still) | (per.type == T_UNKNOWN_UNMOVABLE)
                     | (np.hypot(rel_x, rel_y) > p["max_distance_m"][:, None])
                     | (rel_x < -p["behind_ignore_m"][:, None]))
        # time grid
        t, valid = self.t, self.valid  # (N, K)
        dir_ = np.where(speed > 0.05, numerics.arctan2(vy, vx), heading)
        # lane matching and intents, for every slot
        q, d2 = nearest_on(road.lane_grid, x, y)
        q = np.minimum(q, road.lane_points.shape[0] - 1)
        lane_h = road.lane_point_heading[q]
        dh = np.abs(wrap_angle(dir_ - lane_h))
        bike = per.type == T_BICYCLE
        on_lane = ((np.sqrt(d2) <= p["lane_follow_max_distance_m"][:, None]
                    + np.where(bike, CYCLIST_EXTRA_LANE_DISTANCE_M, 0.0))
                   & (dh <= np.deg2rad(p["lane_follow_max_heading_deg"])[:, None])
                   & (per.tracking_time >= p["min_tracking_time_s"][:, None])
                   & ~ped)
        # cyclist cut-in beside the ego: moves across the ego's path
        cut_in = (bike & (np.abs(rel_x) <= p["cyclist_cut_in_longitudinal_m"][:, None])
                  & (np.abs(rel_y) <= p["cyclist_cut_in_lateral_m"][:, None]) & ~is_static)
        intent = np.where(is_static, INTENT_STATIONARY, np.where(
            cut_in, INTENT_CUT_IN, np.where(on_lane, INTENT_LANE_FOLLOW,
                                            INTENT_CONSTANT_VELOCITY)))
        # trajectories: static obstacles stay put; only slots moving in some variant are
        # forecast (the others' values would be discarded)
        kk = t.shape[1]
        traj_x = np.repeat(x[..., None], kk, axis=-1)
        traj_y = np.repeat(y[..., None], kk, axis=-1)
        traj_h = np.repeat(heading[..., None], kk, axis=-1)
        traj_v = np.zeros((n, m, kk))
        cols = np.flatnonzero((per.published & ~is_static).any(axis=0))
        if cols.size:
            sub = (slice(None), cols)
            tx, ty, th, tv = self._forecast(
                p, t, x[sub], y[sub], vx[sub], vy[sub], ax[sub], ay[sub], speed[sub],
                dir_[sub], ped[sub], bike[sub], q[sub], lane_h[sub], rel_y[sub], lc, ls,
                intent[sub])
            st = is_static[sub][..., None]
            traj_x[sub] = np.where(st, traj_x[sub], tx)
            traj_y[sub] = np.where(st, traj_y[sub], ty)
            traj_h[sub] = np.where(st, traj_h[sub], th)
            traj_v[sub] = np.where(st, 0.0, tv)
        return PredictionOutput(
            published=per.published, x=x, y=y, heading=heading, vx=vx, vy=vy, speed=speed,
            length=per.length, width=per.width, type=per.type, track_id=per.track_id,
            is_static=is_static, intent=intent,
            traj_x=traj_x, traj_y=traj_y, traj_heading=traj_h, traj_v=traj_v,
            traj_t=t, traj_valid=valid, probability=p["trajectory_probability"],
            horizon=p["horizon_s"], perception=per,
        )

    def _forecast(self, p: dict[str, np.ndarray], t: np.ndarray, x: np.ndarray, y: np.ndarray,
                  vx: np.ndarray, vy: np.ndarray, ax: np.ndarray, ay: np.ndarray,
                  speed: np.ndarray, dir_: np.ndarray, ped: np.ndarray, bike: np.ndarray,
                  q: np.ndarray, lane_h: np.ndarray, rel_y: np.ndarray, lc: np.ndarray,
                  ls: np.ndarray, intent: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Trajectories (N, S, K) x, y, heading, speed for S obstacle slots."""
        # longitudinal motion with a fading acceleration
        along = np.where(speed > 0.05, (ax * vx + ay * vy) / np.maximum(speed, 1e-6), 0.0)
        acc = clip(along, -p["max_accel_mps2"][:, None], p["max_accel_mps2"][:, None])
        tt = t[:, None, :]
        vmax = np.where(ped, p["pedestrian_max_speed_mps"][:, None], p["max_speed_mps"][:, None])
        v0 = np.minimum(speed, vmax)
        v_k = clip(v0[..., None] + acc[..., None] * self.accel_tau * self.accel_fade, 0.0,
                   vmax[..., None])
        dt_k = p["time_step_s"][:, None, None]
        dist_k = np.cumsum(0.5 * (v_k + np.concatenate([v0[..., None], v_k[..., :-1]], -1))
                           * dt_k, axis=-1)
        # constant velocity
        cdir, sdir = np.cos(dir_)[..., None], np.sin(dir_)[..., None]
        cv_x = x[..., None] + cdir * dist_k
        cv_y = y[..., None] + sdir * dist_k
        sel_lf = (intent == INTENT_LANE_FOLLOW)[..., None]
        sel_ci = (intent == INTENT_CUT_IN)[..., None]
        tx, ty, th = cv_x, cv_y, np.broadcast_to(dir_[..., None], cv_x.shape)
        # each other motion is computed only when some slot follows it (elementwise: a slot's
        # values do not depend on the others)
        if sel_ci.any():
            ci_x, ci_y, ci_h = self._cut_in(p, tt, cv_x, cv_y, cdir, sdir, speed, rel_y, lc, ls)
            tx, ty = np.where(sel_ci, ci_x, tx), np.where(sel_ci, ci_y, ty)
            th = np.where(sel_ci, ci_h, th)
        if sel_lf.any():
            lf_x, lf_y, lf_h = self._lane_follow(q, x, y, lane_h, bike, dist_k)
            tx, ty = np.where(sel_lf, lf_x, tx), np.where(sel_lf, lf_y, ty)
            th = np.where(sel_lf, lf_h, th)
        return tx, ty, th, v_k

    def _lane_follow(self, q: np.ndarray, x: np.ndarray, y: np.ndarray, lane_h: np.ndarray,
                     bike: np.ndarray, dist_k: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Lane follow along the matched lane and its first successors: x, y, heading
        (N, S, K)."""
        road = self.world.road
        lane = road.lane_point_lane[q]
        cmax = road.chain_points.shape[1] - 1
        pos = clip(road.lane_point_s[q][..., None] + dist_k, 0, cmax - 1e-6)
        i = pos.astype(np.int64)
        u = pos - i
        # flat gathers (``take`` of rows is several times faster than ``chain_points[li, i]``)
        k = lane[..., None] * road.chain_points.shape[1] + i
        chain = road.chain_points.reshape(-1, 2)
        p0 = np.take(chain, k, axis=0)  # (N, S, K, 2)
        p1 = np.take(chain, k + 1, axis=0)
        lf_h = road.chain_heading.reshape(-1).take(k)
        offx = x - road.lane_points[q, 0]
        offy = y - road.lane_points[q, 1]
        lat0 = -offx * np.sin(lane_h) + offy * np.cos(lane_h)
        # vehicles converge to the lane centre; cyclists keep their offset (they ride the edge)
        lat = lat0[..., None] * np.where(bike[..., None], 1.0, self.lane_fade)
        lf_x = p0[..., 0] + u * (p1[..., 0] - p0[..., 0]) - lat * np.sin(lf_h)
        lf_y = p0[..., 1] + u * (p1[..., 1] - p0[..., 1]) + lat * np.cos(lf_h)
        return lf_x, lf_y, lf_h

    @staticmethod
    def _cut_in(p: dict[str, np.ndarray], tt: np.ndarray, cv_x: np.ndarray, cv_y: np.ndarray,
                cdir: np.ndarray, sdir: np.ndarray, speed: np.ndarray, rel_y: np.ndarray,
                lc: np.ndarray, ls: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cut-in: forward motion plus a lateral motion toward and across the ego's path:
        x, y, heading (N, S, K)."""
        lat_v = p["cyclist_cut_in_lateral_speed_mps"][:, None] * -np.sign(rel_y)
        ci_x = cv_x + (-ls * lat_v)[..., None] * tt
        ci_y = cv_y + (lc * lat_v)[..., None] * tt
        ci_h = numerics.arctan2(sdir * speed[..., None] + (lc * lat_v)[..., None],
                                cdir * speed[..., None] - (ls * lat_v)[..., None])
        return ci_x, ci_y, ci_h
