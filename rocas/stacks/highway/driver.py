"""The ego driver: highway-env's IDMVehicle, unchanged, read at its own seams.

``IDMVehicle.act`` decides in three steps: MOBIL picks the target lane (``change_lane_policy``),
the lateral controller steers towards it (``steering_control``), and IDM gives the
acceleration from the front and rear vehicles on the current and target lanes
(``road.neighbour_vehicles`` then ``acceleration``). :func:`ego_class` returns a subclass whose
``act`` runs highway-env's own ``act`` and then reads what each step saw and decided, calling
the same pure functions on the same state (neighbour lookup, IDM acceleration, desired gap):
the perception (neighbours), planning (lane decision, IDM accelerations) and control (the
commands the vehicle stores) seams become one :class:`DecisionFrame` per tick.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from rocas.stacks.highway.hwenv import require


@dataclass(frozen=True)
class Neighbour:
    """A vehicle the driver considers (``vid`` -1 when there is none).

    Attributes:
        vid: the vehicle's id (0 ego, 1.. the scene's others in order), -1 when absent.
        gap_m: lane distance from the ego, centre to centre, along the lane [m].
        speed_mps: its speed [m/s].
    """

    vid: int
    gap_m: float
    speed_mps: float


NO_NEIGHBOUR = Neighbour(-1, 0.0, 0.0)


@dataclass(frozen=True)
class DecisionFrame:
    """One tick of the driver's decision, seam by seam.

    Attributes:
        lane, target_lane: the current lane and MOBIL's target lane.
        front, rear: neighbours on the current lane (perception).
        left_front, left_rear, right_front, right_rear: on the lanes beside it, the lower and
            the higher lane id (perception; absent where there is no such lane).
        idm_accel_mps2, idm_accel_target_mps2: IDM on the current and target lanes (planning).
        desired_gap_m: IDM's desired gap to the front vehicle, 0 without one [m].
        target_speed_mps: the driver's target speed [m/s].
        steering_rad, acceleration_mps2: the commands stored on the vehicle (control).
    """

    lane: tuple[str, str, int]
    target_lane: tuple[str, str, int]
    front: Neighbour
    rear: Neighbour
    left_front: Neighbour
    left_rear: Neighbour
    right_front: Neighbour
    right_rear: Neighbour
    idm_accel_mps2: float
    idm_accel_target_mps2: float
    desired_gap_m: float
    target_speed_mps: float
    steering_rad: float
    acceleration_mps2: float


def _neighbour(ego: Any, other: Any) -> Neighbour:
    if other is None:
        return NO_NEIGHBOUR
    return Neighbour(int(getattr(other, "rocas_id", -2)), float(ego.lane_distance_to(other)),
                     float(other.speed))


def _side(ego: Any, offset: int) -> tuple[Neighbour, Neighbour]:
    """Neighbours on the lane ``offset`` ids away, when the road has it."""
    lane = ego.lane_index
    side = (lane[0], lane[1], lane[2] + offset)
    if side not in ego.road.network.side_lanes(lane):
        return NO_NEIGHBOUR, NO_NEIGHBOUR
    front, rear = ego.road.neighbour_vehicles(ego, side)
    return _neighbour(ego, front), _neighbour(ego, rear)


def read_seams(ego: Any) -> DecisionFrame:
    """What the driver perceived, planned and commanded in the ``act`` that just ran."""
    road = ego.road
    front, rear = road.neighbour_vehicles(ego, ego.lane_index)
    accel = float(ego.acceleration(ego_vehicle=ego, front_vehicle=front, rear_vehicle=rear))
    if ego.target_lane_index != ego.lane_index:
        t_front, t_rear = road.neighbour_vehicles(ego, ego.target_lane_index)
        accel_target = float(ego.acceleration(ego_vehicle=ego, front_vehicle=t_front,
                                              rear_vehicle=t_rear))
    else:
        accel_target = accel
    gap = float(ego.desired_gap(ego, front)) if front is not None else 0.0
    return DecisionFrame(
        tuple(ego.lane_index), tuple(ego.target_lane_index), _neighbour(ego, front),
        _neighbour(ego, rear), *_side(ego, -1), *_side(ego, +1), accel, accel_target, gap,
        float(ego.target_speed), float(ego.action["steering"]),
        float(ego.action["acceleration"]))


def ego_class(constants: Mapping[str, float]) -> type:
    """An IDMVehicle subclass with ``constants`` (IDMVehicle constant name -> value) as its
    class constants, that keeps the last tick's :class:`DecisionFrame` in ``rocas_frame``."""
    require()
    behavior = importlib.import_module("highway_env.vehicle.behavior")

    def act(self: Any, action: Any = None) -> None:
        behavior.IDMVehicle.act(self, action)
        if not self.crashed:
            self.rocas_frame = read_seams(self)

    body: dict[str, Any] = {k: float(v) for k, v in constants.items()}
    body["act"] = act
    body["rocas_frame"] = None
    return type("RocasIDMEgo", (behavior.IDMVehicle,), body)
