"""The rule that picks the reference (and so the triggering entity) among the accident-free
worlds the physical search found: objectives (f1, f2, f3, f4 = minus the shared prefix [s],
f5 = 1 when the accident's other party no longer gets to where it met the ego)."""

import random

import numpy as np
import pytest

from rocas.catalog import entry
from rocas.pipeline.physical import physical_space
from rocas.pipeline.physical_phase import (
    F2_TOLERANCE_M2,
    arc_positions,
    avoidance_shares,
    choose_reference,
    encounter_kept,
    f2_tolerance,
)
from rocas.search.ga import Candidate
from rocas.search.space import Mutation


def _c(values, f1, f2, f3, prefix_s=5.0):
    return Candidate(Mutation(values), (f1, f2, f3, -prefix_s), -1.0, 0)


def test_the_rule_prefers_changing_a_property_to_removing_the_entity():
    space = physical_space(entry("A10").scenario)
    off = _c({"light.tl_skew.enabled": False}, -1.6, 0.0, 2.0)
    yellow = _c({"light.tl_skew.policy": "fixed_yellow"}, -1.6, 0.0, 2.0)
    assert choose_reference([off, yellow], space) is yellow
    # the earlier keys still come first: a smaller change wins even if it removes the entity
    smaller = _c(off.mutation.values, -1.6, 0.0, 1.5)
    assert choose_reference([smaller, yellow], space) is smaller


def test_the_similarity_margin_scales_with_f2():
    assert f2_tolerance(0.0) == F2_TOLERANCE_M2
    assert f2_tolerance(2.0) == 3.0
    assert f2_tolerance(21.0) > 25.8 > 21.0 + F2_TOLERANCE_M2
    space = physical_space(entry("A3").scenario)
    speed = "actor.truck.speed_delta_mps"
    faster = _c({speed: 1.0}, -2.14, 25.8, 1.05)
    far = _c({speed: 4.0}, -2.14, 40.0, 1.4)
    closer = _c({"actor.truck.start_s_m": 140.0}, -2.14, 21.0, 1.2)
    assert choose_reference([closer, faster], space) is faster  # as similar, and a smaller change
    assert choose_reference([closer, far], space) is closer


def test_a_weather_change_never_wins_over_an_entity_change():
    """Fog changes every channel at once; even a less suspicious, less similar, larger entity
    change that avoids the accident is the better reference."""
    space = physical_space(entry("A3").scenario)
    fog = _c({"weather.fog_density": 39.1}, -0.2, 0.0, 1.39)
    truck = _c({"actor.truck.speed_delta_mps": 3.0}, -0.1, 80.0, 1.9)
    assert choose_reference([fog, truck], space) is truck
    assert choose_reference([fog], space) is fog


def test_a_reference_that_departs_from_the_first_frame_loses_to_one_that_departs_later():
    """A whole path shifted 1-2 m makes the ego react from the first frames, so planning and
    control differ from their first messages; a slower truck leaves the ego as it was for 2 s."""
    space = physical_space(entry("A3").scenario)
    shifted = _c({"actor.truck.lateral_offset_m": 1.5}, -2.5, 0.5, 1.1, prefix_s=0.1)
    late = _c({"actor.truck.speed_delta_mps": -3.0}, -2.1, 9.0, 2.4, prefix_s=2.0)
    assert choose_reference([shifted, late], space) is late


def test_the_choice_does_not_depend_on_the_order_candidates_were_found_in():
    space = physical_space(entry("A3").scenario)
    cands = [_c({"actor.truck.color": c}, -2.0, 0.0, 2.0) for c in ("blue", "red", "white", "black")]
    cands += [_c({"actor.truck.model": m}, -2.0, 0.0, 2.0) for m in ("bus", "sedan")]
    first = choose_reference(cands, space)
    for k in range(5):
        random.Random(k).shuffle(cands)
        assert choose_reference(cands, space) is first
    assert choose_reference([], space) is None


def test_a_reference_that_keeps_the_encounter_wins_over_a_more_similar_one_that_takes_it_away():
    """A1: the creeping car stopped is the more similar world (f2 1.9 against 22.1 m^2), but
    the ego just drives past a car that never gets to where it hit the ego, and prediction,
    whose fault the accident is, treats both as static; lifted, the car still gets there."""
    space = physical_space(entry("A1").scenario)
    speed = "actor.creeping_car.speed_delta_mps"
    stopped = Candidate(Mutation({speed: -2.9}), (-2.87, 1.94, 1.37, -4.65, 1.0), -1.0, 0)
    lifted = Candidate(Mutation({speed: 1.03}), (-2.87, 22.1, 1.13, -3.95, 0.0), -1.0, 0)
    assert choose_reference([stopped, lifted], space) is lifted
    assert choose_reference([stopped], space) is stopped


