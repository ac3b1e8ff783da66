import importlib.util
from pathlib import Path

import numpy as np

from rocas.scenarios.model import COLORS
from rocas.stacks.ads import classifier

SCRIPT = Path(__file__).resolve().parents[3] / "scripts" / "train_brake_classifier.py"


def _prob(color: str, dist: float, lateral: float = 0.0) -> float:
    f = classifier.camera_view(
        np.array([[np.arctan2(lateral, dist)]]), np.array([[dist]]), np.array([[1.0]]),
        np.array([[1.6]]), np.array([[COLORS[color]]]), np.array([[1.0]]), np.zeros(1),
        np.zeros(1))
    return float(classifier.mlp_forward(classifier.load_weights(), f)[0])


def test_output_rises_for_red_objects():
    for dist in (12.0, 20.0):
        assert _prob("red", dist) > _prob("white", dist) + 0.3
        assert _prob("red", dist) > _prob("blue", dist) + 0.3


def test_close_obstacle_ahead_means_brake_whatever_its_colour():
    assert _prob("white", 5.0) > 0.8
    assert _prob("white", 5.0, lateral=4.0) < 0.5
    assert _prob("white", 30.0) < 0.2


def test_rows_are_independent_of_the_batch():
    w = classifier.load_weights()
    x = np.random.default_rng(0).random((7, classifier.FEATURES))
    assert np.array_equal(classifier.mlp_forward(w, x)[3:4], classifier.mlp_forward(w, x[3:4]))


def test_training_script_is_reproducible():
    spec = importlib.util.spec_from_file_location("train_brake_classifier", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    a = mod.train(seed=3, samples=1500, epochs=2)
    b = mod.train(seed=3, samples=1500, epochs=2)
    assert all(np.array_equal(a[k], b[k]) for k in a)
    assert set(a) == set(classifier.load_weights())
