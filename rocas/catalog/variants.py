"""Structurally different variants of the catalog's accidents, checked by re-simulation.

A *family* says what a variant changes (:data:`FAMILIES`):

- ``jitter``: the entry's own small ranges (:func:`rocas.catalog._jittered`).
- ``rotate``: the whole world turned by any angle about any point within
  :attr:`VariantRanges.extent_m` of the origin (a rotation about a point is also a translation).
- ``mirror``: the whole world mirrored in any line (a left-hand-traffic world: lateral offsets
  change sign; see :mod:`rocas.scenarios.transform`).
- ``speed``: the ego's speed (its start speed and the lanes' speed limits, capped at the
  planner's default cruise speed first, by one factor) and each actor's speed profile by its own
  factor.
- ``actors``: each vehicle's model and every actor's colour (never to red: red objects are what
  the brake classifier is biased to, A9's mechanism), except the trigger's documented property
  (A9's truck stays red); cyclists and pedestrians keep their kind.
- ``position``: the ego's and each actor's start along its route or path.
- ``mixed``: a rotation (or, one time in two, a mirror) plus half-range ``speed``, ``actors``
  and ``position`` changes.

A drawn variant is kept only when it still crashes with the entry's documented consequence
(and collision partner) and, for a fixable entry, a documented fix still repairs it
(:func:`rocas.catalog.fix_holds`): its ground truth is checked by re-simulation.
Variant ``k`` of family ``f`` with base seed ``s`` is drawn from
``numpy.random.default_rng([s, FAMILIES.index(f), k])``, so a set is the same on every run.

A kept variant is a catalog entry of its own (:class:`~rocas.catalog.CatalogEntry`:
scenario, ground truth with the trigger's reference mutation moved along, e.g. mirrored
waypoints or a scaled speed profile); :func:`variant_toml` writes it in the catalog format and
:func:`load_variant` reads it back.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rocas.catalog import (
    CatalogEntry,
    GroundTruth,
    _jittered,
    accident_matches,
    entry_from_document,
    fix_holds,
    mutate,
    scenario_toml,
    toml_key,
    toml_value,
)
from rocas.catalog.families import FAMILIES as FAMILY_HELP
from rocas.errors import ScenarioError, UsageError
from rocas.scenarios.loader import scenario_from_dict, scenario_to_dict
from rocas.scenarios.model import COLORS, DEFAULT_STACK, VEHICLE_MODELS, Scenario
from rocas.scenarios.transform import (
    PlaneTransform,
    transform_change,
    transform_scenario,
)

FAMILIES = tuple(FAMILY_HELP)
#: colours an actor may be given (red is left out: see the module docstring)
_SAFE_COLORS = tuple(c for c in COLORS if c != "red")


@dataclass(frozen=True)
class VariantRanges:
    """How far the families reach.

    Attributes:
        extent_m: rotation centres and mirror lines pass through points within this distance
            of the origin (per axis) [m].
        speed_rel: actors' speed factors lie in [1 - speed_rel, 1 + speed_rel].
        ego_speed: the ego's speed factor range (low, high).
        position_m: starts move by up to this along their route or path [m].
    """

    extent_m: float = 2000.0
    speed_rel: float = 0.15
    ego_speed: tuple[float, float] = (0.85, 1.1)
    position_m: float = 4.0


@dataclass(frozen=True)
class Variant:
    """One kept variant.

    Attributes:
        entry: the variant as a catalog entry (its key is the variant's name; its truth is the
            source entry's, with the reference mutation moved along with the world).
        source: the catalog entry it was made from.
        family: the family; seed: the base seed; index: the draw index.
        changes: what was drawn, for people (angles in degrees, factors, shifts).
        reference_avoids: whether the moved reference mutation avoids the accident too.
    """

    entry: CatalogEntry
    source: CatalogEntry
    family: str
    seed: int
    index: int
    changes: Mapping[str, Any]
    reference_avoids: bool

    @property
    def name(self) -> str:
        return self.entry.key

    @property
    def scenario(self) -> Scenario:
        return self.entry.scenario


@dataclass(frozen=True)
class VariantReport:
    """Variant generation of one entry and family: draws tried, draws that were not valid
    scenarios (a start beyond a path's end), draws that crash as documented, crashing draws a
    documented fix repairs, and the kept variants (at most the count asked for)."""

    entry: CatalogEntry
    family: str
    tried: int
    invalid: int
    crashed: int
    fix_holds: int
    variants: tuple[Variant, ...]


# --- drawing one variant ----------------------------------------------------------------------

def _default_cruise_mps(doc: Mapping[str, Any]) -> float:
    """The cruise speed the entry's stack plans with by default [m/s] (no cap when it has
    no such parameter): lanes faster than it are not driven faster."""
    from rocas.stacks.registry import get_stack

    stack = get_stack(doc.get("ego", {}).get("stack", DEFAULT_STACK))
    specs = {p.full_name: p for p in stack.parameters}
    cruise = specs.get("planning.cruise_speed_mps")
    return cruise.default if cruise is not None else math.inf


def _scale_profile(profile: list[list[float]], f: float) -> list[list[float]]:
    return [[k[0], min(k[1] * f, 40.0)] for k in profile]


def _speeds(doc: dict[str, Any], ref: dict[str, Any], rng: np.random.Generator,
            r: VariantRanges, reach: float, changes: dict[str, Any]) -> None:
    lo, hi = r.ego_speed
    mid = 1.0
    f_ego = float(mid + rng.uniform(lo - mid, hi - mid) * reach)
    cruise = _default_cruise_mps(doc)
    for lane in doc["lanes"]:
        lane["speed_limit_mps"] = max(min(lane["speed_limit_mps"], cruise) * f_ego, 1.0)
    doc["ego"]["start_speed_mps"] = doc["ego"]["start_speed_mps"] * f_ego
    factors = {}
    for a in doc["actors"]:
        f = float(1.0 + rng.uniform(-1.0, 1.0) * r.speed_rel * reach)
        a["speed_profile"] = _scale_profile(a["speed_profile"], f)
        factors[a["id"]] = round(f, 4)
        if ref.get("actor") == a["id"]:
            if "speed_profile" in ref:
                ref["speed_profile"] = _scale_profile([list(k) for k in ref["speed_profile"]], f)
            if "speed_mps" in ref:
                ref["speed_mps"] = min(ref["speed_mps"] * f, 40.0)
    changes.update(ego_speed_factor=round(f_ego, 4), actor_speed_factors=factors)


def _protected(truth: GroundTruth, actor_id: str, word: str) -> bool:
    """Whether ``word`` names the trigger's documented property of this actor."""
    return actor_id == truth.trigger_entity and word in truth.trigger_property


def _actors(doc: dict[str, Any], truth: GroundTruth, rng: np.random.Generator,
            changes: dict[str, Any]) -> None:
    made = {}
    for a in doc["actors"]:
        model = str(VEHICLE_MODELS[int(rng.integers(len(VEHICLE_MODELS)))])
        color = str(_SAFE_COLORS[int(rng.integers(len(_SAFE_COLORS)))])
        if a["kind"] == "vehicle" and not _protected(truth, a["id"], "model"):
            a["model"] = model
        if not _protected(truth, a["id"], "colo"):
            a["color"] = color
        made[a["id"]] = f"{a['model']} {a['color']}" if a["kind"] == "vehicle" else a["color"]
    changes["actors"] = made


def _path_length(doc: dict[str, Any], a: dict[str, Any]) -> float:
    """Length [m] of an actor's (or the ego's) route or waypoint path in a scenario document."""
    if a.get("route"):
        by_id = {ln["id"]: ln["points"] for ln in doc["lanes"]}
        polylines = [by_id[lane] for lane in a["route"]]
    else:
        polylines = [a["waypoints"]]
    return sum(math.dist(p[i], p[i + 1]) for p in polylines for i in range(len(p) - 1))


def _positions(doc: dict[str, Any], rng: np.random.Generator, r: VariantRanges, reach: float,
               changes: dict[str, Any]) -> None:
    ego = doc["ego"]
    d = float(rng.uniform(-1.0, 1.0) * r.position_m * reach)
    ego_len = _path_length(doc, {"route": ego["route"]})
    ego["start_s_m"] = min(max(ego["start_s_m"] + d, 0.0), ego_len)
    shifts = {"ego": round(d, 3)}
    for a in doc["actors"]:
        d = float(rng.uniform(-1.0, 1.0) * r.position_m * reach)
        a["start_s_m"] = min(max(a["start_s_m"] + d, 0.0), _path_length(doc, a))
        shifts[a["id"]] = round(d, 3)
    changes["start_shift_m"] = shifts


def _rigid(s: Scenario, rng: np.random.Generator, r: VariantRanges, mirror: bool
           ) -> tuple[PlaneTransform, dict[str, Any]]:
    angle = float(rng.uniform(0.0, 2.0 * math.pi))
    point = (float(rng.uniform(-r.extent_m, r.extent_m)),
             float(rng.uniform(-r.extent_m, r.extent_m)))
    if mirror:
        t = PlaneTransform.reflection(angle / 2.0, through=point)
        return t, {"mirror_axis_deg": round(math.degrees(angle / 2.0), 3),
                   "through": [round(v, 3) for v in point]}
    return PlaneTransform.rotation(angle, about=point), {
        "rotate_deg": round(math.degrees(angle), 3), "about": [round(v, 3) for v in point]}


def draw_variant(e: CatalogEntry, family: str, rng: np.random.Generator,
                 ranges: VariantRanges = VariantRanges()
                 ) -> tuple[Scenario, dict[str, Any], dict[str, Any]]:
    """One random variant of ``e`` in ``family``: (scenario, the reference mutation moved
    along, what was drawn). The scenario is validated like a file (a draw that puts a start
    beyond its path's end raises :class:`~rocas.errors.ScenarioError`)."""
    if family not in FAMILIES:
        raise UsageError(f"no variant family {family!r}", f"choose from {', '.join(FAMILIES)}")
    ref = {k: (list(v) if isinstance(v, list | tuple) else v) for k, v in e.truth.reference.items()}
    changes: dict[str, Any] = {}
    source = f"catalog/{e.key}.toml ({family} variant)"
    if family == "jitter":
        return _jittered(e, rng), ref, changes
    doc = scenario_to_dict(e.scenario)
    reach = 0.5 if family == "mixed" else 1.0
    if family in ("speed", "mixed"):
        _speeds(doc, ref, rng, ranges, reach, changes)
    if family in ("actors", "mixed"):
        _actors(doc, e.truth, rng, changes)
    if family in ("position", "mixed"):
        _positions(doc, rng, ranges, reach, changes)
    scenario = scenario_from_dict(doc, source=source)
    if family in ("rotate", "mirror", "mixed"):
        mirror = family == "mirror" or (family == "mixed" and bool(rng.integers(2)))
        t, drawn = _rigid(scenario, rng, ranges, mirror)
        changes.update(drawn)
        scenario = transform_scenario(scenario, t)
        ref = transform_change(ref, t)
    # what a file holds (angles at the format's precision): the checked scenario is the written one
    return scenario_from_dict(scenario_to_dict(scenario), source=source), ref, changes


# --- checking and keeping ----------------------------------------------------------------------

def _batch_key(s: Scenario) -> tuple[object, ...]:
    """Scenarios with equal keys can share one batch simulation (a finer key than the
    simulator's own structure test: whole entities, not only their ids)."""
    return (s.lanes, s.ego.route, s.ego.start_s_m, s.ego.destination_s_m, s.dt_s, s.duration_s,
            tuple(a.id for a in s.actors), s.objects, s.areas, s.traffic_lights)


def _simulate_groups(runs: Sequence[tuple[Scenario, Mapping[str, float] | None]]) -> list[Any]:
    """Simulate (scenario, params) runs, batching those of one structure; returns per run
    (outcome, ego trace (T + 1, 5), times (T + 1,))."""
    from rocas.rollout import simulate_batch

    groups: dict[tuple[object, ...], list[int]] = {}
    for i, (s, _) in enumerate(runs):
        groups.setdefault(_batch_key(s), []).append(i)
    out: list[Any] = [None] * len(runs)
    for idx in groups.values():
        res = simulate_batch([runs[i][0] for i in idx], params=[runs[i][1] for i in idx])
        for j, i in enumerate(idx):
            out[i] = (res.outcomes[j], res.ego[j], res.times)
    return out


def _as_entry(e: CatalogEntry, name: str, scenario: Scenario, ref: Mapping[str, Any],
              family: str, index: int) -> CatalogEntry:
    scenario = dataclasses.replace(
        scenario, name=name,
        description=f"{e.scenario.description} ({family} variant {index} of {e.id})")
    truth = dataclasses.replace(e.truth, reference=dict(ref), diff_change_s=None,
                                diff_note=f"of the catalog entry {e.key}; not measured on this "
                                          "variant")
    return CatalogEntry(key=name, scenario=scenario, truth=truth,
                        document=scenario_to_dict(scenario))


def generate_variants(e: CatalogEntry, family: str, count: int, *, seed: int = 0,
                      max_tries: int | None = None, batch: int = 8,
                      ranges: VariantRanges = VariantRanges(),
                      progress: Callable[[str], None] = lambda _: None) -> VariantReport:
    """Up to ``count`` variants of ``e`` in ``family`` that still crash as documented and that
    a documented fix still repairs (see the module docstring); tries at most ``max_tries``
    (default ``8 * count``) draws, ``batch`` at a time.

    Each draw is simulated with the defaults, with each documented fix and with the reference
    mutation moved along (one batch per world layout, so a rotated draw costs one batch).
    """
    if count < 1:
        raise UsageError("the number of variants must be >= 1")
    if family not in FAMILIES:
        raise UsageError(f"no variant family {family!r}", f"choose from {', '.join(FAMILIES)}")
    max_tries = max_tries or 8 * count
    fixes = [dict(f) for f in e.truth.fixes]
    kept: list[Variant] = []
    tried = invalid = crashed = holds = 0
    k = 0
    # a moved world is a batch of its own: draw no more of them than are still wanted
    per_world = family in ("rotate", "mirror", "mixed")
    while len(kept) < count and tried < max_tries:
        n = min(batch, max_tries - tried, count - len(kept) if per_world else batch)
        drawn = []
        for i in range(k, k + n):
            try:
                drawn.append((i, *draw_variant(e, family, np.random.default_rng(
                    [seed, FAMILIES.index(family), i]), ranges)))
            except ScenarioError:
                invalid += 1
        k += n
        tried += n
        runs: list[tuple[Scenario, Mapping[str, float] | None]] = []
        for _, sc, ref, _ in drawn:
            doc = scenario_to_dict(sc)
            runs.append((sc, None))
            runs.append((mutate(doc, ref, f"{e.key} variant reference"), None))
            runs.extend((sc, f) for f in fixes)
        progress(f"{e.id} {family}: simulating draws {k - n}-{k - 1}")
        res = _simulate_groups(runs)
        per = 2 + len(fixes)
        for j, (i, sc, ref, changes) in enumerate(drawn):
            acc, ref_run, fixed = res[j * per], res[j * per + 1], res[j * per + 2:(j + 1) * per]
            if not accident_matches(e.truth, acc[0]):
                continue
            crashed += 1
            if fixes and not any(fix_holds(acc[0], acc[1], f[0], f[1], acc[2]) for f in fixed):
                continue
            holds += 1
            if len(kept) < count:
                name = f"{e.key}__{family}_s{seed}_k{i:03d}"
                kept.append(Variant(
                    entry=_as_entry(e, name, sc, ref, family, i), source=e, family=family,
                    seed=seed, index=i, changes=changes,
                    reference_avoids=not (ref_run[0].collided or ref_run[0].emergency)))
    return VariantReport(entry=e, family=family, tried=tried, invalid=invalid, crashed=crashed,
                         fix_holds=holds, variants=tuple(kept))


# --- files ---------------------------------------------------------------------------------------

def truth_document(t: GroundTruth) -> dict[str, Any]:
    """The ``[ground_truth]`` table of a ground truth (the keys the catalog reads)."""
    d: dict[str, Any] = {
        "id": t.id, "title": t.title, "paper": t.paper, "consequence": t.consequence,
        "collision_with": t.collision_with, "situation": t.situation, "module": t.module,
        "trigger_entity": t.trigger_entity, "trigger_property": t.trigger_property,
        "reference": dict(t.reference), "parameters": list(t.parameters), "fix": dict(t.fix),
        "alternatives": [dict(a) for a in t.alternatives], "fix_note": t.fix_note,
        "fixable": t.fixable, "no_fix_reason": t.no_fix_reason, "override": t.override,
        "diff_module": t.diff_module, "diff_change_s": t.diff_change_s, "diff_note": t.diff_note,
        "jitter": dict(t.jitter)}
    return {k: v for k, v in d.items() if v is not None}


def variant_toml(v: Variant) -> str:
    """The variant as a catalog-format file: a comment saying what it is, the scenario, and its
    ``[ground_truth]`` table (so ``rocas simulate``/``analyze --scenario`` take it as they take
    a catalog entry)."""
    head = (f"# {v.family} variant {v.index} (seed {v.seed}) of catalog entry {v.source.id} "
            f"({v.source.key}): {toml_value(dict(v.changes))}\n"
            f"# kept because it crashes as documented and a documented fix repairs it "
            f"(re-simulated); the moved reference mutation "
            f"{'avoids' if v.reference_avoids else 'does NOT avoid'} it\n")
    truth = truth_document(v.entry.truth)
    lines = ["[ground_truth]"] + [f"{toml_key(k)} = {toml_value(x)}" for k, x in truth.items()]
    return head + scenario_toml(v.scenario) + "\n" + "\n".join(lines) + "\n"


def load_variant(path: str | Path) -> CatalogEntry:
    """Read a variant file written by :func:`variant_toml` (any catalog-format file)."""
    p = Path(path)
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ScenarioError(f"{p}: cannot read variant file: {exc.strerror or exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{p}: not valid TOML: {exc}") from None
    return entry_from_document(data, key=p.stem, source=str(p))


def source_entry(variant: CatalogEntry) -> CatalogEntry:
    """The catalog entry a variant was made from (by its ground truth's type id)."""
    from rocas.catalog import entry

    return entry(variant.truth.id)


__all__ = ["FAMILIES", "Variant", "VariantRanges", "VariantReport", "draw_variant",
           "generate_variants", "load_variant", "source_entry", "truth_document", "variant_toml"]
