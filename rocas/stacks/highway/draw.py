"""Random scenes and harmful driver parameters for the injected-misconfiguration benchmark
(``tests/benchmarks/bench_cfrca.py``).

highway-env's IDM looks at the front vehicle at any distance and may brake up to ``ACC_MAX``,
so most single-parameter misconfigurations do not crash it on an open highway. The benchmark
therefore draws from three families where a parameter can matter, each with its own harmful
parameters: closing on a slow car on a three-lane highway, the end of merge-v0's on-ramp beside
a column, and entering roundabout-v0.
"""

from __future__ import annotations

import numpy as np

from rocas.stacks.highway.scene import Scene, VehicleSpec

#: family -> parameter -> (harmful low, harmful high)
HARMFUL: dict[str, dict[str, tuple[float, float]]] = {
    "slow_ahead": {"control.ACC_MAX": (1.0, 2.0), "planning.DISTANCE_WANTED": (1.0, 2.0)},
    "ramp_end": {"control.ACC_MAX": (1.0, 2.5), "planning.DISTANCE_WANTED": (1.0, 2.5)},
    "roundabout": {"control.MAX_STEERING_ANGLE": (0.05, 0.15),
                   "control.KP_HEADING": (14.0, 20.0)},
}
FAMILIES = tuple(HARMFUL)


def slow_ahead(rng: np.random.Generator, name: str) -> Scene:
    """Three lanes: the ego in the middle closing on a slow or stopped car 60 to 140 m ahead,
    three to six others beside and ahead of it."""
    ego = VehicleSpec(("0", "1", 1), 0.0, float(rng.uniform(22, 28)),
                      float(rng.uniform(26, 32)))
    slow_speed = float(rng.choice([0.0, float(rng.uniform(0, 8))]))
    others = [VehicleSpec(("0", "1", 1), float(rng.uniform(60, 140)), slow_speed, slow_speed,
                          kind="still" if slow_speed == 0.0 else "idm", lane_change=False)]
    for _ in range(int(rng.integers(3, 7))):
        speed = float(rng.uniform(15, 28))
        others.append(VehicleSpec(("0", "1", int(rng.choice([0, 2]))),
                                  float(rng.uniform(-30, 120)), speed,
                                  speed + float(rng.uniform(-2, 3)),
                                  kind=str(rng.choice(["idm", "idm", "linear", "defensive"]))))
    return Scene(name, "highway-v0", ego, _spaced(others), duration_s=12.0,
                 config=(("lanes_count", 3),))


def ramp_end(rng: np.random.Generator, name: str) -> Scene:
    """merge-v0's acceleration lane: the ego beside a column of three to five cars."""
    speed = float(rng.uniform(14, 22))
    ego = VehicleSpec(("b", "c", 2), float(rng.uniform(-5, 15)), speed)
    s = float(rng.uniform(-15, -5))
    others = []
    for _ in range(int(rng.integers(3, 6))):
        others.append(VehicleSpec(("b", "c", 1), s, speed + float(rng.uniform(-1, 1)),
                                  lane_change=False))
        s += float(rng.uniform(13, 18))
    return Scene(name, "merge-v0", ego, tuple(others), duration_s=10.0)


def roundabout(rng: np.random.Generator, name: str) -> Scene:
    """roundabout-v0: the ego enters from the south towards an exit, one to two others."""
    ego = VehicleSpec(("ser", "ses", 0), float(rng.uniform(115, 130)), float(rng.uniform(6, 10)),
                      destination=str(rng.choice(["nxs", "wxs", "exs"])))
    entries = [(("eer", "ees", 0), "sxr"), (("ner", "nes", 0), "exr"), (("wer", "wes", 0), "nxr")]
    others = []
    for i in rng.permutation(len(entries))[: int(rng.integers(1, 3))]:
        lane, dest = entries[int(i)]
        others.append(VehicleSpec(lane, float(rng.uniform(30, 70)), float(rng.uniform(10, 16)),
                                  destination=dest))
    return Scene(name, "roundabout-v0", ego, tuple(others), duration_s=12.0)


def _spaced(vehicles: list[VehicleSpec]) -> tuple[VehicleSpec, ...]:
    kept: list[VehicleSpec] = []
    for v in vehicles:  # at least 12 m between vehicles of one lane
        if all(k.lane != v.lane or abs(k.s_m - v.s_m) >= 12 for k in kept):
            kept.append(v)
    return tuple(kept)


_DRAW = {"slow_ahead": slow_ahead, "ramp_end": ramp_end, "roundabout": roundabout}


def draw(rng: np.random.Generator, name: str) -> tuple[Scene, str, float]:
    """A random scene of a random family, a harmful parameter of that family and its value."""
    family = FAMILIES[int(rng.integers(len(FAMILIES)))]
    scene = _DRAW[family](rng, name)
    names = sorted(HARMFUL[family])
    param = names[int(rng.integers(len(names)))]
    lo, hi = HARMFUL[family][param]
    return scene, param, float(rng.uniform(lo, hi))
