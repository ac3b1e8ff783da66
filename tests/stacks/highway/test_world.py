"""highway-env as a world: determinism, judging, parameters, the optional import."""

import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip("highway_env")

from rocas.errors import ScenarioError, UsageError  # noqa: E402
from rocas.stacks.highway.world import simulate  # noqa: E402
from rocas.stacks.registry import get_stack  # noqa: E402

from .scenes import PLANTED, WEAK_BRAKES  # noqa: E402


def test_same_seed_gives_the_same_trajectories_bit_for_bit():
    a, b = simulate(PLANTED, WEAK_BRAKES, 3), simulate(PLANTED, WEAK_BRAKES, 3)
    assert a.digest() == b.digest()
    assert np.array_equal(a.ego, b.ego) and np.array_equal(a.others, b.others)


def test_weak_brakes_rear_end_the_crawling_car_and_the_defaults_do_not():
    crash, safe = simulate(PLANTED, WEAK_BRAKES, 0), simulate(PLANTED, {}, 0)
    assert crash.collided and crash.collided_with >= 1  # a vehicle, not an object
    assert 6.0 < crash.collision_t_s < 8.5
    assert crash.constraint() > 0
    assert not safe.accident and safe.constraint() <= 0
    # the commands stay within the limit the parameter sets
    assert crash.ego[:, 4].min() >= -1.82 - 1e-12


def test_the_trajectories_are_the_same_until_the_brakes_saturate():
    crash, safe = simulate(PLANTED, WEAK_BRAKES, 0), simulate(PLANTED, {}, 0)
    differ = np.flatnonzero(np.any(crash.ego[:40] != safe.ego[:40], axis=1))
    assert differ.size == 0


def test_parameters_outside_their_range_are_refused():
    with pytest.raises(ScenarioError, match="out of range"):
        simulate(PLANTED, {"planning.TIME_WANTED": 9.0}, 0)


def test_the_stack_is_registered_with_its_modules_and_parameters():
    stack = get_stack("highway")
    names = {p.full_name for p in stack.parameters}
    assert {"planning.TIME_WANTED", "planning.POLITENESS", "control.KP_LATERAL"} <= names
    assert {ch.writer for ch in stack.channels} == set(stack.modules)
    with pytest.raises(UsageError, match="highway-env's world"):
        stack.build(None, {})


def test_without_highway_env_the_error_names_the_extra():
    code = ("import sys; sys.modules['highway_env'] = None\n"
            "from rocas.stacks.highway.hwenv import require\n"
            "from rocas.errors import UsageError\n"
            "try:\n    require()\nexcept UsageError as e:\n    print(e.hint)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert "rocas[highway]" in out.stdout


def test_every_environment_builds_and_repeats_bit_for_bit():
    from rocas.stacks.highway.accidents import entry
    from rocas.stacks.highway.scene import Scene, VehicleSpec

    crossing = Scene("crossing", "intersection-v0",
                     VehicleSpec(("o0", "ir0", 0), 60.0, 8.0, destination="o1"),
                     (VehicleSpec(("o1", "ir1", 0), 60.0, 8.0, destination="o3"),),
                     duration_s=4.0)
    scenes = [entry(k).scene for k in ("h01", "h02", "h04")] + [crossing]
    assert {s.env_id for s in scenes} == {"highway-v0", "merge-v0", "roundabout-v0",
                                          "intersection-v0"}
    for scene in scenes:
        assert simulate(scene, {}, 1).digest() == simulate(scene, {}, 1).digest()


def test_a_fix_avoids_the_accident_unless_the_same_one_or_an_earlier_other_one_happens():
    from dataclasses import replace

    from rocas.stacks.highway.accidents import entry
    from rocas.stacks.highway.world import avoids

    e = entry("h01")
    crash = simulate(e.scene, e.params, e.seed)
    safe = simulate(e.scene, {}, e.seed)
    assert crash.collided and crash.collided_with > 0 and not safe.accident
    assert avoids(safe, crash) and not avoids(crash, crash)
    t, other = crash.accident_t_s, crash.collided_with % 4 + 1
    later_other = replace(crash, collided_with=other, collision_t_s=t + 1.0)
    earlier_other = replace(crash, collided_with=other, collision_t_s=t - 1.0)
    off_road_later = replace(crash, collided=False, collided_with=-1, collision_t_s=None,
                             off_road=True, off_road_t_s=t + 0.5)
    assert avoids(later_other, crash) and avoids(off_road_later, crash)
    assert not avoids(earlier_other, crash)
