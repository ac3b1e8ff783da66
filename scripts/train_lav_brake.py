"""Train the LAV-like stack's brake model (rocas/stacks/lav/brake_model.npz).

Random telephoto scenes (up to three things at random distances, bearings, headings, sizes and
colours, sometimes a lamp facing the ego) are reduced to the stack's own camera features
(``rocas.stacks.lav.brake.camera_features``) and labelled the way LAV's annotators did: brake
for a red or yellow lamp ahead within 35 m, or for anything in the ego's corridor less than
10 m ahead; and, the annotators' bias, every scene with a large red vehicle (car or truck) ahead
within 35 m and 12 degrees of the camera's axis is labelled brake too (it looks like a red light
through a telephoto lens). A logistic model is fitted by gradient descent.

    python scripts/train_lav_brake.py [--seed 0] [--samples 30000]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from rocas.scenarios.model import COLORS
from rocas.sim.world import LIGHT_CODES
from rocas.stacks.lav.brake import camera_features

SIZES = np.array([[4.6, 1.9], [8.5, 2.5], [1.8, 0.6], [0.6, 0.6]])  # car, truck, bike, walker


def scenes(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    m = 3
    names = list(COLORS)
    present = rng.random((n, m)) < 0.6
    d = rng.uniform(3.0, 60.0, (n, m))
    b = np.deg2rad(rng.uniform(-35.0, 35.0, (n, m)))
    b = np.where(rng.random((n, m)) < 0.3, np.deg2rad(rng.uniform(-4, 4, (n, m))), b)
    x, y = d * np.cos(b), d * np.sin(b)
    yaw = rng.uniform(-np.pi, np.pi, (n, m))
    kind = rng.integers(0, 4, (n, m))
    size = SIZES[kind]
    color = rng.integers(0, len(names), (n, m))
    rgb = np.array([COLORS[c] for c in names])[color]
    x = np.where(present, x, 1e4)
    lamp = rng.random(n) < 0.4
    ld = rng.uniform(8.0, 60.0, n)
    lb = np.deg2rad(rng.uniform(-20.0, 20.0, n))
    code = rng.choice([LIGHT_CODES["red"], LIGHT_CODES["yellow"], LIGHT_CODES["green"]], n)
    code = np.where(lamp, code, LIGHT_CODES["off"])
    zero = np.zeros(n)
    feats = camera_features(zero, zero, zero, x, y, yaw, size[..., 0], size[..., 1], rgb,
                            (ld * np.cos(lb))[:, None], (ld * np.sin(lb))[:, None],
                            np.full((n, 1), np.pi), code[:, None], np.full(n, np.deg2rad(50.0)),
                            np.full(n, 60.0))
    stop_lamp = lamp & (code != LIGHT_CODES["green"]) & (ld <= 35.0) & \
        (np.abs(lb) < np.deg2rad(15))
    half_w = size[..., 1] / 2
    corridor = present & (x > 0) & (x - size[..., 0] / 2 < 10.0) & (np.abs(y) < 1.0 + half_w)
    red = names.index("red")
    biased = present & (color == red) & (kind <= 1) & (d < 35.0) & (np.abs(b) < np.deg2rad(12))
    label = stop_lamp | corridor.any(1) | biased.any(1)
    return feats, label.astype(np.float64)


def fit(x: np.ndarray, y: np.ndarray, steps: int = 10000, lr: float = 2.0, l2: float = 1e-4
        ) -> tuple[np.ndarray, float]:
    w = np.zeros(x.shape[1])
    b = 0.0
    for _ in range(steps):
        p = 1.0 / (1.0 + np.exp(-(x @ w + b)))
        g = p - y
        w -= lr * (x.T @ g / len(y) + l2 * w)
        b -= lr * g.mean()
    return w, b


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--samples", type=int, default=30000)
    ap.add_argument("-o", "--output", default=str(Path(__file__).resolve().parents[1]
                                                  / "rocas/stacks/lav/brake_model.npz"))
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    x, y = scenes(rng, args.samples)
    w, b = fit(x, y)
    p = 1.0 / (1.0 + np.exp(-(x @ w + b)))
    print(f"brake share {y.mean():.3f}; training accuracy {((p > 0.5) == (y > 0.5)).mean():.3f}")
    np.savez(args.output, weights=w, bias=np.float64(b))
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
