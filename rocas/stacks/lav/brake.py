"""brake: LAV's learned brake model on the telephoto camera (``brake_model(tel_rgb)``).

The camera view is reduced to ``COLUMNS`` bearing columns; in each, the nearest thing seen
gives its coverage of the column, its colour (coverage-weighted R, G, B and how much redder
than green and blue it is) and its proximity, and
lamps facing the ego give a red-or-yellow and a green feature. A logistic model with fixed
weights (``brake_model.npz``, trained by ``python scripts/train_lav_brake.py``) turns the
feature vector into a brake probability; ``brake.brake_threshold`` makes it a decision.

Its training labels say "brake" for a red or yellow lamp ahead and for anything close in the
ego's corridor, and, like LAV's, they carry a bias: annotators also marked large red objects
ahead as "brake" (they look like a red light through a telephoto lens), so a red truck ahead
raises the probability well above what a white one gets.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from importlib import resources

import numpy as np

from rocas import numerics
from rocas.sim.geometry import wrap_angle
from rocas.sim.world import LIGHT_CODES, BatchWorld, light_state

COLUMNS = 8
FEATURES_PER_COLUMN = 8
NUM_FEATURES = COLUMNS * FEATURES_PER_COLUMN
PROXIMITY_M = 30.0   # [m] proximity falls linearly to 0 at this distance
LAMP_RANGE_M = 45.0  # [m] lamps farther than this are too small to read


@dataclass(frozen=True, eq=False)
class BrakePrediction:
    """(N,) probability, (N,) bool decision, (N, F) features."""

    probability: np.ndarray
    brake: np.ndarray
    features: np.ndarray


def camera_features(ego_x: np.ndarray, ego_y: np.ndarray, ego_yaw: np.ndarray,
                    x: np.ndarray, y: np.ndarray, yaw: np.ndarray, length: np.ndarray,
                    width: np.ndarray, rgb: np.ndarray, lamp_x: np.ndarray, lamp_y: np.ndarray,
                    lamp_facing: np.ndarray, lamp_code: np.ndarray, fov_rad: np.ndarray,
                    range_m: np.ndarray) -> np.ndarray:
    """The camera's feature vector.

    Args:
        ego_x, ego_y, ego_yaw, fov_rad, range_m: (N,).
        x, y, yaw, length, width: (N, M) things in the world; rgb: (N, M, 3) in [0, 1].
        lamp_x, lamp_y, lamp_facing: (L,) or (N, L); lamp_code: (N, L) LIGHT_CODES.

    Returns:
        (N, COLUMNS * FEATURES_PER_COLUMN).
    """
    n = ego_x.shape[0]
    dx, dy = x - ego_x[:, None], y - ego_y[:, None]
    d = np.maximum(np.hypot(dx, dy), 0.5)
    sight = numerics.arctan2(dy, dx)
    bearing = wrap_angle(sight - ego_yaw[:, None])
    rel = yaw - sight
    apparent = np.abs(length * np.sin(rel)) + np.abs(width * np.cos(rel))
    half = numerics.arctan(apparent / (2.0 * d))
    col_w = fov_rad / COLUMNS  # (N,)
    lo = -fov_rad[:, None] / 2 + col_w[:, None] * np.arange(COLUMNS)[None, :]  # (N, C)
    hi = lo + col_w[:, None]
    in_range = (d <= range_m[:, None])[..., None]
    overlap = np.minimum(hi[:, None, :], (bearing + half)[..., None]) - np.maximum(
        lo[:, None, :], (bearing - half)[..., None])
    overlap = np.where(in_range, np.maximum(overlap, 0.0) / col_w[:, None, None], 0.0)
    overlap = np.minimum(overlap, 1.0)  # (N, M, C)
    if x.shape[1]:
        depth = np.where(overlap > 0.0, d[..., None], np.inf)
        owner = depth.argmin(axis=1)  # (N, C)
        rows = np.arange(n)[:, None]
        cov = overlap[rows, owner, np.arange(COLUMNS)[None, :]]
        col_rgb = rgb[rows, owner]  # (N, C, 3)
        prox = cov * np.maximum(0.0, 1.0 - d[rows, owner] / PROXIMITY_M)
    else:
        cov = np.zeros((n, COLUMNS))
        col_rgb = np.zeros((n, COLUMNS, 3))
        prox = np.zeros((n, COLUMNS))
    red_lamp = np.zeros((n, COLUMNS))
    green_lamp = np.zeros((n, COLUMNS))
    if lamp_code.shape[1]:
        lamp_x, lamp_y, lamp_facing = (np.broadcast_to(a, lamp_code.shape)
                                       for a in (lamp_x, lamp_y, lamp_facing))
        ldx, ldy = lamp_x - ego_x[:, None], lamp_y - ego_y[:, None]
        ld = np.hypot(ldx, ldy)
        lb = wrap_angle(numerics.arctan2(ldy, ldx) - ego_yaw[:, None])  # (N, L)
        faces = np.cos(lamp_facing - ego_yaw[:, None] - np.pi) > 0.7
        visible = faces & (ld <= np.minimum(LAMP_RANGE_M, range_m[:, None])) & \
            (np.abs(lb) < fov_rad[:, None] / 2)
        col = np.clip(((lb + fov_rad[:, None] / 2) / col_w[:, None]).astype(np.int64), 0,
                      COLUMNS - 1)
        hot = visible & ((lamp_code == LIGHT_CODES["red"]) | (lamp_code == LIGHT_CODES["yellow"]))
        go = visible & (lamp_code == LIGHT_CODES["green"])
        onehot = col[..., None] == np.arange(COLUMNS)  # (N, L, C)
        red_lamp = (onehot & hot[..., None]).any(axis=1).astype(np.float64)
        green_lamp = (onehot & go[..., None]).any(axis=1).astype(np.float64)
    redness = np.maximum(col_rgb[..., 0] - np.maximum(col_rgb[..., 1], col_rgb[..., 2]), 0.0)
    feats = np.stack([cov, cov * col_rgb[..., 0], cov * col_rgb[..., 1], cov * col_rgb[..., 2],
                      cov * redness, prox, red_lamp, green_lamp], axis=-1)  # (N, C, 8)
    return feats.reshape(n, NUM_FEATURES)


@cache
def model_weights() -> tuple[np.ndarray, float]:
    """(F,) weights and the bias of the trained logistic model."""
    with resources.files(__package__).joinpath("brake_model.npz").open("rb") as f:
        data = np.load(f)
        return np.asarray(data["weights"], dtype=np.float64), float(data["bias"])


def brake_probability(features: np.ndarray) -> np.ndarray:
    """(N, F) -> (N,), without BLAS (an elementwise product summed in a fixed order)."""
    w, b = model_weights()
    return numerics.sigmoid((features * w[None, :]).sum(axis=1) + b)


class BrakeModel:
    def __init__(self, world: BatchWorld, params: Mapping[str, np.ndarray]) -> None:
        self.world = world
        self.threshold = params["brake.brake_threshold"]
        self.range = params["brake.camera_range_m"]
        self.fov = np.deg2rad(params["brake.camera_fov_deg"])
        w = world
        self.dims = np.concatenate([w.actor_dims, w.object_dims], 1)
        grey = np.full((*w.object_kind.shape, 3), 0.5)
        self.rgb = np.concatenate([w.actor_rgb, grey], 1)

    def step(self, t: float, ego_x: np.ndarray, ego_y: np.ndarray, ego_yaw: np.ndarray,
             ax: np.ndarray, ay: np.ndarray, ayaw: np.ndarray) -> BrakePrediction:
        w = self.world
        x = np.concatenate([ax, w.object_pos[..., 0]], 1)
        y = np.concatenate([ay, w.object_pos[..., 1]], 1)
        yaw = np.concatenate([ayaw, w.object_yaw], 1)
        feats = camera_features(ego_x, ego_y, ego_yaw, x, y, yaw, self.dims[..., 0],
                                self.dims[..., 1], self.rgb, w.light_pos[:, 0],
                                w.light_pos[:, 1], w.light_facing, light_state(w, t),
                                self.fov, self.range)
        p = brake_probability(feats)
        return BrakePrediction(p, p > self.threshold, feats)
