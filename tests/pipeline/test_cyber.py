"""The cyber mutation space: one module's parameters at their values in force, never the
braking limits (capping braking hides an emergency instead of avoiding it), and sensing limits
only widened (narrowing them hides the cause too), pace limits only lowered (driving faster wins
a race instead of removing the cause)."""

import numpy as np
import pytest

from rocas.errors import UsageError
from rocas.pipeline.cyber import cyber_space
from rocas.search.space import Mutation
from rocas.stacks.ads.params import BRAKING_LIMITS, PACE_LIMITS, PARAMETERS, SENSING_LIMITS, parameters


def test_the_space_is_the_module_without_its_braking_limits():
    space = cyber_space("planning", {"planning.yield_distance_m": 9.0})
    names = {v.name for v in space.variables}
    expected = {p.full_name for p in parameters("planning")} - BRAKING_LIMITS
    assert names == expected
    assert "planning.max_decel_mps2" not in names and "planning.yield_distance_m" in names
    assert space.variable("planning.yield_distance_m").original == 9.0


def test_scope_all_spans_every_module_and_still_leaves_out_the_limits():
    names = {v.name for v in cyber_space(None, {}).variables}
    assert names == set(PARAMETERS) - BRAKING_LIMITS
    assert BRAKING_LIMITS <= set(PARAMETERS)


def test_an_unknown_module_is_refused():
    with pytest.raises(UsageError, match="no parameters for module"):
        cyber_space("radar", {})



def test_sensing_limits_may_only_grow():
    space = cyber_space("perception", {"perception.camera_range_m": 55.0})
    cam = space.variable("perception.camera_range_m")
    assert (cam.original, cam.low, cam.high) == (55.0, 55.0, PARAMETERS["perception.camera_range_m"].high)
    assert space.variable("perception.brake_threshold").low == PARAMETERS["perception.brake_threshold"].low
    assert SENSING_LIMITS <= set(PARAMETERS) and not SENSING_LIMITS & BRAKING_LIMITS
    lowest = Mutation({"perception.camera_range_m": cam.decode(0.0)})
    assert not space.decode(space.encode(lowest)).values  # narrowing is not in the space


def test_pace_limits_may_only_fall():
    space = cyber_space("planning", {"planning.junction_speed_mps": 9.0})
    junction = space.variable("planning.junction_speed_mps")
    assert (junction.original, junction.low, junction.high) == (
        9.0, PARAMETERS["planning.junction_speed_mps"].low, 9.0)
    cruise = space.variable("planning.cruise_speed_mps")
    assert cruise.high == cruise.original == PARAMETERS["planning.cruise_speed_mps"].default
    assert space.variable("planning.yield_distance_m").high == PARAMETERS["planning.yield_distance_m"].high
    assert PACE_LIMITS <= set(PARAMETERS) and not PACE_LIMITS & (BRAKING_LIMITS | SENSING_LIMITS)
    faster = Mutation({"planning.junction_speed_mps": 12.0})
    assert not space.decode(space.encode(faster)).values  # raising is not in the space
    # the screening tries a pace limit at its lower end and halfway down only (its upper end is
    # the value in force)
    from rocas.search.ga import screening_genomes

    screened = [m.values["planning.junction_speed_mps"] for m in
                (space.decode(g) for g in screening_genomes(space, 0))
                if "planning.junction_speed_mps" in m.values]
    assert screened == [junction.low, (junction.low + 9.0) / 2]


