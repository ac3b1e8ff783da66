"""The objectives of the paper's two searches (section 5.1 and 5.3).

Physical mutation minimises (f1, f2, f3) subject to "no accident"; cyber mutation
minimises (h1, h2) subject to the same constraint. f3 and h2 are
:meth:`rocas.search.space.MutationSpace.distance`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

#: distance [m] assigned to global entities (weather) that have no position
GLOBAL_ENTITY_DISTANCE_M = 50.0


def suspiciousness(
    entity_xy: Sequence[tuple[float, float] | None],
    ego_xy: tuple[float, float],
    ego_heading: float,
    k: float = 10.0,
    min_distance_m: float = 0.5,
) -> float:
    """f1 = -sum_i (K / dist_i + cos(theta_i)) over the mutated entities.

    Args:
        entity_xy: world position of each mutated entity at the accident [m]; None for a
            global entity (weather), which counts at GLOBAL_ENTITY_DISTANCE_M with cos = 0.
        ego_xy: ego position at the accident [m].
        ego_heading: ego heading at the accident [rad].
        k: weight K of distance against angle [m].
        min_distance_m: distances are clipped below this, so an entity at the ego's
            position scores finitely.

    Returns:
        f1 (lower is more suspicious). Entities close to and in front of the ego are more
        likely to have triggered the accident than those far away or behind it.
    """
    total = 0.0
    hx, hy = math.cos(ego_heading), math.sin(ego_heading)
    for xy in entity_xy:
        if xy is None:
            total += k / GLOBAL_ENTITY_DISTANCE_M
            continue
        dx, dy = xy[0] - ego_xy[0], xy[1] - ego_xy[1]
        dist = max(math.hypot(dx, dy), min_distance_m)
        total += k / dist + (dx * hx + dy * hy) / dist
    return -total


def trajectory_mse(a: np.ndarray, b: np.ndarray) -> float:
    """Mean squared position error [m^2] between trajectories of shapes (T1, 2) and (T2, 2),
    over their common length (a missing trajectory on one side counts as 0 error)."""
    n = min(len(a), len(b))
    if n == 0:
        return 0.0
    d = np.asarray(a[:n], dtype=float) - np.asarray(b[:n], dtype=float)
    return float(np.mean(np.sum(d * d, axis=-1)))


def scenario_dissimilarity(
    original: Mapping[str, np.ndarray], mutated: Mapping[str, np.ndarray]
) -> float:
    """f2 = -sum_j Sim(Traj_p0(j), Traj_p(j)) with Sim = -MSE: the sum over actors of the
    MSE between each actor's original and mutated trajectory [m^2]."""
    return sum(trajectory_mse(original[j], mutated[j]) for j in original if j in mutated)


def ego_dissimilarity(original: np.ndarray, mutated: np.ndarray, until_index: int) -> float:
    """h1 = -Sim(Traj_c0, Traj_c) with Sim = -MSE, over the ego trajectory before the
    accident (the first ``until_index`` samples: [0, d - delta])."""
    return trajectory_mse(original[:until_index], mutated[:until_index])
