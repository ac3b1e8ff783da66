"""The learned front-camera brake classifier: rasterised view features and a small MLP.

The view is a strip of ``CAMERA_COLUMNS`` bearing columns over the camera's horizontal field of
view; each column holds the apparent size of the nearest visible object and its colour (RGB),
dimmed by fog and brightened by glare. A two-layer perceptron with fixed weights (shipped as
``rocas/stacks/ads/brake_classifier.npz``, trained by ``scripts/train_brake_classifier.py``) maps
the view to a brake probability. Its training labels carry the annotators' habit of marking red
objects ahead as "braking", so its output rises for red objects: the flaw of the paper's A9.
"""

from __future__ import annotations

import functools
from importlib import resources
from io import BytesIO

import numpy as np

from rocas import numerics
from rocas.sim.geometry import clip

CAMERA_COLUMNS = 16
CAMERA_HFOV_RAD = np.deg2rad(60.0)
CHANNELS = 4  # apparent size, r, g, b
FEATURES = CAMERA_COLUMNS * CHANNELS
COLUMN_CENTERS = (np.arange(CAMERA_COLUMNS) + 0.5) / CAMERA_COLUMNS * CAMERA_HFOV_RAD \
    - CAMERA_HFOV_RAD / 2
COLUMN_HALF_WIDTH = CAMERA_HFOV_RAD / CAMERA_COLUMNS / 2
FOG_CONTRAST_LENGTH_M = 25.0  # distance over which fog density 100 removes 63 % of contrast
WEIGHTS_RESOURCE = "brake_classifier.npz"


#: The classifier's training truth (what "brake" means): a body whose footprint reaches within
#: BRAKE_CORRIDOR_MARGIN_M of the ego's axis [m], closer ahead than BRAKE_AHEAD_M [m].
BRAKE_CORRIDOR_MARGIN_M = 1.0
BRAKE_AHEAD_M = 9.0


def brake_worthy(ahead: np.ndarray, lateral: np.ndarray, length: np.ndarray, width: np.ndarray,
                 yaw: np.ndarray) -> np.ndarray:
    """Whether each object is a reason to brake (the unbiased training label), any shape.

    Args:
        ahead, lateral: the object's centre along and across the ego's axis [m].
        length, width: its size [m]; yaw: its heading relative to the ego's axis [rad].
    """
    half_y = 0.5 * (width * np.abs(np.cos(yaw)) + length * np.abs(np.sin(yaw)))
    half_x = 0.5 * (length * np.abs(np.cos(yaw)) + width * np.abs(np.sin(yaw)))
    return ((np.abs(lateral) - half_y < BRAKE_CORRIDOR_MARGIN_M) & (ahead + half_x > 0.0)
            & (ahead < BRAKE_AHEAD_M))


def camera_view(
    bearing: np.ndarray, dist: np.ndarray, lat_extent: np.ndarray, height: np.ndarray,
    rgb: np.ndarray, visible: np.ndarray, fog: np.ndarray, glare: np.ndarray,
) -> np.ndarray:
    """Rasterise objects into the front-camera view.

    Args:
        bearing: (N, M) bearing of each object from the camera axis [rad].
        dist: (N, M) distance [m].
        lat_extent: (N, M) half extent of the object across the line of sight [m].
        height: (N, M) [m].
        rgb: (N, M, 3) colour in [0, 1].
        visible: (N, M) visibility weight in [0, 1] (0 outside range, occluded, ...).
        fog: (N,) fog density in [0, 100].
        glare: (N,) brightness added by the sun in [0, 1].

    Returns:
        features (N, FEATURES): per column [size, r, g, b], columns left to right.
    """
    d = np.maximum(dist, 0.5)
    half_angle = numerics.arctan2(lat_extent, d)
    contrast = numerics.exp(-(fog[:, None] / 100.0) * d / FOG_CONTRAST_LENGTH_M) * visible
    size = clip(height / d * 3.0, 0.0, 1.0) * contrast  # (N, M)
    covers = np.abs(bearing[..., None] - COLUMN_CENTERS) <= half_angle[..., None] \
        + COLUMN_HALF_WIDTH  # (N, M, C)
    value = np.where(covers, size[..., None], 0.0)
    n = bearing.shape[0]
    if bearing.shape[1] == 0:
        col_size = np.zeros((n, CAMERA_COLUMNS))
        col_rgb = np.zeros((n, CAMERA_COLUMNS, 3))
    else:
        best = np.argmax(value, axis=1)  # (N, C) nearest-looking object per column
        rows = np.arange(n)[:, None]  # gathers of the chosen object (as take_along_axis)
        col_size = value[rows, best, np.arange(CAMERA_COLUMNS)]
        col_rgb = np.take(rgb.reshape(-1, 3), rows * rgb.shape[1] + best, axis=0) \
            * col_size[..., None]
    col_rgb = clip(col_rgb + glare[:, None, None], 0.0, 1.0)
    return np.concatenate([col_size[..., None], col_rgb], axis=-1).reshape(n, FEATURES)


def mlp_forward(weights: dict[str, np.ndarray], x: np.ndarray) -> np.ndarray:
    """Brake probability (N,) from features (N, FEATURES)."""
    # no BLAS: numerics.rowdot sums each row in a fixed order, so a variant's probability is
    # bit-identical whatever the batch size, the BLAS kernel or the CPU
    h = numerics.tanh(numerics.rowdot(x, weights["w1"]) + weights["b1"])
    z = numerics.rowdot(h, weights["w2"])[:, 0] + weights["b2"][0]
    return numerics.sigmoid(z)


@functools.cache
def load_weights() -> dict[str, np.ndarray]:
    """The shipped weights (read once)."""
    data = (resources.files("rocas.stacks.ads") / WEIGHTS_RESOURCE).read_bytes()
    with np.load(BytesIO(data)) as npz:
        w = {k: np.asarray(npz[k]) for k in ("w1", "b1", "w2", "b2")}
    if w["w1"].shape[0] != FEATURES:
        raise RuntimeError("brake classifier weights do not match the camera view layout")
    return w