def test_fix_candidates_are_the_smallest_distinct_fixes_that_keep_the_trajectory():
    from rocas.pipeline.cyber_phase import _first_fix, _fix_candidates, _nearest_fix
    from rocas.search.ga import Candidate, SearchResult

    def cand(values, h1, h2, ok=True):
        return Candidate(Mutation(values), (h1, h2), -1.0 if ok else 0.5, 1)

    a1 = cand({"planning.a": 1.0}, 0.1, 1.30)
    a2 = cand({"planning.a": 2.0}, 0.0, 1.20)        # same parameter set as a1, smaller
    b = cand({"planning.b": 1.0}, 0.2, 1.25)
    drift = cand({"planning.c": 1.0}, 5.0, 1.01)     # changes the ego's earlier trajectory
    crash = cand({"planning.d": 1.0}, 0.0, 1.00, ok=False)
    pair = cand({"planning.a": 1.0, "planning.b": 1.0}, 0.0, 2.4)
    res = SearchResult(candidates=[crash, drift, a1, b, a2, pair], front=[])
    assert _fix_candidates(res, 1.0, 3) == [a2, b, pair]
    assert _fix_candidates(res, 1.0, 1) == [a2]
    assert _first_fix(res, 1.0) == 3  # the drifting fix does not count
    # when no fix keeps the trajectory there is no candidate (no_configuration_fix); the one
    # that changes it least is recorded as the nearest
    far = SearchResult(candidates=[drift, cand({"planning.e": 1.0}, 3.0, 1.5)], front=[])
    assert _fix_candidates(far, 1.0, 3) == []
    assert _nearest_fix(far, 1.0).mutation.names == ("planning.e",)
    assert _nearest_fix(res, 1.0) is None
    # raising a parameter and lowering it are different fixes when the originals are known
    down = cand({"planning.a": 0.5}, 0.0, 1.22)
    both = SearchResult(candidates=[a1, a2, b, down], front=[])
    assert _fix_candidates(both, 1.0, 3) == [a2, b]  # without originals: one per set
    assert _fix_candidates(both, 1.0, 3, {"planning.a": 1.5, "planning.b": 0.0}) == [a2, down, b]
    # fixes that leave the ego standing come after those that get it past, whatever their h2
    assert _fix_candidates(res, 1.0, 2, stalled=lambda m: "planning.a" in m.values) == [b, a2]


def test_the_smallest_shrunk_fix_wins_and_near_ones_through_other_parameters_are_kept():
    from rocas.pipeline.cyber_phase import _smallest_fix

    dist = Mutation({"planning.min_overtake_distance_m": 1.64})
    buf = Mutation({"planning.overtake_time_buffer_s": 0.82})
    buf2 = Mutation({"planning.overtake_time_buffer_s": 0.7})
    horizon = Mutation({"planning.overlap_check_horizon_s": 2.4})
    fixes = [buf, horizon, dist, buf2]
    best, near = _smallest_fix([1.036, 1.366, 1.034, 1.04], fixes)
    assert fixes[best] == dist
    assert [fixes[i] for i in near] == [buf]   # the same parameter set once; 1.366 is too far
    assert _smallest_fix([1.2], [horizon]) == (0, [])
    # ties go to the parameter names, whatever the order the candidates came in
    assert _smallest_fix([1.1, 1.1], [horizon, dist])[0] == 1


def test_an_equally_small_fix_that_keeps_the_ego_farther_away_wins():
    from rocas.pipeline.cyber_phase import _smallest_fix

    # A3: lowering the overtake margin lets the ego race ahead of the truck (4.7 m gap);
    # raising it makes the ego yield (6.9 m): as small a change, and the repair
    race = Mutation({"planning.min_overtake_distance_m": 2.35})
    yield_ = Mutation({"planning.min_overtake_distance_m": 3.91})
    buf = Mutation({"planning.overtake_time_buffer_s": 0.91})
    originals = {"planning.min_overtake_distance_m": 3.0, "planning.overtake_time_buffer_s": 1.0}
    fixes = [buf, race, yield_]
    best, near = _smallest_fix([1.018, 1.016, 1.023], fixes, separation=[4.7, 4.7, 6.9],
                               originals=originals)
    assert fixes[best] == yield_
    assert [fixes[i] for i in near] == [race, buf]  # both directions are reported
    # less than SEPARATION_MARGIN_M wider, or outside the h2 tolerance: the smallest stays
    assert fixes[_smallest_fix([1.018, 1.016, 1.023], fixes, separation=[4.7, 4.7, 5.0],
                               originals=originals)[0]] == race
    assert fixes[_smallest_fix([1.018, 1.016, 1.2], fixes, separation=[4.7, 4.7, 6.9],
                               originals=originals)[0]] == race


