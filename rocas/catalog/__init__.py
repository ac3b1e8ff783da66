"""The accident catalog: twelve scenarios modelled on the paper's accident types A1-A12.

Each stack's catalog is the folder of this package its stack declares (``Stack.catalog``; the
built-in ADS's ``ads/a01_*.toml`` ... ``ads/a12_*.toml``), each entry a scenario TOML file in the
ordinary scenario format plus one extra table, ``[ground_truth]``, that states the known answer:
the triggering entity and property (and a mutation of it that avoids the accident), the
responsible module, the parameter(s) and values that avoid it (or that no configuration fix
exists), and what ``rocas diff`` finds between the accident and the physically mutated run.

```python
from rocas.catalog import entries, entry
e = entry("A9")
e.scenario            # the Scenario (defaults of the ADS: the accident)
e.truth.fix           # {"perception.brake_threshold": 0.99}
e.reference_scenario  # the triggering property mutated: no accident
```

Another registered stack has its own catalog in the folder it declares (``lav/l01_*.toml``
... for the LAV-like stack): ``entries(stack="lav")``, ``entry("L1", stack="lav")``. Its ground
truth names that stack's modules and parameters, and its scenarios name the stack (``[ego]
stack``).

Instances (:func:`generate_instances`) are seeded variants of an entry (positions, speeds,
timing and weather jittered) that still crash, and that a documented fix still repairs: the
ground truth holds for them as it does for the entry.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from rocas.errors import ScenarioError, UsageError
from rocas.rollout import check_params
from rocas.scenarios.loader import scenario_from_dict, scenario_to_dict
from rocas.scenarios.model import DEFAULT_STACK, Scenario
from rocas.stacks.registry import get_stack

CONSEQUENCES = ("collision", "emergency")
#: a documented fix may move the ego by at most this much (RMSE [m]) before the accident...
PRE_ACCIDENT_RMSE_M = 0.5
#: ...over [0, t_accident - this] [s]
PRE_ACCIDENT_MARGIN_S = 3.0
_ENTITY_KEYS = {"actor": "actors", "object": "objects", "area": "areas",
                "traffic_light": "traffic_lights"}
_TRUTH_KEYS = {"id", "title", "paper", "consequence", "collision_with", "situation", "module",
               "trigger_entity", "trigger_property", "reference", "parameters", "fix",
               "alternatives", "fix_note", "fixable", "no_fix_reason", "override", "diff_module",
               "diff_change_s", "diff_note", "jitter", "replayed_id"}


@dataclass(frozen=True)
class GroundTruth:
    """The known answer of one catalog entry.

    Attributes:
        id: type id, "A1" ... "A12".
        title: one line.
        paper: the paper's description of the type (Table 4).
        consequence: "collision" or "emergency" (emergency braking) with the defaults.
        collision_with: the entity the ego hits (collisions only).
        situation: driving situation (intersection, following, merging, turning).
        module: the responsible module.
        trigger_entity: id of the triggering entity; trigger_property: its property.
        reference: the physical mutation that avoids the accident, ``{"actor": id, field: v}``
            (or ``object``/``area``/``traffic_light``) in the scenario file's terms.
        parameters: the responsible module's parameter(s) (``module.name``).
        fix: parameter values that avoid the accident ({} when none exists).
        alternatives: other fixes of the same misconfiguration, each through other
            parameters of ``parameters`` (e.g. the two terms of one decision margin); each
            alone avoids the accident and keeps the ego's earlier trajectory, like ``fix``.
        fixable: whether a configuration fix exists.
        no_fix_reason: why not (unfixable entries).
        override: scenario-specific ADS overrides and why ("" when the defaults are used).
        diff_module: the first deviating module ``rocas diff`` names between the accident
            recording and the physically mutated reference; diff_change_s: its change time [s].
        jitter: instance generation ranges (see :func:`generate_instances`).
        replayed_id: the id a replay of the entry's recording gives the trigger entity, when
            the stack's channels determine it (lav's pnp numbers its agents in the world's
            actor order, so its first actor replays as ``obstacle_1``); None when they do not
            (the built-in ADS's tracker numbers tracks as they appear).
    """

    id: str
    title: str
    paper: str
    consequence: str
    collision_with: str | None
    situation: str
    module: str
    trigger_entity: str
    trigger_property: str
    reference: Mapping[str, Any]
    parameters: tuple[str, ...]
    fix: Mapping[str, float]
    alternatives: tuple[Mapping[str, float], ...]
    fix_note: str
    fixable: bool
    no_fix_reason: str
    override: str
    diff_module: str
    diff_change_s: float | None
    diff_note: str
    jitter: Mapping[str, Any]
    replayed_id: str | None = None

    @property
    def fixes(self) -> tuple[Mapping[str, float], ...]:
        """Every documented fix: ``fix`` first, then the alternatives (empty when unfixable)."""
        return (self.fix, *self.alternatives) if self.fixable else ()


@dataclass(frozen=True)
class CatalogEntry:
    """One accident type: its scenario (the accident with the defaults) and ground truth."""

    key: str
    scenario: Scenario
    truth: GroundTruth
    document: Mapping[str, Any]

    @property
    def id(self) -> str:
        return self.truth.id

    @property
    def reference_scenario(self) -> Scenario:
        """The scenario with the triggering property mutated (the accident is avoided)."""
        return mutate(self.document, self.truth.reference, f"catalog/{self.key}.toml",
                      name_suffix="_reference")


def _fail(source: str, key: str, reason: str) -> ScenarioError:
    return ScenarioError(f"{source}: ground_truth.{key}: {reason}")


def _inventory(stack: str) -> tuple[tuple[str, ...], set[str]]:
    """The modules a ground truth may name and the parameters it may set: the stack's."""
    st = get_stack(stack)
    return tuple(st.modules), {p.full_name for p in st.parameters}


def _truth(data: Mapping[str, Any], source: str, stack: str = DEFAULT_STACK) -> GroundTruth:
    unknown = set(data) - _TRUTH_KEYS
    if unknown:
        raise _fail(source, sorted(unknown)[0], "unknown key")
    for key in ("id", "title", "consequence", "module", "trigger_entity", "trigger_property",
                "reference", "parameters", "diff_module"):
        if key not in data:
            raise _fail(source, key, "missing")
    if data["consequence"] not in CONSEQUENCES:
        raise _fail(source, "consequence", f"expected one of {CONSEQUENCES}")
    modules, names = _inventory(stack)
    if data["module"] not in modules:
        raise _fail(source, "module", f"expected one of {modules}")
    what = f"parameter of stack {stack!r}"
    for name in list(data["parameters"]) + list(data.get("fix", {})):
        if name not in names:
            raise _fail(source, "parameters", f"unknown {what} {name!r}")
        if not name.startswith(data["module"] + "."):
            raise _fail(source, "parameters", f"{name} is not a {data['module']} parameter")
    fixable = bool(data.get("fixable", True))
    if fixable != bool(data.get("fix")):
        raise _fail(source, "fix", "a fixable entry needs fix values, an unfixable one none")
    alternatives = data.get("alternatives", [])
    if not isinstance(alternatives, list) or not all(
            isinstance(a, dict) and a for a in alternatives):
        raise _fail(source, "alternatives", "expected a list of non-empty tables")
    for alt in alternatives:
        for name in alt:
            if name not in data["parameters"]:
                raise _fail(source, "alternatives", f"{name} is not listed in parameters")
    if alternatives and not fixable:
        raise _fail(source, "alternatives", "an unfixable entry has no alternative fixes")
    return GroundTruth(
        id=data["id"], title=data["title"], paper=data.get("paper", ""),
        consequence=data["consequence"], collision_with=data.get("collision_with"),
        situation=data.get("situation", ""), module=data["module"],
        trigger_entity=data["trigger_entity"], trigger_property=data["trigger_property"],
        reference=dict(data["reference"]), parameters=tuple(data["parameters"]),
        fix={k: float(v) for k, v in data.get("fix", {}).items()},
        alternatives=tuple({k: float(v) for k, v in a.items()} for a in alternatives),
        fix_note=data.get("fix_note", ""), fixable=fixable,
        no_fix_reason=data.get("no_fix_reason", ""), override=data.get("override", ""),
        diff_module=data["diff_module"], diff_change_s=data.get("diff_change_s"),
        diff_note=data.get("diff_note", ""), jitter=dict(data.get("jitter", {})),
        replayed_id=data.get("replayed_id"),
    )


def mutate(document: Mapping[str, Any], change: Mapping[str, Any], source: str,
           name_suffix: str = "") -> Scenario:
    """The scenario of ``document`` with one entity's fields replaced.

    ``change`` names the entity by kind (``actor``, ``object``, ``area``, ``traffic_light``)
    and gives the new field values in the file format, e.g. ``{"actor": "red_truck",
    "color": "white"}``; the result is validated like any scenario file.
    """
    doc = copy.deepcopy(dict(document))
    kinds = [k for k in _ENTITY_KEYS if k in change]
    if len(kinds) != 1:
        raise UsageError(f"{source}: a mutation names exactly one entity (got {kinds})")
    kind = kinds[0]
    ident = change[kind]
    items = doc.get(_ENTITY_KEYS[kind], [])
    for item in items:
        if item.get("id") == ident:
            for field, value in change.items():
                if field == kind:
                    continue
                if field == "speed_mps":
                    item.pop("speed_profile", None)
                if field == "speed_profile":
                    item.pop("speed_mps", None)
                item[field] = value
            break
    else:
        raise UsageError(f"{source}: no {kind} {ident!r} to mutate")
    if name_suffix:
        doc["scenario"] = {**doc["scenario"], "name": doc["scenario"]["name"] + name_suffix}
    return scenario_from_dict(doc, source=source)


def _root(stack: str = DEFAULT_STACK):  # noqa: ANN202
    """The folder of this package holding ``stack``'s catalog (what the stack declares)."""
    return resources.files("rocas.catalog") / _folder(stack)


def _folder(stack: str) -> str:
    folder = getattr(get_stack(stack), "catalog", None)
    if not folder:
        raise UsageError(f"stack {stack!r} has no accident catalog",
                         "catalogs exist for: " + ", ".join(stacks_with_catalog()))
    return str(folder)


def _is_entry_file(name: str) -> bool:
    """``a01_x.toml``, ``l01_x.toml``: a letter, two digits, an underscore."""
    return name.endswith(".toml") and len(name) > 4 and name[0].isalpha() and \
        name[1:3].isdigit() and name[3] == "_"


@cache
def _load_all(stack: str = DEFAULT_STACK) -> tuple[CatalogEntry, ...]:
    root = _root(stack)
    if not root.is_dir():
        raise UsageError(f"stack {stack!r} has no accident catalog",
                         "catalogs exist for: " + ", ".join(stacks_with_catalog()))
    prefix = f"catalog/{_folder(stack)}/"
    out = []
    for f in sorted(root.iterdir(), key=lambda p: p.name):
        if not _is_entry_file(f.name):
            continue
        e = entry_from_document(tomllib.loads(f.read_text(encoding="utf-8")),
                                key=f.name[:-5], source=prefix + f.name, stack=stack)
        if e.scenario.ego.stack != stack:
            raise ScenarioError(f"{prefix}{f.name}: ego.stack: expected {stack!r} (the "
                                f"catalog's stack), got {e.scenario.ego.stack!r}")
        out.append(e)
    return tuple(out)


def shipped_recordings(stack: str = DEFAULT_STACK) -> Path:
    """Where the repository keeps the recordings of ``stack``'s catalog (``recordings/`` and
    the subfolder the stack declares as ``recordings``)."""
    return Path("recordings") / str(getattr(get_stack(stack), "recordings", stack))


def stacks_with_catalog() -> tuple[str, ...]:
    """The registered stacks that declare an accident catalog (the default stack first)."""
    from rocas.stacks.registry import names

    have = [n for n in names() if getattr(get_stack(n), "catalog", None)]
    return tuple(sorted(have, key=lambda n: (n != DEFAULT_STACK, n)))


def entry_from_document(data: Mapping[str, Any], key: str, source: str,
                        stack: str = DEFAULT_STACK) -> CatalogEntry:
    """A catalog entry from a parsed catalog-format document (a scenario plus its
    ``[ground_truth]`` table): the shipped entries and generated variants' files alike."""
    data = dict(data)
    truth_doc = data.pop("ground_truth", None)
    if not isinstance(truth_doc, Mapping):
        raise ScenarioError(f"{source}: no [ground_truth] table")
    scenario = check_params(scenario_from_dict(data, source=source), source)
    return CatalogEntry(key=key, scenario=scenario, truth=_truth(truth_doc, source, stack),
                        document=data)


def entries(stack: str = DEFAULT_STACK) -> tuple[CatalogEntry, ...]:
    """All catalog entries of ``stack``'s catalog, in type order (A1 or L1 first)."""
    return tuple(sorted(_load_all(stack), key=lambda e: int(e.id[1:])))


def entry(type_id: str, stack: str = DEFAULT_STACK) -> CatalogEntry:
    """One entry by type id ("A9", "a9", "a09") or file stem."""
    want = type_id.lower()
    for e in entries(stack):
        if want in (e.id.lower(), e.key, e.key.split("_", 1)[0]) or (
                want[:1] == e.id[:1].lower() and want[1:].isdigit()
                and int(want[1:]) == int(e.id[1:])):
            return e
    raise UsageError(f"no catalog entry {type_id!r} for stack {stack!r}",
                     f"available: {', '.join(e.id for e in entries(stack))}")


def accident_matches(truth: GroundTruth, outcome: Any) -> bool:
    """Whether a run's outcome is the entry's documented accident."""
    if truth.consequence == "collision":
        return bool(outcome.collided) and (truth.collision_with is None
                                           or outcome.collision_with == truth.collision_with)
    return bool(outcome.emergency) and not outcome.collided


def accident_time(outcome: Any) -> float | None:
    """Time of the accident [s]: the collision, else the first emergency sign."""
    if outcome.collided:
        return outcome.collision_time_s
    times = [t for t in (outcome.hard_brake_time_s, outcome.estop_time_s) if t is not None]
    return min(times) if times else None


# --- instances ---------------------------------------------------------------------------------

def _jittered(e: CatalogEntry, rng: np.random.Generator) -> Scenario:
    """One random variant of the entry: the actors' start positions and speeds, the timing
    (a common time shift of speed profiles) and the weather are jittered within the entry's
    ``jitter`` ranges (defaults below)."""
    j = {"position_m": 1.0, "speed_rel": 0.04, "time_s": 0.2, "weather": 5.0,
         "actors": None, **e.truth.jitter}
    doc = scenario_to_dict(e.scenario)
    chosen = j["actors"]
    for a in doc["actors"]:
        if chosen is not None and a["id"] not in chosen:
            continue
        if a.get("route"):
            a["start_s_m"] = max(0.0, a["start_s_m"] + rng.uniform(-1, 1) * j["position_m"])
        else:
            dx, dy = rng.uniform(-1, 1, 2) * j["position_m"] * 0.5
            a["waypoints"] = [[p[0] + dx, p[1] + dy] for p in a["waypoints"]]
        scale = 1.0 + rng.uniform(-1, 1) * j["speed_rel"]
        shift = rng.uniform(-1, 1) * j["time_s"]
        knots = a["speed_profile"]
        a["speed_profile"] = [[k[0] if i == 0 else max(k[0] + shift, knots[i - 1][0] + 1e-3),
                               k[1] * scale] for i, k in enumerate(knots)]
    w = doc["weather"]
    for name in ("cloudiness", "precipitation", "fog_density"):
        if w[name] > 0 or name == "cloudiness":
            w[name] = float(np.clip(w[name] + rng.uniform(-1, 1) * j["weather"], 0.0, 100.0))
    return scenario_from_dict(doc, source=f"catalog/{e.key}.toml (instance)")


@dataclass(frozen=True)
class InstanceReport:
    """Instance generation of one type: how many variants were tried, how many crash as
    documented, and of those how many a documented fix still repairs (all of them for an
    unfixable entry, which has no fix to check)."""

    entry: CatalogEntry
    tried: int
    crashed: int
    fix_holds: int
    instances: tuple[tuple[int, Scenario], ...]   # (seed, scenario) of the kept variants


def fix_holds(accident: Any, accident_ego: np.ndarray, fixed: Any, fixed_ego: np.ndarray,
              times: np.ndarray) -> bool:
    """Whether a fix repairs an accident the way the catalog documents fixes: the fixed run
    (outcome ``fixed``) has neither collision nor emergency, and its ego stays within
    PRE_ACCIDENT_RMSE_M of the accident run's over [0, t_accident - PRE_ACCIDENT_MARGIN_S].

    Args:
        accident, fixed: the two runs' outcomes.
        accident_ego, fixed_ego: (T + 1, >=2) the two runs' ego positions [m].
        times: (T + 1,) sample times [s].
    """
    if fixed.collided or fixed.emergency:
        return False
    t_acc = accident_time(accident)
    if t_acc is None:
        return True
    return trajectory_rmse(accident_ego, fixed_ego, times,
                           t_acc - PRE_ACCIDENT_MARGIN_S) < PRE_ACCIDENT_RMSE_M


def generate_instances(e: CatalogEntry, count: int, *, seed: int = 0,
                       max_tries: int | None = None, batch: int = 16) -> InstanceReport:
    """Up to ``count`` seeded variants of an entry that still crash (as documented) and, for a
    fixable entry, that one of its documented fixes still repairs (:func:`fix_holds`): a
    variant the documented fix does not repair has no known misconfiguration, so scoring an
    analysis of it against the entry's would be scoring against a wrong answer.

    Variants are drawn in batches from ``numpy.random.default_rng([seed, k])`` for
    k = 0, 1, ...; each is simulated (the crashing ones again with each documented fix) and
    kept when it passes. Stops at ``count`` kept or ``max_tries`` (default ``8 * count``)
    tried.
    """
    from rocas.rollout import simulate_batch

    if count < 1:
        raise UsageError("the number of instances must be >= 1")
    max_tries = max_tries or 8 * count
    fixes = [dict(f) for f in e.truth.fixes]
    kept: list[tuple[int, Scenario]] = []
    tried = crashed = holds = 0
    k = 0
    while len(kept) < count and tried < max_tries:
        n = min(batch, max_tries - tried)
        variants = [(k + i, _jittered(e, np.random.default_rng([seed, k + i]))) for i in range(n)]
        k += n
        res = simulate_batch([v for _, v in variants], [{}] * n, [v.seed for _, v in variants])
        tried += n
        crash = [i for i, out in enumerate(res.outcomes) if accident_matches(e.truth, out)]
        crashed += len(crash)
        good = crash
        if fixes and crash:
            pairs = [(i, f) for i in crash for f in fixes]
            fixed = simulate_batch([variants[i][1] for i, _ in pairs], [f for _, f in pairs],
                                   [variants[i][1].seed for i, _ in pairs])
            ok = {i for j, (i, _) in enumerate(pairs)
                  if fix_holds(res.outcomes[i], res.ego[i], fixed.outcomes[j], fixed.ego[j], res.times)}
            good = [i for i in crash if i in ok]
        holds += len(good)
        for i in good[:count - len(kept)]:
            vseed, sc = variants[i]
            kept.append((vseed, dataclasses.replace(
                sc, name=f"{e.key}_i{vseed:03d}", description=f"{sc.description} (instance {vseed})")))
    return InstanceReport(entry=e, tried=tried, crashed=crashed, fix_holds=holds,
                          instances=tuple(kept))


def trajectory_rmse(a: np.ndarray, b: np.ndarray, times: np.ndarray, until_s: float) -> float:
    """RMSE [m] between two ego position traces (T+1, >=2) over [0, until_s]."""
    sel = times <= until_s + 1e-9
    if not sel.any():
        return 0.0
    d = a[sel, :2] - b[sel, :2]
    return math.sqrt(float(np.mean(np.sum(d * d, axis=1))))


__all__ = ["PRE_ACCIDENT_MARGIN_S", "PRE_ACCIDENT_RMSE_M", "CatalogEntry", "GroundTruth",
           "InstanceReport", "accident_matches", "accident_time", "entries", "entry",
           "entry_from_document", "fix_holds",
           "generate_instances", "mutate",
           "scenario_toml", "stacks_with_catalog", "trajectory_rmse"]



# --- writing variants back as scenario files ---------------------------------------------------

def toml_key(k: str) -> str:
    """A TOML key: bare when it can be, else quoted (a dotted name is one key, not a path)."""
    import re

    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)


def toml_value(v: Any) -> str:
    """A TOML value (inline tables and arrays included; None entries of a table are left out)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | float):
        return repr(float(v)) if isinstance(v, float) else str(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, Mapping):
        return "{ " + ", ".join(f"{toml_key(str(k))} = {toml_value(x)}" for k, x in v.items()
                                if x is not None) + " }"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def scenario_toml(scenario: Scenario) -> str:
    """The scenario as a TOML document in the scenario file format."""
    doc = scenario_to_dict(scenario)
    lines = [f"format = {doc['format']}", ""]

    def table(header: str, d: Mapping[str, Any]) -> None:
        lines.append(header)
        for k, v in d.items():
            if v is None or isinstance(v, Mapping) and header == "[ego]":
                continue
            lines.append(f"{k} = {toml_value(v)}")
        lines.append("")

    table("[scenario]", doc["scenario"])
    table("[weather]", doc["weather"])
    for key in ("lanes", "traffic_lights", "objects", "areas", "actors"):
        for item in doc[key]:
            table(f"[[{key}]]", item)
    table("[ego]", doc["ego"])
    for module, values in doc["ego"].get("params", {}).items():
        table(f"[ego.params.{module}]", values)
    return "\n".join(lines)
