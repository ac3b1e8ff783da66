"""Property-based tests of the scenario loader and the parameter overrides: whatever a user
writes, the answer is a valid scenario or one ScenarioError naming the file, the key and the
reason; never another exception."""

from __future__ import annotations

import copy
import math
import re
import tomllib

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rocas.catalog import entries
from rocas.errors import ScenarioError
from rocas.scenarios import example_names, load_example, scenario_from_dict, scenario_to_dict
from rocas.stacks.ads.params import PARAMETERS, parameters
from rocas.stacks.base import parse_assignment as parse_any
from rocas.stacks.base import validate_value

SOURCE = "fuzz.toml"
#: Documents mutated by the tests: every example and catalog scenario.
DOCUMENTS = [scenario_to_dict(load_example(n)) for n in example_names()] + [
    scenario_to_dict(e.scenario) for e in entries()]
SETTINGS = settings(max_examples=300, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])

scalars = st.one_of(
    st.none(), st.booleans(), st.integers(-10**6, 10**6),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=12),
)
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)),
    max_leaves=8)


def _paths(node, prefix=()):  # noqa: ANN001, ANN202
    """Every (path, value) in a nested document; a path is a tuple of keys and indices."""
    yield prefix, node
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, prefix + (i,))


def _key_text(path) -> str:  # noqa: ANN001
    """The loader's spelling of a path: ``actors[1].speed_mps``."""
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


@st.composite
def edits(draw):  # noqa: ANN001, ANN202
    """A document and one edit to it: replace a value, delete a key or add an unknown key."""
    doc = copy.deepcopy(draw(st.sampled_from(DOCUMENTS)))
    paths = [p for p, _ in _paths(doc) if p]
    path = draw(st.sampled_from(paths))
    parent = doc
    for p in path[:-1]:
        parent = parent[p]
    kind = draw(st.sampled_from(["replace", "delete", "add"]))
    if kind == "replace":
        parent[path[-1]] = draw(values)
    elif kind == "delete":
        del parent[path[-1]]
    else:
        target = parent[path[-1]] if isinstance(parent[path[-1]], dict) else parent
        if isinstance(target, dict):
            target[draw(st.text(min_size=1, max_size=8).filter(lambda k: k not in target))] = 1
    return doc, path, kind


@SETTINGS
@given(edits())
def test_an_edited_document_loads_or_is_refused_with_file_key_and_reason(case):
    doc, path, _ = case
    try:
        s = scenario_from_dict(doc, source=SOURCE)
    except ScenarioError as exc:
        msg = str(exc)
        assert msg.startswith(f"{SOURCE}: "), msg
        assert "\n" not in msg
        # "file: key: reason": a key path, then a reason
        assert re.match(rf"""{re.escape(SOURCE)}: (?:'[^']*'|"[^"]*"|[^\s:'"])+: \S""", msg), msg
        return
    # accepted: what was accepted is a scenario that survives its own round trip
    assert scenario_from_dict(scenario_to_dict(s)) == s


@SETTINGS
@given(st.sampled_from(DOCUMENTS), st.sampled_from(["actors", "objects", "lanes", "weather",
                                                    "ego", "scenario", "traffic_lights"]))
def test_a_wrong_type_for_a_whole_section_names_that_section(doc, section):
    doc = copy.deepcopy(doc)
    doc[section] = 7
    try:
        scenario_from_dict(doc, source=SOURCE)
    except ScenarioError as exc:
        assert str(exc).startswith(f"{SOURCE}: {section}"), str(exc)
    else:
        raise AssertionError(f"{section} = 7 was accepted")


@SETTINGS
@given(st.text(max_size=400))
def test_arbitrary_text_is_valid_toml_or_refused(text):
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        return  # load_scenario turns this into "not valid TOML" (tested in test_loader)
    try:
        scenario_from_dict(data, source=SOURCE)
    except ScenarioError as exc:
        assert str(exc).startswith(f"{SOURCE}: ")


names = st.one_of(st.sampled_from(sorted(PARAMETERS)), st.text(max_size=30))


@SETTINGS
@given(names, st.one_of(scalars, st.lists(scalars, max_size=2)))
def test_a_parameter_override_is_in_range_or_refused_naming_it(name, value):
    try:
        v = validate_value(PARAMETERS, name, value, source=SOURCE)
    except ScenarioError as exc:
        assert str(exc).startswith(f"{SOURCE}: {name}: "), str(exc)
        return
    p = PARAMETERS[name]
    assert math.isfinite(v) and p.low <= v <= p.high
    if p.is_integer:
        assert v == round(v)


@SETTINGS
@given(st.text(max_size=40))
def test_a_set_assignment_parses_or_is_refused_naming_it(text):
    try:
        name, v = parse_any(text, tuple(parameters()))
    except ScenarioError as exc:
        assert str(exc).startswith("--set"), str(exc)
        return
    assert name in PARAMETERS and PARAMETERS[name].low <= v <= PARAMETERS[name].high


def test_the_edit_strategy_reaches_deep_keys():
    """The documents are rich enough that edits hit actor, lane and ego fields."""
    keys = {_key_text(p) for d in DOCUMENTS for p, _ in _paths(d)}
    assert any(k.startswith("actors[") and k.endswith("speed_profile") for k in keys)
    assert any(k.startswith("lanes[") and k.endswith("points") for k in keys)
    assert "ego.route" in keys
