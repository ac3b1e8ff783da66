"""Track assembly on synthetic detections with known answers."""

import numpy as np

from rocas.replay.source import Detections
from rocas.replay.tracks import build_tracks, smooth
from rocas.scenarios.model import Lane


def _detections(rows: list[tuple], colors: list[str]) -> Detections:
    a = np.asarray(rows, dtype=float)
    return Detections(times=a[:, 0], track_id=a[:, 1].astype(int), xy=a[:, 2:4], heading=a[:, 4],
                      velocity=a[:, 5:7], size=a[:, 7:10], type=a[:, 10].astype(int),
                      sub_type=a[:, 11].astype(int), color=tuple(colors))


def _car(t: np.ndarray, tid: int, x0: float, v: float, noise: float = 0.0, seed: int = 0,
         sub_type: int = 3, color: str = "red") -> tuple[list[tuple], list[str]]:
    rng = np.random.default_rng(seed)
    rows = [(ti, tid, x0 + v * ti + noise * rng.normal(), 2.0 + noise * rng.normal(), 0.0, v, 0.0,
             8.5, 2.5, 3.3, 5, sub_type) for ti in t]
    return rows, [color] * len(rows)


def test_id_switch_and_gap_are_stitched_and_bridged():
    t1 = np.round(np.arange(0.0, 3.0, 0.1), 6)
    t2 = np.round(np.arange(4.0, 8.0, 0.1), 6)   # 1 s occlusion, new id after it
    r1, c1 = _car(t1, 4, 0.0, 10.0)
    r2, c2 = _car(t2, 9, 0.0, 10.0)
    tracks = build_tracks(_detections(r1 + r2, c1 + c2), 0.1)
    assert len(tracks) == 1
    tr = tracks[0]
    assert tr.track_ids == (4, 9) and tr.name == "obstacle_4"
    assert (tr.kind, tr.model, tr.color) == ("vehicle", "truck", "red")
    gap = (tr.times > 3.0) & (tr.times < 4.0)
    assert not tr.observed[gap].any()
    assert np.allclose(tr.xy[gap, 0], 10.0 * tr.times[gap], atol=0.05)  # bridged on the line
    assert np.allclose(tr.speed[5:-5], 10.0, atol=0.05)


def test_different_obstacles_are_not_stitched():
    t = np.round(np.arange(0.0, 2.0, 0.1), 6)
    a, ca = _car(t, 1, 0.0, 10.0)
    b, cb = _car(t + 2.5, 2, 200.0, 10.0, sub_type=6, color="blue")   # elsewhere, a pedestrian
    tracks = build_tracks(_detections(a + b, ca + cb), 0.1)
    assert [tr.track_ids for tr in tracks] == [(1,), (2,)]
    assert tracks[1].kind == "pedestrian" and tracks[1].color == "blue"


def test_parked_obstacle_sits_at_the_median_and_unknowns_are_noted():
    t = np.round(np.arange(0.0, 5.0, 0.1), 6)
    rows, colors = _car(t, 3, 50.0, 0.0, noise=0.15, seed=1, sub_type=0, color="unknown")
    tracks = build_tracks(_detections(rows, colors), 0.1)
    tr = tracks[0]
    assert tr.stationary and np.allclose(tr.speed, 0.0)
    assert np.allclose(tr.xy[0], [50.0, 2.0], atol=0.1)
    assert tr.model == "truck" and tr.color == "white"           # from the size; default colour
    assert any("colour" in n for n in tr.notes) and any("size" in n for n in tr.notes)


def test_smoother_keeps_lines_and_reduces_noise():
    t = np.arange(0.0, 5.0, 0.1)
    line = np.stack([3.0 * t, -t], 1)
    assert np.allclose(smooth(t, line), line)  # local linear: no bias, even at the ends
    noisy = line + np.random.default_rng(2).normal(0, 0.2, line.shape)
    assert np.abs(smooth(t, noisy) - line).std() < 0.6 * np.abs(noisy - line).std()


def _truck(ti: float) -> tuple[float, float]:
    """(position [m], speed [m/s]) of a truck at 8 m/s speeding up at 2.5 m/s^2 from 1.5 s."""
    a = max(ti - 1.5, 0.0)
    return 8.0 * ti + 1.25 * a * a, 8.0 + 2.5 * a


def _lost_truck() -> Detections:
    """The truck seen 0.1-3.7 s (track 1; the tracker's velocity lags 2 m/s) and 4.8-7.8 s
    (track 2; its velocity starts from rest, as a new track's does)."""
    rows = []
    for tid, times in ((1, np.arange(0.1, 3.75, 0.1)), (2, np.arange(4.8, 7.85, 0.1))):
        for k, ti in enumerate(np.round(times, 6)):
            x, v = _truck(float(ti))
            reported = min(v, 1.6 + 2.0 * k) if tid == 2 else v - 2.0
            rows.append((ti, tid, x, 2.0, 0.0, reported, 0.0, 8.5, 2.5, 3.3, 5, 3))
    return _detections(rows, ["white"] * len(rows))


