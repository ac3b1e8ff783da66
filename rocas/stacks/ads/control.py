"""Control: lateral tracking (pure pursuit or Stanley) and a longitudinal PID on the planned
trajectory, mapped to throttle/brake/steering percentages through a calibration."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rocas import numerics
from rocas.sim.geometry import _arange, clip, wrap_angle
from rocas.sim.world import BatchWorld
from rocas.stacks.ads.localization import ChassisOutput, LocalizationOutput
from rocas.stacks.ads.planning import PlanningOutput


@dataclass(frozen=True, eq=False)
class ControlOutput:
    """Actuator commands, each (N,): throttle, brake [0, 100] %, steering_target
    [-100, 100] %, steering_rate [%/s], acceleration [m/s^2], estop (bool), lateral_error [m],
    heading_error [rad], station_error [m], speed_error [m/s]."""

    throttle: np.ndarray
    brake: np.ndarray
    steering_target: np.ndarray
    steering_rate: np.ndarray
    acceleration: np.ndarray
    estop: np.ndarray
    lateral_error: np.ndarray
    heading_error: np.ndarray
    station_error: np.ndarray
    speed_error: np.ndarray


def _interp_rows(xq: np.ndarray, xp: np.ndarray, *fps: np.ndarray) -> list[np.ndarray]:
    """Row-wise linear interpolation of several tables: xq (N,), xp and each fp (N, K), xp
    nondecreasing per row."""
    k = xp.shape[1]
    # xp <= xq holds on a prefix of each row (xp is nondecreasing), so its length is the
    # first False (argmin of a bool row, far cheaper than a sum), or k when all hold
    below = xp <= xq[:, None]
    i = clip(np.where(below[:, -1], k, np.argmin(below, axis=1)) - 1, 0, k - 2)
    r = _arange(xp.shape[0])
    x0, x1 = xp[r, i], xp[r, i + 1]
    u = clip((xq - x0) / np.maximum(x1 - x0, 1e-9), 0.0, 1.0)
    return [fp[r, i] + u * (fp[r, i + 1] - fp[r, i]) for fp in fps]


class Control:
    def __init__(self, world: BatchWorld, params: dict[str, np.ndarray]) -> None:
        self.world = world
        self.p = {k.split(".", 1)[1]: v for k, v in params.items() if k.startswith("control.")}
        n = world.batch_size
        self.integral = np.zeros(n)
        self.prev_error = np.zeros(n)
        self.steering = np.zeros(n)
        self._rows_of: PlanningOutput | None = None  # the plan _t_rows and _s_rows are of
        self._t_rows = self._s_rows = np.zeros((n, 0))

    def step(self, now_s: float, plan: PlanningOutput, plan_time_s: float,
             loc: LocalizationOutput, chassis: ChassisOutput) -> ControlOutput:
        p = self.p
        dt = self.world.dt_s
        n = loc.x.shape[0]
        r = _arange(n)
        # match the pose on the trajectory (nearest valid point, then the segment)
        d2 = (plan.x - loc.x[:, None]) ** 2 + (plan.y - loc.y[:, None]) ** 2
        d2 = np.where(plan.valid, d2, np.inf)
        i = clip(np.argmin(d2, axis=1), 0, plan.x.shape[1] - 2)
        th = plan.theta[r, i]
        ex, ey = loc.x - plan.x[r, i], loc.y - plan.y[r, i]
        along = ex * np.cos(th) + ey * np.sin(th)
        lateral = -ex * np.sin(th) + ey * np.cos(th)
        s_match = plan.s[r, i] + along
        heading_err = wrap_angle(loc.heading - th)
        # longitudinal
        tq = now_s - plan_time_s + p["preview_time_s"]
        if plan is not self._rows_of:  # a plan's interpolation tables, made once per plan
            self._rows_of = plan
            self._t_rows = np.where(plan.valid, plan.t, plan.t[:, :1] + 1e3 + plan.t)
            self._s_rows = np.where(plan.valid, plan.s, plan.s[:, -1:] + 1e3 + plan.t)
        t_rows, s_rows = self._t_rows, self._s_rows
        v_ref, a_ref = _interp_rows(tq, t_rows, plan.v, plan.a)
        (s_ref,) = _interp_rows(np.full(n, now_s - plan_time_s), t_rows, plan.s)
        speed = chassis.speed
        ev = v_ref - speed
        es = s_ref - s_match
        self.integral = clip(self.integral + ev * dt, -p["integral_limit_mps"],
                                p["integral_limit_mps"])
        deriv = (ev - self.prev_error) / dt
        self.prev_error = ev
        kp = np.where(speed < p["low_speed_threshold_mps"], p["low_speed_kp"], p["speed_kp"])
        acc = a_ref + kp * ev + p["speed_ki"] * self.integral + p["speed_kd"] * deriv \
            + p["station_kp"] * es
        acc = clip(acc, -p["max_decel_cmd_mps2"], p["max_accel_cmd_mps2"])
        throttle = np.where(acc > 0, acc / p["calibration_max_accel_mps2"] * 100.0, 0.0)
        brake = np.where(acc < 0, -acc / p["calibration_max_decel_mps2"] * 100.0, 0.0)
        throttle = np.where(throttle < p["throttle_deadzone_pct"], 0.0, np.minimum(throttle, 100))
        brake = np.where(brake < p["brake_deadzone_pct"], 0.0, np.minimum(brake, 100.0))
        hold = (v_ref < 0.05) & (speed < 0.2)
        brake = np.where(hold, np.maximum(brake, p["standstill_brake_pct"]), brake)
        throttle = np.where(hold, 0.0, throttle)
        estop = plan.estop | (np.abs(lateral) > p["lateral_error_estop_m"])
        brake = np.where(estop, p["estop_brake_pct"], brake)
        throttle = np.where(estop, 0.0, throttle)
        # lateral
        wb = p["wheelbase_m"]
        look = np.maximum(p["pure_pursuit_min_lookahead_m"],
                          p["pure_pursuit_lookahead_gain_s"] * speed)
        tx, ty = _interp_rows(s_match + look, s_rows, plan.x, plan.y)
        kappa = plan.kappa[r, i]
        # one arctan2 call for the three angles that do not depend on each other (arctan(v) is
        # arctan2(v, 1) bit for bit); each element's arithmetic is what three calls would do
        bearing, stanley, feedforward = numerics.arctan2(
            np.concatenate([ty - loc.y, p["stanley_gain"] * lateral, wb * kappa]),
            np.concatenate([tx - loc.x, speed + p["stanley_softening_mps"], np.ones(n)]),
        ).reshape(3, n)
        alpha = wrap_angle(bearing - loc.heading)
        delta_pp = numerics.arctan2(2.0 * wb * np.sin(alpha), look)
        delta_st = -heading_err - stanley + p["curvature_feedforward_gain"] * feedforward
        delta = np.where(p["lateral_controller"] >= 0.5, delta_st, delta_pp)
        target = clip(delta / p["max_steer_angle_rad"] * 100.0, -100.0, 100.0)
        max_step = p["steering_rate_limit_pct_s"] * dt
        new_steer = self.steering + clip(target - self.steering, -max_step, max_step)
        rate = (new_steer - self.steering) / dt
        self.steering = new_steer
        return ControlOutput(
            throttle=throttle, brake=brake, steering_target=new_steer, steering_rate=rate,
            acceleration=acc, estop=estop, lateral_error=lateral, heading_error=heading_err,
            station_error=es, speed_error=ev,
        )
