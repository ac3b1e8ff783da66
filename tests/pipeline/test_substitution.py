"""The second opinion by module substitution (rocas.pipeline.substitution)."""

import pytest

from rocas.catalog import accident_matches, entries, entry
from rocas.pipeline.substitution import second_opinion
from rocas.rollout import simulate_batch
from rocas.stacks.ads.oracle import SUBSTITUTABLE


@pytest.fixture(scope="module")
def a10():
    return second_opinion(entry("A10").scenario)


def test_the_baseline_is_the_accident_as_simulated(a10):
    e = entry("A10")
    op = a10
    assert op.baseline == simulate_batch(e.scenario).outcomes[0]
    assert accident_matches(e.truth, op.baseline)
    assert [r.modules for r in op.runs] == [("perception",), ("prediction",),
                                            ("perception", "prediction")]


def test_ground_truth_perception_removes_a_misread_light(a10):
    op = a10
    assert op.module == "perception"
    assert op.run("perception").avoided and not op.run("prediction").avoided
    assert op.cleared == ("prediction",)
    assert op.stance("perception") == "agrees"
    assert op.stance("planning") == "disagrees"


def test_ground_truth_prediction_removes_a_predicted_cut_in():
    op = second_opinion(entry("A12").scenario)
    assert op.module == "prediction"
    assert op.cleared == ("perception",)
    assert "perception ground truth does not" in op.reason


def test_upstream_ground_truth_that_leaves_the_accident_points_downstream():
    op = second_opinion(entry("A2").scenario)
    assert op.accident and op.module is None
    assert op.cleared == SUBSTITUTABLE and not op.jointly_avoided
    assert "downstream" in op.reason
    assert op.stance("planning") == "consistent"
    assert op.stance("perception") == "disagrees"
    assert op.to_dict()["runs"][0]["substituted"] == ["perception"]


def test_a_fixed_run_has_nothing_to_explain():
    e = entry("A10")
    op = second_opinion(e.scenario, dict(e.truth.fix))
    assert not op.accident and op.module is None
    assert op.stance("perception") == "undetermined"


@pytest.mark.slow
def test_ground_truth_perception_removes_the_red_truck_misread_as_braking():
    op = second_opinion(entry("A9").scenario)
    assert op.module == "perception"
    assert op.run("perception").avoided


#: What substitution says on each catalog entry (docs/algorithms.md explains each
#: disagreement with the documented module; the catalog is not tuned to agree).
CATALOG_OPINIONS = {
    "A1": "prediction", "A2": None, "A3": "prediction", "A4": "prediction", "A5": None,
    "A6": "prediction", "A7": None, "A8": None, "A9": "perception", "A10": "perception",
    "A11": "prediction", "A12": "prediction",
}


@pytest.mark.slow
@pytest.mark.parametrize("type_id", sorted(CATALOG_OPINIONS, key=lambda k: int(k[1:])))
def test_catalog_opinions(type_id):
    e = entry(type_id)
    op = second_opinion(e.scenario)
    assert accident_matches(e.truth, op.baseline)
    assert op.module == CATALOG_OPINIONS[type_id]


def test_every_catalog_entry_has_an_expected_opinion():
    assert set(CATALOG_OPINIONS) == {e.id for e in entries()}