def test_two_fixes_that_both_pass_at_several_metres_keep_the_smaller():
    """An A11 speed variant (s613): the moving-obstacle check 0.5 -> 1.83 m (h2 1.443) keeps
    6.0 m from the truck, the lateral buffer 0.3 -> 1.69 m (h2 1.464) 6.8 m: both raise a
    margin, neither races; 0.8 m wider is only 14 % more, so the smaller change stays."""
    from rocas.pipeline.cyber_phase import SEPARATION_RATIO, _smallest_fix

    check = Mutation({"planning.collision_check_moving_m": 1.828})
    buffer = Mutation({"planning.lateral_safety_buffer_m": 1.692})
    fixes = [buffer, check]
    originals = {"planning.collision_check_moving_m": 0.5, "planning.lateral_safety_buffer_m": 0.3}
    best, near = _smallest_fix([1.464, 1.443], fixes, separation=[6.82, 6.00],
                               originals=originals)
    assert fixes[best] == check and [fixes[i] for i in near] == [buffer]
    # the same two gaps scaled down to a race (1.0 m against 1.82 m) swap
    wide = 1.0 * SEPARATION_RATIO + 0.6
    assert fixes[_smallest_fix([1.464, 1.443], fixes, separation=[wide, 1.0],
                               originals=originals)[0]] == buffer


def test_a_fix_is_known_only_when_its_whole_batch_has_run():
    from rocas.pipeline.cyber_phase import _first_fix, _first_fix_batch
    from rocas.search.ga import Candidate, GenerationStats, SearchResult

    def cand(name, gen, ok):
        return Candidate(Mutation({name: 1.0}), (0.0, 1.1), -1.0 if ok else 0.5, gen)

    def gen(g, evaluations):
        return GenerationStats(g, evaluations, 0, 0.0, np.zeros((0, 2)), np.zeros(0))

    # the screening batch (generation 0) holds 4 simulations, generation 1 another 3
    cands = [cand("a", 0, False), cand("b", 0, False), cand("c", 0, False), cand("d", 0, False),
             cand("e", 1, False), cand("f", 1, True), cand("g", 1, True)]
    res = SearchResult(candidates=cands, front=[], generations=[gen(0, 4), gen(1, 7)])
    assert _first_fix(res, 1.0) == 6 and _first_fix_batch(res, 1.0) == 7
    early = SearchResult(candidates=[cands[0], cand("b", 0, True), *cands[2:]], front=[],
                         generations=res.generations)
    assert _first_fix(early, 1.0) == 2 and _first_fix_batch(early, 1.0) == 4
    none = SearchResult(candidates=cands[:5], front=[], generations=res.generations)
    assert _first_fix_batch(none, 1.0) is None


def test_a_fix_that_leaves_a_scrape_ranks_after_every_one_that_keeps_a_gap():
    """An A11 variant: `idm_exponent` 4 -> 6.4 is the smallest fix (h2 1.34) but the ego
    passes the truck at 6 cm; the collision check (h2 1.42) keeps 6.1 m and is the repair."""
    from rocas.pipeline.cyber_phase import _smallest_fix

    idm = Mutation({"planning.idm_exponent": 6.375})
    check = Mutation({"planning.collision_check_moving_m": 1.75})
    buffer = Mutation({"planning.lateral_safety_buffer_m": 2.03})
    fixes = [idm, check, buffer]
    assert fixes[_smallest_fix([1.339, 1.417, 1.577], fixes, separation=[0.06, 6.11, 6.86])[0]] == check
    # a gap of SCRAPE_M or more is no scrape (A2's parked car passed at 0.43 m), and nothing
    # near at all (an infinite gap) is none either
    assert fixes[_smallest_fix([1.339, 1.417, 1.577], fixes, separation=[0.43, 6.11, 6.86])[0]] == idm
    assert fixes[_smallest_fix([1.339, 1.417, 1.577], fixes,
                               separation=[float("inf"), 6.11, 6.86])[0]] == idm


