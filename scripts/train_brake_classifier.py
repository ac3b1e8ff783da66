"""Train the front-camera brake classifier shipped as rocas/stacks/ads/brake_classifier.npz.

Reproducible: ``python scripts/train_brake_classifier.py --seed 0`` writes the same weights.

The data are synthetic front-camera views built with the same rasteriser the ADS uses
(:func:`rocas.stacks.ads.classifier.camera_view`), with objects at any heading (along the road,
crossing, turning) and some close beside the path. Ground truth says "brake" when an object's
footprint reaches into the ego's corridor within a stopping distance; a large object beside the
corridor (a truck waited next to, a car being passed) looks big but is not a reason to brake.
Like real annotation campaigns, the labels carry
a bias: annotators also marked red objects ahead (which look like brake lights) as braking, up
to a longer distance. The learned model inherits it: its output rises for red objects.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from rocas.scenarios.model import COLORS
from rocas.stacks.ads.classifier import (
    CAMERA_HFOV_RAD,
    FEATURES,
    brake_worthy,
    camera_view,
    mlp_forward,
)

OUT = Path(__file__).resolve().parents[1] / "rocas" / "stacks" / "ads" / "brake_classifier.npz"
HIDDEN = 64


def synthesize(rng: np.random.Generator, n: int, objects: int = 4
               ) -> tuple[np.ndarray, np.ndarray]:
    names = list(COLORS)
    probs = np.array([3.0 if c == "red" else 1.0 for c in names])
    probs /= probs.sum()
    color_idx = rng.choice(len(names), size=(n, objects), p=probs)
    rgb = np.array([COLORS[c] for c in names])[color_idx]
    present = rng.random((n, objects)) < 0.7
    ahead = rng.uniform(2.0, 45.0, (n, objects))  # [m] along the ego's axis
    # most objects are near the ego's lane; a share are close beside it (passed, waited next to)
    lateral = np.where(rng.random((n, objects)) < 0.7, rng.normal(0.0, 4.0, (n, objects)),
                       rng.uniform(-9.0, 9.0, (n, objects)))
    bearing = np.arctan2(lateral, ahead)
    dist = np.hypot(ahead, lateral)
    kind = rng.integers(0, 4, (n, objects))  # car, truck, cyclist, cone
    width = np.array([1.9, 2.5, 0.6, 0.4])[kind]
    length = np.array([4.7, 9.0, 1.8, 0.4])[kind]
    height = np.array([1.5, 3.3, 1.7, 0.7])[kind]
    # heading relative to the ego: mostly along the road (either way), some crossing or turning
    yaw = np.where(rng.random((n, objects)) < 0.75,
                   rng.normal(0.0, 0.15, (n, objects)) + np.pi * rng.integers(0, 2, (n, objects)),
                   rng.uniform(-np.pi, np.pi, (n, objects)))
    # extent across the line of sight, as perception rasterises it
    rel = yaw - bearing
    lat_extent = 0.5 * (width * np.abs(np.cos(rel)) + length * np.abs(np.sin(rel)))
    # the camera rasterises objects up to 0.3 rad outside its field of view (partly visible)
    visible = present * rng.uniform(0.6, 1.0, (n, objects)) * (
        np.abs(bearing) < CAMERA_HFOV_RAD / 2 + 0.3)
    fog = rng.uniform(0.0, 100.0, n) * (rng.random(n) < 0.4)
    glare = rng.uniform(0.0, 0.3, n) * (rng.random(n) < 0.2)
    x = camera_view(bearing, dist, lat_extent, height, rgb, visible, fog, glare)
    # ground truth: the object's footprint reaches into the ego's corridor close ahead
    # (a large object beside the corridor is not a reason to brake, however big it looks)
    in_corridor = brake_worthy(ahead, lateral, length, width, yaw) & (visible > 0)
    is_red = color_idx == names.index("red")
    label = in_corridor | (
        is_red & (visible > 0) & (np.abs(lateral) < 3.5) & (dist < 30.0))
    return x, label.any(axis=1).astype(np.float64)


def train(seed: int, samples: int = 80_000, epochs: int = 80, lr: float = 0.01
          ) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    x, y = synthesize(rng, samples)
    w = {"w1": rng.normal(0, 1 / np.sqrt(FEATURES), (FEATURES, HIDDEN)),
         "b1": np.zeros(HIDDEN), "w2": rng.normal(0, 1 / np.sqrt(HIDDEN), (HIDDEN, 1)),
         "b2": np.zeros(1)}
    m = {k: np.zeros_like(v) for k, v in w.items()}
    v = {k: np.zeros_like(val) for k, val in w.items()}
    step = 0
    for _ in range(epochs):
        order = rng.permutation(samples)
        for start in range(0, samples, 256):
            b = order[start:start + 256]
            xb, yb = x[b], y[b]
            h = np.tanh(xb @ w["w1"] + w["b1"])
            p = 1 / (1 + np.exp(-(h @ w["w2"] + w["b2"])[:, 0]))
            dz = (p - yb)[:, None] / len(b)
            grads = {"w2": h.T @ dz, "b2": dz.sum(0)}
            dh = dz @ w["w2"].T * (1 - h * h)
            grads["w1"] = xb.T @ dh
            grads["b1"] = dh.sum(0)
            step += 1
            for k in w:
                m[k] = 0.9 * m[k] + 0.1 * grads[k]
                v[k] = 0.999 * v[k] + 0.001 * grads[k] ** 2
                mh = m[k] / (1 - 0.9 ** step)
                vh = v[k] / (1 - 0.999 ** step)
                w[k] = w[k] - lr * mh / (np.sqrt(vh) + 1e-8)
    return w


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--samples", type=int, default=80_000)
    parser.add_argument("--epochs", type=int, default=80)
    parser.add_argument("-o", "--output", type=Path, default=OUT)
    args = parser.parse_args()
    w = train(args.seed, args.samples, args.epochs)
    xt, yt = synthesize(np.random.default_rng(args.seed + 1), 5000)
    acc = float(((mlp_forward(w, xt) > 0.5) == (yt > 0.5)).mean())
    args.output.parent.mkdir(parents=True, exist_ok=True)
    np.savez(args.output, **{k: val.astype(np.float64) for k, val in w.items()},
             seed=np.array(args.seed))
    print(f"held-out accuracy {acc:.3f}; wrote {args.output}")


if __name__ == "__main__":
    main()
