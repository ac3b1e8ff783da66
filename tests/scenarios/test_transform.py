"""Rigid motions of a scenario: exact where they must be, invertible, distance-keeping, and a
rotated catalog accident is the same accident."""

from __future__ import annotations

import dataclasses
import math

import pytest

from rocas.catalog import accident_time, entries, entry, mutate
from rocas.geometry import polyline_length
from rocas.scenarios.loader import scenario_from_dict, scenario_to_dict
from rocas.scenarios.model import Scenario
from rocas.scenarios.transform import PlaneTransform, transform_change, transform_scenario

ENTRIES = entries()
IDS = [e.id for e in ENTRIES]


def _numbers(x: object, path: str = "") -> list[tuple[str, float]]:
    """Every float in a dataclass tree with where it is (strings and ids left out)."""
    if dataclasses.is_dataclass(x):
        return [n for f in dataclasses.fields(x)
                for n in _numbers(getattr(x, f.name), f"{path}.{f.name}")]
    if isinstance(x, tuple):
        return [n for i, v in enumerate(x) for n in _numbers(v, f"{path}[{i}]")]
    if isinstance(x, float) and not isinstance(x, bool):
        return [(path, x)]
    return []


def _close(a: Scenario, b: Scenario, tol: float) -> list[str]:
    """Fields where two scenarios of one structure differ by more than ``tol`` (angles
    compared modulo a full turn)."""
    bad = []
    na, nb = _numbers(a), _numbers(b)
    assert [p for p, _ in na] == [p for p, _ in nb]
    for (path, x), (_, y) in zip(na, nb, strict=True):
        d = abs(x - y)
        if path.endswith(("facing_rad", "yaw_rad")):
            d = abs(math.remainder(x - y, 2 * math.pi))
        elif path.endswith("sun_azimuth_deg"):
            d = abs(math.remainder(x - y, 360.0))
        if d > tol:
            bad.append(f"{path}: {x!r} vs {y!r}")
    return bad


@pytest.mark.parametrize("type_id", IDS)
def test_the_identity_and_a_zero_rotation_about_any_point_change_nothing(type_id):
    s = entry(type_id).scenario
    assert transform_scenario(s, PlaneTransform()) == s
    assert transform_scenario(s, PlaneTransform.rotation(0.0, about=(123.4, -56.7))) == s


@pytest.mark.parametrize("type_id", IDS)
@pytest.mark.parametrize("t", [
    PlaneTransform.rotation(math.radians(37.0), about=(120.0, -40.0)),
    PlaneTransform.rotation(math.radians(-181.0), about=(-1500.0, 1900.0)),
    PlaneTransform.reflection(math.radians(23.0), through=(10.0, 700.0)),
    PlaneTransform.translation(-2500.5, 1234.25).then(PlaneTransform.reflection(1.0)),
], ids=["rot37", "rot-181-far", "mirror23", "translate-then-mirror"])
def test_a_transform_then_its_inverse_gives_the_scenario_back(type_id, t):
    s = entry(type_id).scenario
    moved = transform_scenario(s, t)
    assert _close(moved, s, 1e-3), "the transform must move something"
    assert _close(transform_scenario(moved, t.inverse()), s, 1e-9) == []


def test_compositions_follow_the_algebra():
    r = PlaneTransform.rotation(0.7, about=(3.0, -4.0))
    m = PlaneTransform.reflection(-0.4, through=(-2.0, 5.0))
    for t in (r, m, r.then(m), m.then(r), m.then(m)):
        for p in ((0.0, 0.0), (17.5, -3.25), (-900.0, 1200.0)):
            a = t.then(t.inverse()).point(p)
            assert math.dist(a, p) < 1e-9
            assert math.dist(m.then(r).point(p), r.point(m.point(p))) < 1e-9
    # a reflection fixes the points of its line and a mirror twice is no mirror
    assert math.dist(m.point((-2.0 + 3 * math.cos(-0.4), 5.0 + 3 * math.sin(-0.4))),
                     (-2.0 + 3 * math.cos(-0.4), 5.0 + 3 * math.sin(-0.4))) < 1e-12
    assert not m.then(m).mirror and abs(math.remainder(m.then(m).angle_rad, 2 * math.pi)) < 1e-12


@pytest.mark.parametrize("type_id", IDS)
def test_lengths_and_speeds_are_kept_and_a_mirror_flips_lateral_offsets(type_id):
    s = entry(type_id).scenario
    m = transform_scenario(s, PlaneTransform.reflection(math.radians(71.0), through=(5.0, 9.0)))
    for a, b in zip(s.lanes, m.lanes, strict=True):
        assert polyline_length(b.centerline) == pytest.approx(polyline_length(a.centerline),
                                                              abs=1e-9)
    for a, b in zip(s.actors, m.actors, strict=True):
        assert b.lateral_offset_m == -a.lateral_offset_m
        assert b.speed_profile == a.speed_profile and b.start_s_m == a.start_s_m
    assert m.ego.start_lateral_m == -s.ego.start_lateral_m
    # the file format reads back what the transform made
    assert _close(scenario_from_dict(scenario_to_dict(m)), m, 1e-9) == []


@pytest.mark.parametrize("type_id", ["A2", "A8", "A10", "A11", "A12"])
def test_a_moved_reference_is_the_reference_of_the_moved_world(type_id):
    e = entry(type_id)
    t = PlaneTransform.reflection(math.radians(-33.0), through=(40.0, -12.0)).then(
        PlaneTransform.rotation(2.0, about=(300.0, 100.0)))
    moved = transform_scenario(e.scenario, t)
    via_change = mutate(scenario_to_dict(moved), transform_change(e.truth.reference, t), "t")
    via_world = transform_scenario(e.reference_scenario, t)
    assert _close(via_change, dataclasses.replace(via_world, name=via_change.name), 1e-9) == []


def test_the_sun_turns_with_the_world():
    s = entry("A1").scenario  # sun at 200 deg
    assert transform_scenario(s, PlaneTransform.rotation(math.radians(170.0))
                              ).weather.sun_azimuth_deg == pytest.approx(10.0)
    assert transform_scenario(s, PlaneTransform.reflection(0.0)
                              ).weather.sun_azimuth_deg == pytest.approx(160.0)


#: the brake classifier reads an obstacle's world yaw against an ego-frame bearing (docs/ads.md,
#: "Known bug"), so turning the world changes what it scores: A6 brakes hard at 7.65 s instead
#: of colliding at 9.40 s, A9 brakes at 8.90 s instead of 10.25 s. With the bearing taken in
#: the world frame (measured by patching perception) both keep their accident within a tick.
_CLASSIFIER_YAW = pytest.mark.xfail(strict=True, reason="the brake classifier is not "
                                    "rotation-invariant (docs/ads.md, Known bug)")


@pytest.mark.slow
@pytest.mark.parametrize("type_id", [pytest.param(i, marks=_CLASSIFIER_YAW) if i in ("A6", "A9")
                                     else i for i in IDS])
def test_a_rotated_catalog_accident_is_the_same_accident_within_a_tick(type_id):
    from rocas.rollout import simulate_batch

    e = entry(type_id)
    turned = transform_scenario(e.scenario, PlaneTransform.rotation(math.radians(90.0),
                                                                    about=(300.0, -150.0)))
    a = simulate_batch(e.scenario).outcomes[0]
    b = simulate_batch(turned).outcomes[0]
    assert (b.collided, b.collision_with, b.emergency) == (a.collided, a.collision_with,
                                                          a.emergency)
    assert abs(accident_time(b) - accident_time(a)) <= e.scenario.dt_s + 1e-9
