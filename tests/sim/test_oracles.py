import dataclasses

from rocas.rollout import simulate, simulate_batch
from rocas.scenarios import load_example, scenario_from_dict

ROAD = {
    "scenario": {"name": "oracle", "duration_s": 12.0},
    "lanes": [{"id": "a", "points": [[0, 0], [300, 0]]}],
    "traffic_lights": [{"id": "red", "stop_lane": "a", "stop_s_m": 80.0,
                        "policy": {"mode": "fixed", "color": "red"}}],
    "ego": {"route": ["a"], "start_s_m": 40.0, "start_speed_mps": 8.0},
}


def test_hit_while_stopped_names_the_actor_and_time():
    data = dict(ROAD, actors=[{"id": "reckless", "route": ["a"], "start_s_m": 0.0,
                               "speed_mps": 12.0}])
    out = simulate(scenario_from_dict(data)).outcome
    assert out.collided and out.collision_with == "reckless"
    assert out.collision_kind == "actor"
    assert 3.0 < out.collision_time_s < 12.0
    assert 30.0 < out.collision_position[0] < 80.0
    assert out.min_separation_m < 0


def test_stops_for_red_light_cleanly_and_reports_margin():
    out = simulate(scenario_from_dict(ROAD)).outcome
    assert not out.collided and not out.emergency
    assert 0.05 < out.route_completion < 0.3  # stopped at the line
    assert out.min_separation_m == float("inf")


def test_collision_with_map_entity_and_building():
    data = dict(ROAD, traffic_lights=[], objects=[{"id": "box", "kind": "box",
                                                     "position": [70.0, 0.0]}],
                ego=dict(ROAD["ego"], params={"perception": {"min_obstacle_height_m": 1.5}}))
    out = simulate(scenario_from_dict(data)).outcome
    assert out.collided and out.collision_with == "box" and out.collision_kind == "object"
    wall = dict(ROAD, traffic_lights=[], areas=[{"id": "wall", "kind": "building",
                                                 "polygon": [[60, -5], [61, -5], [61, 5],
                                                             [60, 5]]}],
                ego=dict(ROAD["ego"], params={"perception": {"max_range_m": 20.0}}))
    out = simulate(scenario_from_dict(wall)).outcome
    assert out.collided and out.collision_kind == "area" and out.collision_with == "wall"


def test_disabled_building_is_not_collidable():
    data = dict(ROAD, traffic_lights=[], areas=[{"id": "wall", "kind": "building",
                                                 "enabled": False,
                                                 "polygon": [[60, -5], [61, -5], [61, 5],
                                                             [60, 5]]}])
    assert not simulate(scenario_from_dict(data)).outcome.collided


def test_brake_threshold_turns_a_red_truck_into_an_emergency():
    # accident type A9 in miniature: a red truck ahead fires the learned brake classifier
    data = dict(ROAD, traffic_lights=[], actors=[
        {"id": "red_truck", "model": "truck", "color": "red", "route": ["a"],
         "start_s_m": 62.0, "speed_mps": 8.0}])
    s = scenario_from_dict(data)
    white = scenario_from_dict(dict(data, actors=[dict(data["actors"][0], color="white")]))
    res = simulate_batch([s, s, white],
                         params=[None, {"perception.brake_threshold": 0.99}, None])
    default, raised, not_red = res.outcomes
    assert default.estop and default.emergency  # fires on the red truck with defaults
    assert not raised.estop  # the configuration fix of the paper
    assert not not_red.estop  # a white truck at the same place does not fire it


def test_precipitation_changes_the_world():
    s = dataclasses.replace(load_example("junction_straight"), duration_s=10.0)
    wet = dataclasses.replace(s, weather=dataclasses.replace(s.weather, precipitation=100.0,
                                                             fog_density=90.0))
    res = simulate_batch([s, wet])
    assert not (res.ego[0] == res.ego[1]).all()


def test_standing_behind_a_blocking_car_is_an_unexpected_stop_unless_queued_at_a_light():
    """A stopped car blocks the lane: the ego stops behind it (the planner's reason is
    "blocked") and stands. With no light that is an unexpected stop; with a red light 10 m
    beyond the car the ego waits in a queue, which is traffic."""
    queued = dict(ROAD, actors=[{"id": "waiting", "route": ["a"], "start_s_m": 70.0,
                                 "speed_mps": 0.0}])
    blocked = dict(queued, traffic_lights=[])
    out = [simulate(scenario_from_dict(d)).outcome for d in (blocked, queued)]
    assert out[0].unexpected_stop and out[0].emergency and not out[0].collided
    assert not out[1].unexpected_stop and not out[1].emergency and not out[1].collided
    # a green light does not make the wait legitimate
    green = dict(queued, traffic_lights=[dict(ROAD["traffic_lights"][0],
                                              policy={"mode": "fixed", "color": "green"})])
    assert simulate(scenario_from_dict(green)).outcome.unexpected_stop
