"""Module substitution on the highway ego: ideal control implicates control or clears it."""

import json

import pytest

pytest.importorskip("highway_env")

from rocas.stacks.highway.accidents import entry  # noqa: E402
from rocas.stacks.highway.scene import Scene, VehicleSpec  # noqa: E402
from rocas.stacks.highway.substitution import (  # noqa: E402
    SubstitutionRun,
    judge,
    second_opinion,
)

from .scenes import LAZY_LANE_CHANGE, PLANTED, WEAK_BRAKES  # noqa: E402


def test_weak_brakes_crash_disappears_under_ideal_control():
    o = second_opinion(PLANTED, WEAK_BRAKES, 0)
    assert o.accident and o.baseline.collided and 6.0 < o.baseline.accident_t_s < 8.5
    assert not o.ideal_control.accident and o.ideal_control.accident_t_s is None
    assert o.ideal_control.substituted == ("control",) and o.baseline.substituted == ()
    assert o.module == "control" and o.cleared == ("perception",)
    assert o.stance("control") == "agrees"
    assert o.stance("planning") == "disagrees" and o.stance(None) == "disagrees"


def test_the_jam_distance_crash_persists_under_ideal_control():
    e = entry("h03")
    o = second_opinion(e.scene, e.params, e.seed)
    assert o.accident and o.ideal_control.collided
    assert o.module == "planning" and o.cleared == ("perception", "control")
    assert "no driver could avoid it" in o.reason
    assert o.stance("planning") == "agrees" and o.stance("control") == "disagrees"
    assert o.stance("perception") == "disagrees"
    assert o.stance(None) == "consistent" and o.stance("world") == "consistent"


def test_an_unavoidable_crash_is_left_to_planning_by_elimination():
    e = entry("h06")  # no configuration fix: 28 m/s, a stopped car 14 m ahead
    o = second_opinion(e.scene, e.params, e.seed)
    assert o.module == "planning" and o.ideal_control.collided
    assert o.stance(None) == "consistent"


def test_without_an_accident_the_opinion_is_undetermined():
    o = second_opinion(PLANTED, LAZY_LANE_CHANGE, 0)  # a planning change with no crash here
    assert not o.accident and o.module is None
    assert o.stance("planning") == "undetermined" and o.stance("control") == "undetermined"


def test_a_plan_beyond_the_default_control_limit_is_put_on_control():
    # IDM with a 0.1 s time gap plans up to 9.8 m/s^2 of braking; highway-env's control
    # executes 6 (ACC_MAX's default) and crashes, ideal control executes it and does not:
    # a two-module accident (ACC_MAX at 8 avoids it too), which substitution puts on control
    o = second_opinion(PLANTED, {"planning.TIME_WANTED": 0.1}, 0)
    assert o.accident and not o.ideal_control.accident and o.module == "control"


def test_the_opinion_is_deterministic_and_serialisable():
    a, b = second_opinion(PLANTED, WEAK_BRAKES, 2), second_opinion(PLANTED, WEAK_BRAKES, 2)
    assert a == b
    assert json.loads(json.dumps(a.to_dict()))["ideal_control"]["substituted"] == ["control"]


#: roundabout-v0 with two cars entering; with control.KP_HEADING at 14.8 the ego leaves the
#: road at the south entry (bench_cfrca's accident bench-0-168)
RING = Scene("ring", "roundabout-v0",
             VehicleSpec(("ser", "ses", 0), 126.55, 7.345, destination="nxs"),
             (VehicleSpec(("ner", "nes", 0), 62.82, 15.89, destination="exr"),
              VehicleSpec(("eer", "ees", 0), 31.16, 13.70, destination="sxr")),
             duration_s=12.0)


def test_another_accident_later_under_ideal_control_is_not_this_one():
    o = second_opinion(RING, {"control.KP_HEADING": 14.8}, 0)
    assert o.baseline.off_road and o.baseline.accident_t_s < 3.5
    # ideal control keeps the ego on the ring; its exact path then meets the car entering
    # from the east, which IDM/MOBIL does not yield to
    assert o.ideal_control.collided and o.ideal_control.what() == "hit vehicle 2"
    assert o.other_accident and o.module == "control" and "another" in o.reason


def _run(what: str, t: float | None) -> SubstitutionRun:
    return SubstitutionRun((), what != "none", what.startswith("hit"), what == "off road", t,
                           2 if what == "hit 2" else -1, 10, 0.0, "")


def test_the_rule_on_the_accident_and_the_ideal_run():
    crash = _run("hit 2", 5.0)
    assert judge(crash, _run("none", None)).module == "control"
    assert judge(crash, _run("hit 2", 7.0)).module == "planning"  # later, same car
    assert judge(crash, _run("off road", 6.0)).module == "control"  # another, later
    first = judge(crash, _run("off road", 4.0))  # another, earlier: no conclusion
    assert first.module is None and first.other_accident and first.accident
    assert first.stance("planning") == "consistent" and first.stance("perception") == "disagrees"
    assert judge(_run("none", None), _run("none", None)).stance("control") == "undetermined"
