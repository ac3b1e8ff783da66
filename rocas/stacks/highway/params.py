"""The ego driver's parameters: highway-env's IDMVehicle class constants as rocas ParamSpecs.

Each spec's ``name`` is the constant's own name, so a value is applied by overriding that
constant on the ego's class for one run. The module is the seam that reads it: IDM and MOBIL
constants are read by ``planning``, the steering and acceleration limits and the lateral
controller's gains by ``control``. ``KP_A`` is not offered: IDMVehicle never calls the speed
controller that reads it.
"""

from __future__ import annotations

import math
from functools import cache

from rocas.stacks.base import ParamSpec

MODULES = ("world", "vehicle", "perception", "planning", "control")

_SPECS = (
    ("planning", "TIME_WANTED", 1.5, 0.1, 4.0, "s", "IDM desired time gap to the front vehicle"),
    ("planning", "DISTANCE_WANTED", 10.0, 1.0, 30.0, "m",
     "IDM jam distance to the front vehicle (centre to centre)"),
    ("planning", "COMFORT_ACC_MAX", 3.0, 0.5, 6.0, "m/s^2", "IDM maximum acceleration"),
    ("planning", "COMFORT_ACC_MIN", -5.0, -10.0, -0.5, "m/s^2", "IDM comfortable deceleration"),
    ("planning", "DELTA", 4.0, 1.0, 10.0, "", "IDM exponent of the speed term"),
    ("planning", "POLITENESS", 0.0, 0.0, 1.0, "", "MOBIL weight of the others' gains"),
    ("planning", "LANE_CHANGE_MIN_ACC_GAIN", 0.2, 0.0, 3.0, "m/s^2",
     "MOBIL acceleration gain that justifies a lane change"),
    ("planning", "LANE_CHANGE_MAX_BRAKING_IMPOSED", 2.0, 0.0, 10.0, "m/s^2",
     "MOBIL safety criterion: largest braking imposed on the new follower"),
    ("planning", "LANE_CHANGE_DELAY", 1.0, 0.2, 5.0, "s", "time between MOBIL decisions"),
    ("control", "ACC_MAX", 6.0, 1.0, 12.0, "m/s^2", "acceleration command limit (both signs)"),
    ("control", "KP_HEADING", 5.0, 0.5, 20.0, "1/s", "heading controller gain"),
    ("control", "KP_LATERAL", 1.0 / 0.6, 0.1, 10.0, "1/s", "lateral position controller gain"),
    ("control", "TAU_PURSUIT", 0.1, 0.0, 1.0, "s", "look-ahead time of the lane heading"),
    ("control", "MAX_STEERING_ANGLE", math.pi / 3, 0.05, 1.2, "rad", "steering command limit"),
)


@cache
def parameters() -> tuple[ParamSpec, ...]:
    """Every ego driver parameter, planning first."""
    return tuple(ParamSpec(m, n, float(d), float(lo), float(hi), u, doc)
                 for m, n, d, lo, hi, u, doc in _SPECS)


def constant_name(full_name: str) -> str:
    """``"planning.TIME_WANTED"`` -> ``"TIME_WANTED"`` (the IDMVehicle constant)."""
    return full_name.split(".", 1)[1]