def test_the_encounter_is_kept_when_the_other_party_still_gets_to_where_it_met_the_ego():
    t = np.arange(0, 8.1, 0.05)[:, None]
    creep = np.hstack([np.full_like(t, -1.75), 3.75 - 0.3 * t])  # southwards at 0.3 m/s
    assert encounter_kept(creep, creep)
    lifted = np.hstack([np.full_like(t, -1.75), 3.75 - 1.3 * t])
    aside = creep + [0.8, 0.0]  # another line, as far along
    assert encounter_kept(creep, lifted) and encounter_kept(creep, aside)
    stopped = np.repeat(creep[:1], len(t), axis=0)
    slower = np.hstack([np.full_like(t, -1.75), 3.75 - 0.1 * t])
    beyond = creep - [0.0, 3.0]  # starts past the place where it met the ego
    assert not encounter_kept(creep, stopped)
    assert not encounter_kept(creep, slower)
    assert not encounter_kept(creep, beyond)
    parked = np.repeat(creep[:1], len(t), axis=0)
    assert encounter_kept(parked, creep)  # a party that did not move keeps it trivially


def test_positions_along_a_path_extend_past_both_ends():
    path = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])
    s = arc_positions(path, np.array([[-2.0, 1.0], [5.0, -3.0], [11.0, 4.0], [10.0, 13.0]]))
    assert s == pytest.approx([-2.0, 5.0, 14.0, 23.0])


def _screened(name, values, avoided):
    """Screened single-property candidates of ``name``: the first ``avoided`` values avoid
    the accident, the rest do not."""
    return [Candidate(Mutation({name: v}), (-1.0, 0.0, 2.0, -5.0, 0.0), -0.5 if k < avoided else 1.5, 0)
            for k, v in enumerate(values)]


def test_the_property_whose_changes_avoid_the_accident_more_often_wins():
    """A9 laid out otherwise: the cone at the entry moved 3 m avoids the accident at one of its
    four screened x values, every other colour of the red truck avoids it; the cone is closer
    to the ego (more suspicious), but the truck's colour is what the accident depends on."""
    space = physical_space(entry("A9").scenario)
    colours = ["black", "blue", "brown", "gray", "green", "orange", "silver", "white", "yellow"]
    truck = _screened("actor.red_truck.color", colours, 9)
    ring = _screened("actor.ring_car.color", colours, 7)
    cone = _screened("object.cone_entry.x", [1.0, 2.0, 3.0, 4.0], 1)
    cone[0] = Candidate(cone[0].mutation, (-3.0, 0.0, 1.5, -7.0, 0.0), -0.3, 0)
    screened = truck + ring + cone
    shares = avoidance_shares(screened)
    assert shares["actor.red_truck.color"] == pytest.approx(10 / 11)
    assert shares["actor.ring_car.color"] == pytest.approx(8 / 11)
    assert shares["object.cone_entry.x"] == pytest.approx(2 / 6)
    feasible = [c for c in screened if c.feasible]
    assert choose_reference(feasible, space) is cone[0]  # without the shares: the most suspicious
    chosen = choose_reference(feasible, space, shares)
    assert chosen.mutation.names == ("actor.red_truck.color",)


def test_a_bool_screened_once_does_not_outrank_a_property_that_avoids_it_at_most_values():
    """A bool has one screened value: avoiding the accident there is 2/3 by the rule of
    succession, as is 3 of 4 light policies, so the rule's later steps (a property change over
    removing the light) decide, as they did without the shares."""
    space = physical_space(entry("A10").scenario)
    policy = _screened("light.tl_skew.policy", ["fixed_green", "fixed_yellow", "off", "fixed_red"], 3)
    off = _screened("light.tl_skew.enabled", [False], 1)
    shares = avoidance_shares(policy + off)
    assert shares["light.tl_skew.enabled"] == shares["light.tl_skew.policy"]
    chosen = choose_reference([c for c in policy + off if c.feasible], space, shares)
    assert chosen.mutation.names == ("light.tl_skew.policy",)


def test_properties_that_avoid_the_accident_only_in_combination_are_not_ranked_by_their_kind():
    """No screened value of either property avoids the accident: the genetic search's
    combinations are not told apart by how many values a bool (1) or a colour (9) was
    screened at, so the rule's later steps decide as they would without the shares."""
    screened = _screened("actor.red_truck.color", ["black", "blue"], 0)
    screened += _screened("area.island.enabled", [False], 0)
    shares = avoidance_shares(screened)
    assert shares == {"actor.red_truck.color": 0.0, "area.island.enabled": 0.0}
