"""Scene, signals and search logging, read back from the .rrd."""

import dataclasses

import numpy as np
import pytest
from foreign_stack import make_pair
from rrd import read_rrd

from rocas.recording.formats import open_recording
from rocas.rollout import simulate
from rocas.scenarios.loader import load_example
from rocas.search.ga import GenerationStats
from rocas.viz.execution import load_execution
from rocas.viz.scene import actor_names, log_scene
from rocas.viz.search import generations_from_json, log_search
from rocas.viz.signals import log_signals
from rocas.viz.stream import rrd_recording
from rocas.viz.world import light_color_at


@pytest.fixture(scope="module")
def red_truck(tmp_path_factory):
    path = tmp_path_factory.mktemp("scene") / "accident.mcap"
    simulate(load_example("roundabout_red_truck"), output=path)
    return path


def _count(path, topic):
    return sum(1 for m in open_recording(path).messages() if m.channel.topic == topic)


def test_execution_reads_pose_obstacles_plan_prediction_and_outcome(red_truck):
    ex = load_execution(red_truck)
    assert ex.sources == {
        "pose": "/localization/pose",
        "obstacles": "/perception/obstacles",
        "plan": "/planning",
        "prediction": "/prediction",
    }
    assert len(ex.ego_t) == _count(red_truck, "/localization/pose")
    assert len(ex.obstacles) == len(ex.plans) == _count(red_truck, "/perception/obstacles")
    assert ex.world is not None and ex.world["lanes"]
    t, what, _ = ex.accident()
    assert what == "hard brake" and 5.0 < t < 8.0
    # the red truck is named by its kind and colour, not by its track id
    assert "red_truck" in actor_names(ex).values()
    # obstacles are in the world frame: the truck is ahead of the ego on its lane at the start
    first = ex.obstacles[1]
    assert np.all(np.abs(first.xy[:, 1] - (-20.0)) < 25.0)
    assert any("ESTOP" in text for _, _, text in ex.events)


def test_scene_and_signals_rows_and_timelines(red_truck, tmp_path):
    ex = load_execution(red_truck)
    out = tmp_path / "scene.rrd"
    with rrd_recording(out) as rec:
        log_scene(rec, ex, "executions/accident", highlight=["red_truck", "island"])
        log_signals(rec, ex, "executions/accident")
    e, _ = read_rrd(out)
    p = "/executions/accident"
    n_pose, n_obs = len(ex.ego_t), len(ex.obstacles)
    assert e[f"{p}/ego/box"].rows == n_pose and "sim_time" in e[f"{p}/ego/box"].timelines
    assert e[f"{p}/actors/boxes"].rows == n_obs
    assert e[f"{p}/actors/trails"].rows == n_obs
    assert e[f"{p}/actors/predictions"].rows == len(ex.predictions)
    assert e[f"{p}/ego/plan"].rows == len(ex.plans)
    assert e[f"{p}/actors/highlight"].rows == n_obs
    assert e[f"{p}/world/highlight"].static_rows == 1  # the island (an area)
    for static in ("roads", "lane_edges", "areas/vegetation", "objects"):
        assert e[f"{p}/world/{static}"].static_rows >= 1
    assert e[f"{p}/accident"].rows == 1
    assert e[f"{p}/signals/speed"].rows == _count(red_truck, "/canbus/chassis")
    assert e[f"{p}/signals/brake/probability"].rows == e[f"{p}/signals/brake/threshold"].rows == n_obs
    assert e[f"{p}/signals/acceleration/commanded"].rows == _count(red_truck, "/control")
    assert e[f"{p}/signals/decisions"].rows == len(ex.events)
    assert e[f"{p}/channels/planning"].rows == len(ex.plans)


def test_traffic_lights_follow_their_policy(tmp_path):
    scn = load_example("junction_straight")
    path = tmp_path / "junction.mcap"
    simulate(dataclasses.replace(scn, duration_s=6.0), output=path)
    ex = load_execution(path)
    out = tmp_path / "j.rrd"
    with rrd_recording(out) as rec:
        log_scene(rec, ex, "x")
    e, _ = read_rrd(out)
    assert e["/x/world/traffic_lights"].rows >= 1 and e["/x/world/stop_lines"].static_rows == 1
    # each light's label is drawn beside it (placed clear of the light), one row per change
    assert e["/x/world/traffic_light_labels"].rows == e["/x/world/traffic_lights"].rows
    cyc = {"mode": "cycle", "green_s": 8.0, "yellow_s": 3.0, "red_s": 8.0, "offset_s": 3.0}
    assert [light_color_at(cyc, True, t) for t in (0.0, 5.5, 8.5, 20.0)] == [
        "green",
        "yellow",
        "red",
        "green",
    ]
    assert light_color_at(cyc, False, 0.0) == "off"
    assert light_color_at({"mode": "fixed", "color": "red"}, True, 3.0) == "red"


def test_foreign_recording_is_interpreted_by_field_names(tmp_path):
    pair = make_pair(tmp_path)
    ex = load_execution(pair.accident)
    assert ex.sources == {
        "obstacles": "/fusion/tracks",
        "plan": "/behaviour/plan",
        "prediction": "/fusion/forecast",
    }
    assert ex.t0_ns > 0 and 11.0 < ex.duration_s < 12.5
    assert {"/vehicle/state", "/diag/status", "/vehicle/actuation"} <= set(ex.channels)
    assert any("behaviour = HALT" in text for _, _, text in ex.events)
    out = tmp_path / "acme.rrd"
    with rrd_recording(out) as rec:
        log_scene(rec, ex, "executions/accident")
        log_signals(rec, ex, "executions/accident")
    e, _ = read_rrd(out)
    assert e["/executions/accident/actors/boxes"].rows == len(ex.obstacles)
    assert e["/executions/accident/signals/speed"].rows == len(ex.channels["/vehicle/state"].times_s)
    assert e["/executions/accident/channels/diag.status"].rows == len(ex.channels["/diag/status"].times_s)
    assert "/executions/accident/world/roads" not in e  # no world in a foreign file


