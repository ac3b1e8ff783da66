"""Random highway scenes and harmful driver parameters (the injected-misconfiguration
benchmark, ``tests/benchmarks/bench_cfrca.py``)."""

from __future__ import annotations

import numpy as np

from rocas.stacks.highway.scene import Scene, VehicleSpec

#: parameter -> (harmful low, harmful high): values a misconfiguration injects
HARMFUL = {
    "planning.TIME_WANTED": (0.1, 0.3),
    "planning.DISTANCE_WANTED": (1.0, 3.0),
    "planning.COMFORT_ACC_MIN": (-1.2, -0.5),
    "planning.LANE_CHANGE_MAX_BRAKING_IMPOSED": (7.0, 10.0),
    "control.ACC_MAX": (1.0, 2.0),
    "control.KP_LATERAL": (6.0, 10.0),
    "control.MAX_STEERING_ANGLE": (0.05, 0.1),
}


def random_scene(rng: np.random.Generator, name: str) -> Scene:
    """A three-lane highway: the ego in the middle lane closing on a slow or stopped vehicle
    60 to 140 m ahead, with three to six others around it (some beside it, so changing lane
    is not always possible)."""
    ego = VehicleSpec(("0", "1", 1), 0.0, float(rng.uniform(22, 28)),
                      float(rng.uniform(26, 32)))
    slow_speed = float(rng.uniform(0, 8))
    others = [VehicleSpec(("0", "1", 1), float(rng.uniform(60, 140)), slow_speed, slow_speed,
                          kind=str(rng.choice(["still", "idm"])), lane_change=False)]
    for _ in range(int(rng.integers(3, 7))):
        speed = float(rng.uniform(15, 28))
        others.append(VehicleSpec(("0", "1", int(rng.choice([0, 2]))),
                                  float(rng.uniform(-30, 120)), speed,
                                  speed + float(rng.uniform(-2, 3)),
                                  kind=str(rng.choice(["idm", "idm", "linear", "defensive"]))))
    kept: list[VehicleSpec] = []
    for v in others:  # at least 12 m between vehicles of one lane
        if all(k.lane != v.lane or abs(k.s_m - v.s_m) >= 12 for k in kept):
            kept.append(v)
    return Scene(name, "highway-v0", ego, tuple(kept), duration_s=12.0,
                 config=(("lanes_count", 3),))


def harmful_value(rng: np.random.Generator, name: str) -> float:
    lo, hi = HARMFUL[name]
    return float(rng.uniform(lo, hi))
