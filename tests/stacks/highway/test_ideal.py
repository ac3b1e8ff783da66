"""Ideal control for the highway ego: planning's decision executed, no control parameter read."""

import math

import numpy as np
import pytest

pytest.importorskip("highway_env")

from rocas.errors import UsageError  # noqa: E402
from rocas.stacks.highway.accidents import entry  # noqa: E402
from rocas.stacks.highway.ideal import G_MPS2, STEERING_LOCK_RAD  # noqa: E402
from rocas.stacks.highway.world import simulate  # noqa: E402

from .scenes import PLANTED, WEAK_BRAKES  # noqa: E402

#: every control parameter at a range end, far from highway-env's values
BAD_CONTROL = {"control.ACC_MAX": 1.0, "control.KP_HEADING": 20.0, "control.KP_LATERAL": 0.1,
               "control.TAU_PURSUIT": 0.0, "control.MAX_STEERING_ANGLE": 0.05}


def _frames(scene, params, substitute="control"):
    rows = []

    def observe(tick, t, sim, frame):
        lane = sim.road.network.get_lane(sim.ego.target_lane_index)
        rows.append((t, lane.local_coordinates(sim.ego.position)[1], frame.steering_rad,
                     frame.acceleration_mps2, sim.ego.lane_index != sim.ego.target_lane_index))

    run = simulate(scene, params, 0, observer=observe, substitute=substitute)
    return run, np.array(rows, dtype=float)


def test_no_control_parameter_changes_an_ideal_control_run():
    for scene in (PLANTED, entry("h04").scene):
        ideal = simulate(scene, {}, 0, substitute="control")
        assert simulate(scene, BAD_CONTROL, 0, substitute="control").digest() == ideal.digest()
        # ... while they do change highway-env's own control
        assert simulate(scene, BAD_CONTROL, 0).digest() != simulate(scene, {}, 0).digest()


def test_planning_parameters_still_drive_the_ideal_control_run():
    ideal = simulate(PLANTED, {}, 0, substitute="control")
    for change in ({"planning.TIME_WANTED": 3.0}, {"planning.LANE_CHANGE_MIN_ACC_GAIN": 2.5}):
        assert simulate(PLANTED, change, 0, substitute="control").digest() != ideal.digest()


def test_the_commands_stay_within_physics_and_the_lane_change_settles_without_chatter():
    run, rows = _frames(PLANTED, {})
    assert not run.accident and rows[:, 4].any()  # MOBIL changes lanes
    assert np.abs(rows[:, 3]).max() <= G_MPS2 and np.abs(rows[:, 2]).max() <= STEERING_LOCK_RAD
    settled = rows[np.flatnonzero(rows[:, 4])[-1] + 15:]  # a second after the lane change
    assert settled.size and np.abs(settled[:, 1]).max() < 0.01  # on the centre line [m]
    flips = np.count_nonzero(np.diff(np.sign(np.round(rows[:, 2], 4))) != 0)
    assert flips <= 8  # no tick-by-tick steering reversal


def test_ideal_control_brakes_beyond_acc_max_as_idm_plans():
    crash, rows = _frames(PLANTED, WEAK_BRAKES, substitute=None)
    ideal, ideal_rows = _frames(PLANTED, WEAK_BRAKES)
    assert crash.collided and rows[:, 3].min() >= -1.82 - 1e-12
    assert not ideal.accident and ideal_rows[:, 3].min() < -1.82


def test_ideal_control_follows_the_roundabout_a_tiny_steering_limit_leaves():
    assert simulate(entry("h04").scene, entry("h04").params, 0).off_road
    run, rows = _frames(entry("h04").scene, entry("h04").params)
    assert not run.accident and math.isclose(run.times[-1] + 1 / 15, 12.0)


def test_an_unknown_substitute_is_refused():
    with pytest.raises(UsageError, match="no ideal 'planning'"):
        simulate(PLANTED, {}, 0, substitute="planning")
