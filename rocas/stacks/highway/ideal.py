"""Ideal control for the highway ego: planning's decision executed exactly.

highway-env's IDMVehicle plans (MOBIL's target lane, IDM's acceleration) and then controls: a
cascaded proportional lateral controller (``KP_LATERAL``, ``TAU_PURSUIT``, ``KP_HEADING``)
whose steering it clips to ``MAX_STEERING_ANGLE``, and IDM's acceleration clipped to
``ACC_MAX``. Those five constants are the control module's parameters. :func:`ideal_control_class`
keeps the planning (the same ``follow_road``, ``change_lane_policy`` and ``acceleration``
calls, with the run's planning parameters) and replaces the control by one that reads none of
them and is bounded only by physics:

- **Longitudinal**: IDM's acceleration as planned (the smaller of the current and the target
  lane's while changing lanes), bounded by one g (:data:`G_MPS2`, what tyres on a dry road
  give) instead of ``ACC_MAX``.
- **Lateral**: highway-env's kinematic bicycle model (``Vehicle.step``) moves the vehicle
  along its heading plus the slip angle ``beta = arctan(tan(delta) / 2)`` and turns the
  heading at ``v sin(beta) / (L/2)``. The ideal steering sets the direction of motion over
  the tick to a reference course: the target lane's direction over the tick (the lane
  geometry, no ``TAU_PURSUIT`` look-ahead) turned towards its centre line by the angle of
  the fastest lateral speed from which the lateral motion can still stop at the centre line
  under one g, and no faster than closes the offset within the tick. It is bounded by one g
  of lateral acceleration (``v`` times the heading rate) and by a passenger car's steering
  lock (:data:`STEERING_LOCK_RAD`), not by ``MAX_STEERING_ANGLE``; no gain is read. (Turning
  the *heading* to a reference within one tick instead chatters: the slip that turns the
  heading also moves the car sideways, so it overshoots the centre line every tick.)

Both axes are bounded separately (one g each, not one g together): an idealisation that gives
control the benefit of the doubt. highway-env itself is not edited: the ideal controller is a
subclass of :func:`rocas.stacks.highway.driver.ego_class`'s, read at the same seams.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from rocas.stacks.highway.driver import ego_class, read_seams

#: the physical bound of either acceleration, longitudinal and lateral: one g [m/s^2]
G_MPS2 = 9.81
#: the largest road-wheel angle of a passenger car (about 40 degrees) [rad]
STEERING_LOCK_RAD = 0.7
#: the modules a run can replace by their ideal counterpart
SUBSTITUTES = ("control",)


def planned_acceleration(ego: Any) -> float:
    """IDM's acceleration as IDMVehicle plans it, before its control limit: on the current
    lane, and the smaller of that and the target lane's while changing lanes [m/s^2]."""
    front, rear = ego.road.neighbour_vehicles(ego, ego.lane_index)
    accel = float(ego.acceleration(ego_vehicle=ego, front_vehicle=front, rear_vehicle=rear))
    if ego.lane_index != ego.target_lane_index:
        front, rear = ego.road.neighbour_vehicles(ego, ego.target_lane_index)
        accel = min(accel, float(ego.acceleration(ego_vehicle=ego, front_vehicle=front,
                                                  rear_vehicle=rear)))
    return accel


def ideal_acceleration(planned_mps2: float) -> float:
    """The planned acceleration, bounded by one g [m/s^2]."""
    return float(np.clip(planned_mps2, -G_MPS2, G_MPS2))


def reference_course(ego: Any, target_lane_index: Any, dt_s: float) -> float:
    """The direction [rad] the ego should move in during the next ``dt_s``: the target lane's
    chord over the tick (its heading half a tick's travel ahead) turned by the angle of the
    lateral speed that brings the ego's offset from the centre line to zero as fast as one g
    of lateral deceleration allows, without overshooting within the tick."""
    lane = ego.road.network.get_lane(target_lane_index)
    s, offset = lane.local_coordinates(ego.position)
    speed = float(ego.speed)
    lateral = min(math.sqrt(2.0 * G_MPS2 * abs(offset)), abs(offset) / dt_s)
    lateral = -math.copysign(lateral, offset)
    angle = math.asin(max(-1.0, min(1.0, lateral / speed))) if speed > 1e-9 else 0.0
    return float(lane.heading_at(s + speed * dt_s / 2.0)) + angle


def ideal_steering(ego: Any, target_lane_index: Any, dt_s: float) -> float:
    """The steering angle [rad] that moves the ego along :func:`reference_course` during the
    next ``dt_s`` under highway-env's kinematic bicycle model (it moves along its heading plus
    the slip angle ``beta = arctan(tan(delta) / 2)``), bounded by one g of lateral
    acceleration and the steering lock."""
    speed = float(ego.speed)
    half = ego.LENGTH / 2.0
    beta = math.remainder(reference_course(ego, target_lane_index, dt_s) - ego.heading,
                          2.0 * math.pi)
    bound = math.asin(sin_beta_bound(speed, half))
    beta = max(-bound, min(bound, beta))
    delta = math.atan(2.0 * math.tan(beta))
    return float(max(-STEERING_LOCK_RAD, min(STEERING_LOCK_RAD, delta)))


def sin_beta_bound(speed_mps: float, half_length_m: float) -> float:
    """The largest ``sin(beta)`` one g of lateral acceleration allows at ``speed_mps``
    (lateral acceleration ``v^2 sin(beta) / (L/2)``), at most 1."""
    return min(1.0, G_MPS2 * half_length_m / max(speed_mps * speed_mps, 1e-9))


def ideal_control_class(constants: Mapping[str, float], dt_s: float) -> type:
    """:func:`~rocas.stacks.highway.driver.ego_class` ``(constants)`` with its control replaced
    by ideal control (module docstring); ``dt_s`` is the simulation tick [s]. Its planning
    reads the same constants; the control constants among them are never read."""
    base = ego_class(constants)
    kinematics = importlib.import_module("highway_env.vehicle.kinematics")

    def act(self: Any, action: Any = None) -> None:
        if self.crashed:
            return
        self.follow_road()  # planning, as IDMVehicle.act runs it
        if self.enable_lane_change:
            self.change_lane_policy()
        command = {"steering": ideal_steering(self, self.target_lane_index, dt_s),
                   "acceleration": ideal_acceleration(planned_acceleration(self))}
        kinematics.Vehicle.act(self, command)
        self.rocas_frame = read_seams(self)

    return type("RocasIdealControlEgo", (base,), {"act": act})


__all__ = ["G_MPS2", "STEERING_LOCK_RAD", "SUBSTITUTES", "ideal_acceleration",
           "ideal_control_class", "ideal_steering", "planned_acceleration",
           "reference_course", "sin_beta_bound"]
