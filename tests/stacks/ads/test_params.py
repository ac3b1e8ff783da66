import pickle

import pytest

from rocas.errors import ScenarioError
from rocas.stacks.ads.params import MODULES, PARAMETERS, parameters
from rocas.stacks.base import StackParams, batch_params
from rocas.stacks.base import parse_assignment as parse_any

SPECS = tuple(parameters())


def ParamSet(overrides=None):  # noqa: N802 - the ADS's full assignment, as the rollout makes it
    return StackParams(SPECS, overrides)


def parse_assignment(text):
    return parse_any(text, SPECS)


def test_inventory_is_large_and_well_formed():
    assert len(PARAMETERS) >= 120
    for name, p in PARAMETERS.items():
        assert name == f"{p.module}.{p.name}" and p.module in MODULES
        assert p.low <= p.default <= p.high and p.low < p.high
        assert p.description and p.unit is not None
    assert {p.module for p in parameters()} == set(MODULES)
    assert all(p.module == "control" for p in parameters("control"))


def test_paper_parameters_exist():
    for name in ("perception.brake_threshold", "prediction.still_obstacle_speed_mps",
                 "prediction.cyclist_cut_in_lateral_m", "planning.static_obstacle_lateral_buffer_m",
                 "planning.lateral_safety_buffer_m", "planning.use_path_tangent_heading",
                 "planning.yield_distance_m", "planning.min_overtake_distance_m",
                 "planning.overtake_time_buffer_s", "planning.collision_check_moving_m"):
        assert name in PARAMETERS


def test_paramset_is_an_immutable_hashable_mapping():
    a = ParamSet({"planning.yield_distance_m": 3.0})
    assert a["planning.yield_distance_m"] == 3.0
    assert a["control.speed_kp"] == PARAMETERS["control.speed_kp"].default
    assert len(a) == len(PARAMETERS)
    assert a.overrides() == {"planning.yield_distance_m": 3.0}
    assert pickle.loads(pickle.dumps(a)) == a and hash(a) == hash(ParamSet(a.overrides()))
    b = a.with_values({"control.speed_kp": 1.0})
    assert b.overrides() == {"planning.yield_distance_m": 3.0, "control.speed_kp": 1.0}
    stacked = batch_params([a, b])
    assert stacked["control.speed_kp"].tolist() == [PARAMETERS["control.speed_kp"].default, 1.0]


@pytest.mark.parametrize(("text", "match"), [
    ("planning.nope=1", "unknown parameter"),
    ("planning.yield_distance_m=abc", "not a number"),
    ("planning.yield_distance_m=99", "out of range"),
    ("perception.track_min_hits=2.5", "integer"),
    ("planning.yield_distance_m", "module.param=value"),
])
def test_bad_assignments(text, match):
    with pytest.raises(ScenarioError, match=match):
        parse_assignment(text)


def test_good_assignment():
    assert parse_assignment("planning.use_path_tangent_heading=false") == (
        "planning.use_path_tangent_heading", 0.0)
    assert parse_assignment(" planning.yield_distance_m = 2.5") == (
        "planning.yield_distance_m", 2.5)


def test_every_parameter_is_read_by_some_module():
    # a parameter that no code reads would be searched, reported and "fixed" without effect;
    # the modules read parameters by their short name (p["name"] or params.module.name)
    import re
    from pathlib import Path

    import rocas
    from rocas.stacks.ads.params import PARAMETERS

    root = Path(rocas.__file__).parent
    code = "\n".join(f.read_text() for f in root.rglob("*.py")
                     if f.name != "params.py" and not f.name.endswith("_pb2.py"))
    unread = [n for n in PARAMETERS
              if not re.search(r"""["']%s["']|\.%s\b""" % ((re.escape(n.split(".", 1)[1]),) * 2), code)]
    assert unread == []
