"""The physical mutation space: speed changes that lift slow actors and start late, the
screening's single-property mutants, and the shared prefix of two executions."""

import dataclasses
import json

import numpy as np
import pytest

from rocas.catalog import entry
from rocas.pipeline.evaluate import VariantResult
from rocas.pipeline.physical import (
    SCREEN_FRACTIONS,
    SPEED_LIFT_MPS,
    apply_physical,
    physical_space,
    screening_mutants,
)
from rocas.pipeline.physical_phase import shared_prefix_s
from rocas.search.space import Mutation


def test_the_speed_change_lifts_a_creeping_actor_above_walking_pace():
    """A car creeping at 0.3 m/s can be lifted to SPEED_LIFT_MPS more (a scaling of its
    profile by at most 1.5 could only reach 0.45 m/s), or stopped."""
    scn = entry("A1").scenario
    creeper = scn.actors[0]
    var = physical_space(scn).variable(f"actor.{creeper.id}.speed_delta_mps")
    assert var.high >= SPEED_LIFT_MPS and var.low == -max(v for _, v in creeper.speed_profile)
    lifted = apply_physical(scn, Mutation({var.name: var.high})).actors[0]
    assert lifted.speed_profile[0][1] >= 0.3 + SPEED_LIFT_MPS
    stopped = apply_physical(scn, Mutation({var.name: var.low})).actors[0]
    assert all(v == 0.0 for _, v in stopped.speed_profile)


def test_the_screening_tries_every_property_alone():
    scn = entry("A3").scenario
    space = physical_space(scn)
    mutants = screening_mutants(space)
    assert len(set(mutants)) == len(mutants) and all(len(m.values) == 1 for m in mutants)
    for var in space.variables:
        mine = [m for m in mutants if var.name in m.values]
        if var.kind == "enum":
            assert sorted(map(str, (m.values[var.name] for m in mine))) == \
                sorted(str(c) for c in var.choices if c != var.original)
        elif var.kind == "bool":
            assert [m.values[var.name] for m in mine] == [not var.original]
        else:
            assert len(mine) == sum(var.change(var.decode(f)) > 0 for f in SCREEN_FRACTIONS)


def _result(ego, actors):
    return VariantResult(None, np.asarray(ego, float), np.asarray(actors, float))  # outcome unread


def test_the_shared_prefix_ends_where_the_ego_departs():
    t = np.arange(10.0)
    ego = np.stack([t, 0 * t], axis=1)
    actors = np.stack([t + 10, 0 * t], axis=1)[:, None]
    original = _result(ego, actors)
    assert shared_prefix_s(original, original, 0.1, 10) == pytest.approx(1.0)
    moved = actors.copy()
    moved[1:, 0, 1] += 2.0  # an actor that moves otherwise while the ego drives on as before
    assert shared_prefix_s(original, _result(ego, moved), 0.1, 10) == pytest.approx(1.0)
    ego_moved = ego.copy()
    ego_moved[6:, 1] += 0.05
    assert shared_prefix_s(original, _result(ego_moved, actors), 0.1, 10) == pytest.approx(0.6)
    ego_moved[4:6, 1] += 1e-4  # below SAME_POSITION_M: the same position
    assert shared_prefix_s(original, _result(ego_moved, actors), 0.1, 10) == pytest.approx(0.6)


def test_a_world_where_the_ego_stops_short_of_the_accident_is_no_reference():
    from rocas.pipeline.physical_phase import reference_violation
    from rocas.sim.oracles import Outcome

    fields = {f.name: None for f in dataclasses.fields(Outcome)}
    calm = Outcome(**(fields | {"collided": False, "emergency": False, "min_separation_m": 3.0}))
    crash = Outcome(**(fields | {"collided": True, "emergency": False, "min_separation_m": -0.2}))
    t = np.linspace(0.0, 20.0, 21)
    drives = np.stack([t, 0 * t], axis=1)
    waits = np.zeros((21, 2))
    assert reference_violation(VariantResult(calm, drives, np.zeros((21, 0, 2))), 10.0) <= 0
    stalled = reference_violation(VariantResult(calm, waits, np.zeros((21, 0, 2))), 10.0)
    assert 0.5 < stalled <= 1.0
    assert reference_violation(VariantResult(crash, drives, np.zeros((21, 0, 2))), 10.0) > 1.0