def test_a_fix_that_leaves_the_ego_standing_where_the_accident_left_it_is_no_repair():
    """An A2 variant: the nudge look-ahead 40 -> 50.3 m (h2 1.11) turns the hard brake in front
    of the parked pair into a gentle stop there and keeps 5.8 m from both cars; the static
    buffer 0.6 -> 0.33 m (h2 1.09) passes them at 0.42 m. Without the progress rule the wider
    gap chose the look-ahead; the ego it leaves stands where the accident left it."""
    from rocas.pipeline.cyber_phase import _smallest_fix

    buf = Mutation({"planning.static_obstacle_lateral_buffer_m": 0.328})
    look = Mutation({"planning.nudge_lookahead_m": 50.3})
    fixes = [look, buf]
    h2, sep = [1.109, 1.091], [5.84, 0.42]
    assert fixes[_smallest_fix(h2, fixes, separation=sep)[0]] == look   # the gap alone
    best, near = _smallest_fix(h2, fixes, separation=sep, stalled=[True, False])
    assert fixes[best] == buf and [fixes[i] for i in near] == [look]
    # a stalled fix ranks after the others whatever its h2, and wins only when all are stalled
    assert fixes[_smallest_fix([1.05, 1.4], fixes, separation=sep, stalled=[True, False])[0]] == buf
    assert fixes[_smallest_fix([1.05, 1.4], fixes, separation=sep, stalled=[True, True])[0]] == look


def test_an_accident_ended_blocked_when_its_ego_stood_without_a_collision():
    from rocas.pipeline.cyber_phase import driven_m, ended_blocked
    from rocas.pipeline.evaluate import VariantResult
    from rocas.sim.oracles import Outcome

    def outcome(collided: bool) -> Outcome:
        return Outcome(collided, 8.0 if collided else None, "car" if collided else None,
                       "actor" if collided else None, None, not collided,
                       None if collided else 8.0, False, None, False, not collided, 7.0, 1.0, 0.3)

    # 10 s at 0.05 s: 10 m/s for 8 s, then 0.5 m/s (crawling in front of the obstacle)
    speed = np.r_[np.full(160, 10.0), np.full(40, 0.5)]
    xs = np.r_[0.0, np.cumsum(speed * 0.05)]
    xy = np.stack([xs, np.zeros_like(xs)], axis=1)
    assert driven_m(xy) == pytest.approx(81.0)
    stood = VariantResult(outcome(False), xy, np.zeros((201, 0, 2)))
    assert ended_blocked(stood, 0.05)
    # a collision run, or one that drove on at 10 m/s, did not end blocked
    assert not ended_blocked(VariantResult(outcome(True), xy, np.zeros((201, 0, 2))), 0.05)
    moving = np.stack([np.arange(201) * 0.5, np.zeros(201)], axis=1)
    assert not ended_blocked(VariantResult(outcome(False), moving, np.zeros((201, 0, 2))), 0.05)


def test_another_stack_names_its_own_limits():
    space = cyber_space(None, {}, stack="lav")
    names = {v.name for v in space.variables}
    assert "controller.max_brake_decel_mps2" not in names  # a braking limit
    camera = space.variable("brake.camera_range_m")  # a sensing limit
    assert camera.low == camera.original < camera.high
    top = space.variable("planner.max_speed_kmh")  # a pace limit
    assert top.low < top.original == top.high


def test_the_other_shrunk_fixes_are_listed_once_per_parameter_and_direction():
    from rocas.pipeline.cyber_phase import _other_fixes

    originals = {"planning.lateral_safety_buffer_m": 0.3, "planning.collision_check_moving_m": 0.5,
                 "planning.idm_exponent": 4.0}
    chosen = Mutation({"planning.lateral_safety_buffer_m": 1.69})
    check = Mutation({"planning.collision_check_moving_m": 2.45})
    check2 = Mutation({"planning.collision_check_moving_m": 2.6})   # the same fix, larger
    lower = Mutation({"planning.collision_check_moving_m": 0.1})    # the other direction
    idm = Mutation({"planning.idm_exponent": 6.4})
    fixes = [chosen, check2, idm, check, lower]
    h2 = [1.46, 1.7, 1.34, 1.65, 1.9]
    got = _other_fixes(h2, fixes, [0], originals)
    assert [fixes[i] for i in got] == [idm, check, lower]  # smallest first, check2 once as check
    # a fix shown as a near alternative is not listed again
    assert [fixes[i] for i in _other_fixes(h2, fixes, [0, 2], originals)] == [check, lower]
    assert _other_fixes([1.2], [chosen], [0], originals) == []
