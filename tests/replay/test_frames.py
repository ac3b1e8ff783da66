import numpy as np

from rocas.replay.frames import ego_to_world, ego_vector_to_world, interpolate_pose, world_to_ego


def test_ego_to_world_known_answer():
    # ego at (10, 5) facing north: a point 2 m ahead and 1 m left is at (9, 7)
    x, y = ego_to_world(10.0, 5.0, np.pi / 2, 2.0, 1.0)
    assert np.allclose([x, y], [9.0, 7.0])
    vx, vy = ego_vector_to_world(np.pi / 2, 3.0, 0.0)
    assert np.allclose([vx, vy], [0.0, 3.0])


def test_round_trip():
    rng = np.random.default_rng(0)
    ex, ey, eh = rng.normal(size=3) * [50, 50, 3]
    px, py = rng.normal(size=(2, 20)) * 30
    wx, wy = ego_to_world(ex, ey, eh, px, py)
    bx, by = world_to_ego(ex, ey, eh, wx, wy)
    assert np.allclose(bx, px) and np.allclose(by, py)


def test_interpolate_pose_across_the_heading_wrap():
    times = np.array([0.0, 1.0])
    pose = np.array([[0.0, 0.0, np.pi - 0.1], [2.0, 0.0, -np.pi + 0.1]])
    x, y, h = interpolate_pose(times, pose, np.array([0.5]))[0]
    assert np.isclose(x, 1.0) and np.isclose(abs(h), np.pi)