@pytest.mark.slow  # a whole analysis of A1 without validation (about 20 s)
def test_a1_keeps_the_encounter_and_the_shrink_does_not_change_the_diffs_answer(tmp_path):
    """The creeping car stopped avoids A1 and is the more similar world, but it takes the
    encounter away; the car lifted keeps it. Shrunk to +0.19 m/s (0.49 m/s, still below the
    still-obstacle speed) it avoids the accident another way: prediction no longer departs and
    the diff names planning, so the shrink stops at the step where the same modules depart as
    in the unshrunk reference's diff."""
    from pathlib import Path

    from rocas.pipeline import AnalyzeConfig, analyze
    from rocas.search import SerialExecutor

    rec = Path(__file__).resolve().parents[2] / "recordings" / "a01_creeping_car_junction.mcap"
    cfg = AnalyzeConfig(validation_variants=0, alternate_references=0, second_opinion=False)
    report = analyze(rec, tmp_path / "run", cfg, executor=SerialExecutor()).to_json()
    physical = json.loads((tmp_path / "run" / "physical.json").read_text())
    (name, value), = physical["chosen"]["mutation"].items()
    assert name.endswith(".speed_delta_mps") and value > 0
    checked = physical["shrink_checked"]
    assert checked[0]["module"] == "prediction" and "prediction" in checked[0]["departed"]
    assert any("prediction" not in c["departed"] for c in checked[1:])
    assert report["deviating_module"] == "prediction"
    assert not list((tmp_path / "run").glob("shrink_*.mcap"))


def test_a_shrink_step_keeps_the_mechanism_when_only_consequences_depart_or_stop():
    """Generated variants (other speeds, seed 313). A12: the cyclist moved -1.0 m, the diff names
    planning; shrunk to -0.41 m the same modules depart, prediction first (4.0 s, with the
    commands), and also the ego's pose at 4.1 s, after the commands: their consequence, so the
    step keeps the mechanism (and names prediction, the documented module). A4: the left turner
    moved -2.0 m, the pose departs at 1.4 s after the commands (0.6 s) and the diff names
    prediction; shrunk to -1.78 m the pose no longer departs, and the step names planning
    (documented)."""
    from rocas.pipeline.physical_phase import same_mechanism

    want = {"canbus": 0.9, "control": 0.8, "perception": 0.9, "planning": 0.8, "prediction": 7.8}
    step = {"canbus": 4.1, "control": 4.0, "localization": 4.1, "perception": 4.1,
            "planning": 4.0, "prediction": 4.0}
    assert same_mechanism(want, 0.8, step, 4.0)
    assert same_mechanism(want, 0.8, want, 0.8)
    # a module that starts to depart with or before the commands is another mechanism
    assert not same_mechanism(want, 0.8, {**step, "localization": 4.0}, 4.0)
    assert not same_mechanism(want, 0.8, step, None)
    # a module that no longer departs (A1: prediction, the car forecast static again) ...
    a1 = {"control": 3.0, "planning": 3.0, "prediction": 0.4, "canbus": 3.1}
    assert not same_mechanism(a1, 3.0, {m: t for m, t in a1.items() if m != "prediction"}, 3.0)
    # ... unless it departed only after the commands (A4: the ego's pose)
    a4 = {"control": 0.6, "planning": 0.6, "prediction": 0.6, "canbus": 0.7,
          "perception": 0.7, "localization": 1.4}
    shrunk = {"control": 6.6, "planning": 6.6, "prediction": 6.6, "canbus": 6.7, "perception": 6.7}
    assert same_mechanism(a4, 0.6, shrunk, 6.6)
    assert not same_mechanism(a4, None, shrunk, 6.6)


