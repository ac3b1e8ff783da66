"""The speed-profile design against the simulator's own actor law."""

import numpy as np

from rocas.replay.lanes import forward_branches, walk_lanes
from rocas.replay.paths import design_profile
from rocas.scenarios import load_example
from rocas.sim.actors import ACTOR_ACCEL_MPS2, ACTOR_DECEL_MPS2, SPEED_GAIN_PER_S
from rocas.sim.dynamics import profile_speed


def _drive(profile, dt, steps):
    kt = np.array([[k[0] for k in profile]])
    kv = np.array([[k[1] for k in profile]])
    v, s = float(kv[0, 0]), 0.0
    out = [s]
    for i in range(steps):
        target = float(profile_speed(i * dt, kt, kv)[0])
        a = min(max(SPEED_GAIN_PER_S * (target - v), -ACTOR_DECEL_MPS2), ACTOR_ACCEL_MPS2)
        vn = max(v + a * dt, 0.0)
        s += 0.5 * (v + vn) * dt
        v = vn
        out.append(s)
    return np.array(out)


def test_designed_profile_follows_an_accelerating_target():
    dt, dur = 0.05, 12.0
    t = np.arange(0.0, dur + 1.0, 0.1)
    v = np.clip(2.0 * (t - 3.0), 0.0, 12.0)            # stands 3 s, then 2 m/s^2 up to 12 m/s
    s = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * 0.1)])
    prof = design_profile(t, s, dt, dur)
    got = _drive(prof, dt, int(dur / dt))
    want = np.interp(np.arange(len(got)) * dt, t, s)
    assert np.max(np.abs(got - want)) < 0.3
    # a naive profile (the target speed itself) lags by metres
    naive = tuple((float(a), float(b)) for a, b in zip(t, v, strict=True))
    assert np.max(np.abs(_drive(naive, dt, int(dur / dt)) - want)) > 1.0
    assert len(prof) < len(t)  # knots on straight stretches are dropped



def test_a_target_beyond_the_acceleration_limit_is_met_by_looking_ahead(monkeypatch):
    """A truck recorded speeding up at 3.5 m/s^2 for a second, then at the simulator's limit
    of 2.5 m/s^2 (a tracker catching up with it records such a stretch): once the actor falls
    behind it cannot catch up, so the profile must start accelerating when a target ahead needs
    it, not when the present error does."""
    import rocas.replay.paths as paths

    dt, dur = 0.05, 8.0
    t = np.arange(0.0, dur + 1.0, 0.1)
    acc = np.where((t > 1.0) & (t < 2.0), 3.5, np.where(t >= 2.0, ACTOR_ACCEL_MPS2, 0.0))
    v = np.minimum(8.0 + np.concatenate([[0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1]) * 0.1)]),
                   18.0)
    s = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * 0.1)])
    want = np.interp(np.arange(int(dur / dt) + 1) * dt, t, s)
    ahead = np.max(np.abs(_drive(design_profile(t, s, dt, dur), dt, int(dur / dt)) - want))
    monkeypatch.setattr(paths, "PREVIEW_MIN_S", 1e9)     # feedback on the present target only
    feedback = np.max(np.abs(_drive(design_profile(t, s, dt, dur), dt, int(dur / dt)) - want))
    assert ahead < 0.75 and feedback > 2.0               # measured: 0.54 m against 2.88 m

def test_walking_the_map_back_and_forth():
    lanes = load_example("left_turn_oncoming").lanes
    by_id = {ln.id: ln for ln in lanes}
    lane = by_id["w_in"]
    p0, p1 = np.array(lane.centerline[0]), np.array(lane.centerline[-1])
    h = float(np.arctan2(*(p1 - p0)[::-1]))
    mid = p0 + 0.5 * (p1 - p0)
    back = walk_lanes(lanes, mid, h, 30.0, forward=False)
    assert np.isclose(np.hypot(*(back[0] - mid)), 30.0, atol=0.5)  # 30 m upstream, ordered to mid
    assert np.allclose(back[:, 1], mid[1])                          # on the lane
    assert np.all(np.diff(np.hypot(*(back - mid).T)) <= 1e-9)     # ordered towards mid
    beyond = walk_lanes(lanes, mid, h, 500.0, forward=False)       # past the map's end: straight
    assert np.isclose(np.hypot(*(beyond[0] - mid)), 500.0, atol=0.5)
    e_in = by_id["e_in"]                                           # straight on, or left
    branches = forward_branches(lanes, np.array(e_in.centerline[-1]) - [5.0, 0.0], 0.0, 60.0)
    assert len(branches) == len(e_in.successors) == 2
    ends = sorted((tuple(np.round(b[-1])) for b in branches), key=lambda e: e[1])
    assert ends[0][1] < 0 < ends[1][1]                             # one goes east, one north