def test_short_gap_missing_the_straight_line_gate_is_reidentified_on_the_map():
    """A truck speeding up (8 -> 13.5 m/s) leaves the field of view for 1.1 s and comes back
    under a new id. The tracker's velocity lags at the first piece's end and starts from rest
    on the second piece, so the straight-line prediction misses the 3.65 m gate; on the map it
    is the same truck (the mirrored A3 variant was replayed with two trucks)."""
    lane = Lane(id="road", centerline=((-50.0, 2.0), (400.0, 2.0)))
    d = _lost_truck()
    last = int(np.flatnonzero(d.track_id == 1)[-1])
    x_end, _ = _truck(3.7)
    x_back, _ = _truck(4.8)
    assert abs(x_back - (x_end + d.velocity[last, 0] * 1.1)) > 2.0 + 1.5 * 1.1  # the straight gate fails
    tracks = build_tracks(d, 0.1, (lane,))
    assert [tr.track_ids for tr in tracks] == [(1, 2)]
    assert tracks[0].times[0] == 0.1 and abs(tracks[0].times[-1] - 7.8) < 1e-9


def test_bridge_between_pieces_follows_the_detections_not_the_trackers_velocity():
    """The bridge over the gap takes its end tangents from the pieces' displacements: the new
    track's velocity starts from rest, and bridging with it made the truck slow down from 15
    to 12 m/s in the gap and speed up again (a replayed actor limited to 2.5 m/s^2 then fell
    metres behind)."""
    lane = Lane(id="road", centerline=((-50.0, 2.0), (400.0, 2.0)))
    tr = build_tracks(_lost_truck(), 0.1, (lane,))[0]
    gap = (tr.times > 3.7 + 1e-6) & (tr.times < 4.8 - 1e-6)
    true = np.array([_truck(float(t))[1] for t in tr.times[gap]])
    assert np.all(np.diff(tr.speed[gap]) > 0.0)       # it keeps speeding up
    assert np.max(np.abs(tr.speed[gap] - true)) < 1.5


def _alpha_beta(z: np.ndarray, missed: set[int], a: float, b: float, dt: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The built-in ADS's tracker on measurements ``z`` (n, 2), as rocas.stacks.ads.perception runs
    it: a new track starts at the measurement at rest, later frames are corrected by gains
    ``a`` (position) and ``b`` (velocity), missed frames coast. Returns the published frames
    (the first update on: one hidden frame) as (indices, positions, velocities)."""
    x, v = z[0].copy(), np.zeros(2)
    idx, xs, vs = [], [], []
    for k in range(1, len(z)):
        pred = x + v * dt
        if k in missed:
            x = pred
        else:
            r = z[k] - pred
            x, v = pred + a * r, v + b * r / dt
        idx.append(k), xs.append(x.copy()), vs.append(v.copy())
    return np.array(idx), np.array(xs), np.array(vs)


def test_the_alpha_beta_trackers_lag_is_undone_and_its_coasted_frames_found():
    from rocas.replay.tracks import measured, undo_alpha_beta
    from rocas.stacks.base import AlphaBetaTracker

    dt, n = 0.1, 40
    t = np.round(np.arange(n) * dt, 6)
    z = np.stack([4.5 * t + 0.5 * 2.5 * t ** 2, 0.3 * np.sin(t)], axis=1)  # accelerating
    tracker = AlphaBetaTracker(position_gain=0.6, velocity_gain=0.1, hidden_frames=1)
    idx, xs, vs = _alpha_beta(z, {20, 21}, 0.6, 0.1, dt)
    rows = [(t[k], 7, x[0], x[1], 0.0, v[0], v[1], 4.6, 1.9, 1.5, 5, 3)
            for k, x, v in zip(idx, xs, vs, strict=True)]
    d = _detections(rows, ["red"] * len(rows))
    order = np.arange(len(rows))
    assert np.abs(xs - z[idx]).max() > 0.3           # the published track lags the car
    keep = measured(d, order)
    assert set(idx[~keep].tolist()) == {20, 21}       # exactly the coasted frames
    back = undo_alpha_beta(d, order, tracker, dt)
    assert np.allclose(back[keep], z[idx][keep], atol=1e-9)


def test_the_built_in_stack_declares_its_tracker_with_the_recorded_parameters():
    from rocas.stacks.ads.perception import POSITION_GAIN
    from rocas.stacks.registry import get_stack

    declare = get_stack("ads").tracker
    assert declare({}) == type(declare({}))(POSITION_GAIN, 0.1, 1)   # the defaults
    tr = declare({"perception.velocity_filter_alpha": 0.25, "perception.track_min_hits": 3.0})
    assert (tr.velocity_gain, tr.hidden_frames) == (0.25, 2)


def test_slow_obstacles_get_a_wider_kernel_and_twicing_needs_detections_on_both_sides():
    from rocas.replay.tracks import SLOW_SIGMA_MAX_S, SMOOTH_SIGMA_S, slow_sigma, two_sided

    t = np.round(np.arange(0.0, 6.0, 0.1), 6)
    fast = np.stack([10.0 * t, np.zeros_like(t)], axis=1)
    creeping = np.stack([0.35 * t, np.zeros_like(t)], axis=1)
    assert np.allclose(slow_sigma(t, fast), SMOOTH_SIGMA_S)
    assert np.allclose(slow_sigma(t, creeping)[10:-10], SLOW_SIGMA_MAX_S)
    seen = np.ones(len(t), dtype=bool)
    seen[30:40] = False                                # a 1 s gap
    w = two_sided(t, seen)
    assert np.allclose(w[10:20], 1.0) and w[0] == 0.0 and w[-1] == 0.0
    assert w[29] < 0.5 and w[40] < 0.5                 # one side of the gap is empty
