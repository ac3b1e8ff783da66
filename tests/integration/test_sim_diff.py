"""rocas diff on recordings of the built-in simulator and ADS (an end-to-end check)."""

import pytest

from rocas.analysis import diff
from rocas.rollout import simulate
from rocas.scenarios import load_example


@pytest.fixture(scope="module")
def a9_pair(tmp_path_factory):
    d = tmp_path_factory.mktemp("a9")
    scenario = load_example("roundabout_red_truck")
    accident = simulate(scenario, output=d / "accident.mcap")
    fixed = simulate(scenario, params={"perception.brake_threshold": 0.99},
                     output=d / "fixed.mcap")
    assert accident.outcome.emergency and not fixed.outcome.emergency
    return d / "accident.mcap", d / "fixed.mcap"


def test_red_truck_hard_brake_deviates_first_in_perception(a9_pair):
    r = diff(*a9_pair)
    assert r.control_channel == "/control"
    assert r.deviating_module == "perception"
    assert "/perception/brake_signal" in r.pinpoint.path