def test_a_shrink_step_keeps_the_modules_that_led_the_commands_ahead_of_them():
    """Catalog A1 and a generated A1 variant (other speeds, seed 313): lifted by +1.03 m/s the
    creeping car is forecast as moving, and prediction and planning depart at 0.5 s, 2.5 s
    before the commands. Shrunk to +0.26 m/s prediction still departs first (0.7 s): the same
    mechanism. Shrunk to +0.15 m/s (0.45 m/s, under the still-obstacle speed) it departs only
    after the commands (3.2 s): the accident is avoided by timing, another mechanism. A4's
    prediction departs one bin before the commands: that is no lead."""
    from rocas.pipeline.physical_phase import same_mechanism

    lifted = {"canbus": 3.1, "control": 3.0, "localization": 3.2, "perception": 3.2,
              "planning": 0.5, "prediction": 0.5}
    catalog_step = {**lifted, "planning": 3.0, "prediction": 0.7}
    timing_step = {**lifted, "planning": 3.0, "prediction": 3.2}
    assert same_mechanism(lifted, 3.0, catalog_step, 3.0, 0.1)
    assert not same_mechanism(lifted, 3.0, timing_step, 3.0, 0.1)
    a4 = {"control": 0.6, "planning": 0.6, "prediction": 0.5, "canbus": 0.7}
    assert same_mechanism(a4, 0.6, {**a4, "prediction": 6.6}, 0.6, 0.1)
    assert not same_mechanism({**a4, "prediction": 0.4}, 0.6, {**a4, "prediction": 6.6}, 0.6, 0.1)


def test_an_emergency_the_accident_had_long_before_it_does_not_count_against_a_reference():
    """A7 laid out with the ego stopping close behind a long truck: its control raises an estop
    at 0.25 s in every world, and the car behind hits it at 7.35 s. A world in which the car
    behind stops short has the same estop at 0.25 s and no collision: a reference. An estop at
    another time, one the accident did not have, or one within Algorithm 1's window before
    the accident (part of it) still counts."""
    from rocas.pipeline.physical_phase import reference_violation, without_prior_emergencies
    from rocas.sim.oracles import Outcome

    fields = {f.name: None for f in dataclasses.fields(Outcome)}
    base = fields | {"collided": False, "hard_brake": False, "unexpected_stop": False,
                     "max_decel_mps2": 0.8, "min_separation_m": 4.0}
    accident = Outcome(**(base | {"collided": True, "collision_time_s": 7.35, "estop": True,
                                  "estop_time_s": 0.25, "emergency": True,
                                  "min_separation_m": -2.2}))
    stopped_short = Outcome(**(base | {"estop": True, "estop_time_s": 0.25, "emergency": True}))
    drives = np.stack([np.linspace(0.0, 20.0, 21), np.zeros(21)], axis=1)
    ref = VariantResult(stopped_short, drives, np.zeros((21, 0, 2)))
    assert reference_violation(ref, 10.0) >= 1.0  # without the accident's outcome: an emergency
    assert reference_violation(ref, 10.0, accident, 7.35 - 3.0, 0.05) <= 0
    cleared = without_prior_emergencies(stopped_short, accident, 4.35, 0.025)
    assert not cleared.emergency and not cleared.estop and cleared.estop_time_s is None
    other_time = dataclasses.replace(stopped_short, estop_time_s=3.0)
    assert without_prior_emergencies(other_time, accident, 4.35, 0.025).emergency
    assert without_prior_emergencies(stopped_short, accident, 0.2, 0.025).emergency  # in the window
    hard = dataclasses.replace(stopped_short, hard_brake=True, hard_brake_time_s=0.25)
    assert without_prior_emergencies(hard, accident, 4.35, 0.025).hard_brake  # the accident had none
    crash = VariantResult(accident, drives, np.zeros((21, 0, 2)))
    assert reference_violation(crash, 10.0, accident, 4.35, 0.05) > 1.0
