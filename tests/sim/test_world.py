"""The ego reference line: projections of points near it and far from it."""

import numpy as np

from rocas.scenarios import scenario_from_dict
from rocas.sim.world import FAR_LATERAL_M, project_on_reference, road_geometry

# the ego turns right: east along y = -1.75, then south along x = 1.75 (a quarter circle)
ARC = [[-10.0 + 11.75 * np.sin(a), -1.75 - 11.75 * (1 - np.cos(a))]
       for a in np.linspace(0.0, np.pi / 2, 9)]
TURN = {
    "scenario": {"name": "turn", "duration_s": 5.0},
    "lanes": [
        {"id": "in", "points": [[-100.0, -1.75], [-10.0, -1.75]], "successors": ["arc"]},
        {"id": "arc", "points": ARC, "successors": ["out"], "junction": True},
        {"id": "out", "points": [ARC[-1], [ARC[-1][0], -100.0]]},
        {"id": "north", "points": [[-1.75, 100.0], [-1.75, 10.0]]},
    ],
    "ego": {"route": ["in", "arc", "out"], "start_s_m": 20.0},
}


def _road():
    sc = scenario_from_dict(TURN)
    return road_geometry(sc.lanes, sc.ego.route, sc.ego.start_s_m, None)


def test_points_near_the_route_project_on_it():
    road = _road()
    idx, s, lat = project_on_reference(road, np.array([-50.0, -50.0]), np.array([-1.75, 0.25]))
    np.testing.assert_allclose(lat, [0.0, 2.0], atol=1e-6)
    np.testing.assert_allclose(s[1] - s[0], 0.0, atol=1e-6)
    assert np.all(idx < road.ref_points.shape[0])


def test_points_far_from_a_curved_route_are_not_beside_it():
    # a truck on the north road, 40 m from the junction: nowhere near the ego's right turn,
    # but the tangent at the end of the (southbound) reference line passes close to it
    road = _road()
    _, _, lat = project_on_reference(road, np.array([-1.75, -1.75]), np.array([40.0, 90.0]))
    assert np.all(np.abs(lat) >= FAR_LATERAL_M)
