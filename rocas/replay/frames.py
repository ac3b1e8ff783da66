"""Coordinate transforms between the ego frame of the ADS and the simulator's world frame.

The ego frame has x forward and y left of the ego, origin at the localization estimate; the
world frame is the map's (x east, y north). Headings are counter-clockwise from +x [rad].
"""

from __future__ import annotations

import numpy as np


def wrap(angle: np.ndarray | float) -> np.ndarray:
    """Angles wrapped to [-pi, pi) [rad]."""
    return (np.asarray(angle, dtype=np.float64) + np.pi) % (2.0 * np.pi) - np.pi


def ego_to_world(ego_x: np.ndarray, ego_y: np.ndarray, ego_heading: np.ndarray,
                 x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points in the ego frame -> world frame (all arrays broadcast; metres, radians)."""
    c, s = np.cos(ego_heading), np.sin(ego_heading)
    return ego_x + x * c - y * s, ego_y + x * s + y * c


def ego_vector_to_world(ego_heading: np.ndarray, vx: np.ndarray, vy: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Vectors (velocities, accelerations) expressed in ego axes -> world axes."""
    c, s = np.cos(ego_heading), np.sin(ego_heading)
    return vx * c - vy * s, vx * s + vy * c


def world_to_ego(ego_x: np.ndarray, ego_y: np.ndarray, ego_heading: np.ndarray,
                 x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World points -> ego frame (the inverse of :func:`ego_to_world`)."""
    c, s = np.cos(ego_heading), np.sin(ego_heading)
    dx, dy = x - ego_x, y - ego_y
    return dx * c + dy * s, -dx * s + dy * c


def interpolate_pose(times: np.ndarray, pose: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Ego pose at times ``t`` by linear interpolation (heading unwrapped first).

    Args:
        times: (T,) increasing pose times [s].
        pose: (T, 3) x [m], y [m], heading [rad].
        t: (K,) query times [s]; held at the ends outside ``times``.

    Returns:
        (K, 3) x, y, heading (wrapped).
    """
    t = np.asarray(t, dtype=np.float64)
    heading = np.unwrap(pose[:, 2])
    return np.stack([np.interp(t, times, pose[:, 0]), np.interp(t, times, pose[:, 1]),
                     wrap(np.interp(t, times, heading))], -1)


__all__ = ["ego_to_world", "ego_vector_to_world", "interpolate_pose", "world_to_ego", "wrap"]