def test_search_progress_on_the_generation_timeline(tmp_path):
    rng = np.random.default_rng(0)
    gens = [
        GenerationStats(
            g, 8 * (g + 1), g, 1.0 - 0.5 * g, rng.random((8, 3)), np.linspace(-0.5, 1.0, 8) + 0.5 - 0.5 * g
        )
        for g in range(4)
    ]
    out = tmp_path / "search.rrd"
    with rrd_recording(out) as rec:
        log_search(rec, "physical", gens, [f"best {g}" for g in range(4)])
    e, _ = read_rrd(out)
    base = "/search/physical"
    assert e[f"{base}/objectives/f1"].rows == 4 and e[f"{base}/objectives/f3"].rows == 4
    assert e[f"{base}/objectives/f1"].timelines == {"generation"}
    assert e[f"{base}/feasible"].rows == e[f"{base}/evaluations"].rows == 4
    assert e[f"{base}/population"].rows == 4
    assert e[f"{base}/best_candidate"].rows == 4
    assert e[f"{base}/best/f1"].rows == 4  # the first generation already has a feasible member
    assert e[f"{base}/summary"].static_rows == 1
    back = generations_from_json(
        [
            {
                "generation": 0,
                "evaluations": 8,
                "feasible": 1,
                "best_constraint": -0.1,
                "objectives": gens[0].objectives.tolist(),
                "constraints": gens[0].constraints.tolist(),
            }
        ]
    )
    assert back[0].objectives.shape == (8, 3)


def test_the_cyber_search_plots_are_named_h1_h2(tmp_path):
    gens = [GenerationStats(0, 8, 0, 1.0, np.ones((8, 2)), np.zeros(8))]
    out = tmp_path / "cyber.rrd"
    with rrd_recording(out) as rec:
        log_search(rec, "cyber", gens)
    e, _ = read_rrd(out)
    assert "/search/cyber/objectives/h1" in e and "/search/cyber/best/h2" in e
    assert not any(k.startswith("/search/cyber/objectives/f") for k in e)


def test_the_accident_label_shows_in_the_frame_a_view_at_the_accident_time_shows():
    from rocas.viz.scene import first_frame_at

    times = [round(0.1 * k, 10) for k in range(130)]  # 10 Hz frames, as perception publishes
    # a hard brake at 10.25 s: a view at 10.25 s shows the 10.2 s frame, which must carry it
    assert times[first_frame_at(times, 10.25)] == 10.2
    assert times[first_frame_at(times, 10.3)] == 10.3  # a frame at the very time is that one
    assert first_frame_at(times, -0.5) is None


@pytest.mark.parametrize("name", ["a07_rear_ended_at_red", "a10_skewed_junction_light"])
def test_a_light_label_keeps_off_the_road_around_the_light(name):
    # A7's label used to sit on the stop line and on the car queued at the light
    from pathlib import Path

    from rocas.viz.labels import LabelItem, label_rects, place_labels
    from rocas.viz.world import road_patches

    path = Path(__file__).parents[2] / "recordings" / f"{name}.mcap"
    world = load_execution(path).world
    lanes = world["lanes"]
    pts = {ln["id"]: np.asarray(ln["points"], dtype=np.float64) for ln in lanes}
    lights = world["traffic_lights"]
    road = road_patches(lanes, pts, [tuple(tl["position"]) for tl in lights])
    assert road  # the lights stand by a road
    items = [LabelItem(f"{tl['id']}: yellow", tuple(tl["position"]), 1.2) for tl in lights]
    for x0, y0, x1, y1 in label_rects(items, place_labels(items, obstacles=road)):
        assert not any(x0 < b[2] and b[0] < x1 and y0 < b[3] and b[1] < y1 for b in road)


def test_a_recording_with_too_many_channels_shows_the_first_ones_and_says_so(tmp_path,
                                                                               monkeypatch):
    import rocas.viz.execution as execution

    pair = make_pair(tmp_path)
    monkeypatch.setattr(execution, "MAX_CHANNELS_SHOWN", 3)
    ex = execution.load_execution(pair.accident)
    assert len(ex.channels) <= 3
    assert any("channels are not shown" in w and "first 3 channels" in w for w in ex.warnings)


def test_a_view_of_too_many_channels_does_not_import_them_all(tmp_path, monkeypatch):
    import rocas.viz.analysis as analysis

    pair = make_pair(tmp_path)
    monkeypatch.setattr(analysis, "MAX_CHANNELS_SHOWN", 3)
    ex, topics = analysis.write_recording_rrd(tmp_path / "many.rrd", pair.accident)
    assert topics == ()
    assert any("more than the view imports (3)" in w for w in ex.warnings)
    e, _ = read_rrd(tmp_path / "many.rrd")
    assert not any(path.startswith("/sensing") or path.startswith("/fusion") for path in e)


def test_the_diff_verdict_markdown_escapes_names_from_data(tmp_path):
    from hostile import hostile_pair

    from rocas.analysis.diff import diff
    from rocas.viz.diff import report_markdown

    acc, ref = hostile_pair(tmp_path)
    text = report_markdown(diff(acc, ref))
    assert "\x1b" not in text and "\r" not in text
    assert "`/fusion/" not in text  # names are escaped text, not code spans that act
