"""Accidents grouped by root cause, and how well the groups match the documented answers.

A root cause is read from an analysis's report (:func:`root_cause_keys`):

- ``misconfiguration``: the deviating module and the misconfigured parameter(s), each with the
  direction of its fix (``planning: planning.min_overtake_distance_m up``);
- ``no_configuration_fix``: the deviating module and the kind of trigger, the triggering
  entity's kind (``perception: no configuration fix; trigger vegetation``): a missing feature
  shows itself through what sets it off. Not the property the reference changed: that is the
  physical search's choice among the worlds that avoid the accident (the car that rear-ends
  the stopped ego slowed in one analysis, moved aside in another), not a property of the
  accident, and splitting by it made one mechanism two groups;
- ``no_reference`` and ``not_reproduced``: the verdict alone.

A misconfiguration has more than one name when the analysis found nearly-as-small fixes
(the report's ``alternatives``): the same margin through another term, as
``min_overtake_distance_m`` and ``overtake_time_buffer_s`` of one overtaking decision. Those
that move their parameters the same way as the chosen fix name the same root cause, and
:func:`group_accidents` puts an accident into the group of the name most accidents share
(a greedy cover: the name shared by most ungrouped accidents first, ties to the name that is
most often the chosen fix, then alphabetical), so one misconfiguration reached through two
terms stays one group. An alternative that moves a parameter the other way (letting the ego
race ahead instead of yielding) is another root cause and never joins.

Scores against the documented answers (each accident's catalog type, where known):

- completeness: per type, the share of its accidents in its largest group (overall: accidents
  in their type's largest group over accidents with a known type);
- purity: per group, the share of its accidents of its most common type (overall: weighted by
  group size);
- documented: whether a group's root cause is the documented one of its most common type
  (:func:`documented_keys`: the module, and for a fixable type a documented fix's parameter
  moved the way that fix moves it), counted over groups, and over accidents whose group's root
  cause is their own type's documented one. Purity counts types; this counts right answers.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from typing import Any

VERDICTS_BY_CAUSE = ("misconfiguration", "no_configuration_fix")


def _direction(item: dict[str, Any]) -> str:
    try:
        delta = float(item["mutated"]) - float(item["original"])
    except (TypeError, ValueError):
        return "changed"  # a boolean or an enumeration
    return "up" if delta > 0 else "down" if delta < 0 else "unchanged"


def fix_key(module: str | None, misconfiguration: Sequence[dict[str, Any]]) -> str:
    """The root cause of a misconfiguration: module and parameter(s) with directions."""
    changes = sorted(f"{m['parameter']} {_direction(m)}" for m in misconfiguration)
    return f"{module}: {', '.join(changes)}"


def _directions(misconfiguration: Sequence[dict[str, Any]]) -> set[str]:
    return {_direction(m) for m in misconfiguration}


def trigger_kind(report: dict[str, Any]) -> str:
    """The kind of trigger: the triggering entity's kind, e.g. "vehicle" (see the module
    docstring for why not the property the reference changed)."""
    trig = report.get("triggering_entity") or {}
    return trig.get("kind") or "unknown"


def _named_fixes(report: dict[str, Any]) -> list[tuple[str, Sequence[dict[str, Any]]]]:
    """A misconfiguration's names (see :func:`root_cause_keys`), each with its changes."""
    module = report.get("deviating_module")
    chosen = report["misconfiguration"]
    named = [(fix_key(module, chosen), chosen)]
    for alt in report.get("alternatives") or []:
        mis = alt.get("misconfiguration") or []
        if mis and _directions(mis) == _directions(chosen):
            key = fix_key(module, mis)
            if key not in [k for k, _ in named]:
                named.append((key, mis))
    return named


def root_cause_keys(report: dict[str, Any]) -> list[str]:
    """The report's root cause, then the other names of the same root cause (nearly-as-small
    fixes moving their parameters the same way); see the module docstring."""
    verdict = report["verdict"]
    module = report.get("deviating_module")
    if verdict == "misconfiguration" and report.get("misconfiguration"):
        return [k for k, _ in _named_fixes(report)]
    if verdict == "no_configuration_fix":
        return [f"{module}: no configuration fix; trigger {trigger_kind(report)}"]
    return [verdict.replace("_", " ")]


def _moves_a_fix_its_way(changes: Sequence[dict[str, Any]], fixes: Sequence[Mapping[str, float]]) -> bool:
    """Whether some change moves a documented fix's parameter the way that fix moves it from
    the same original value (as ``rocas bench`` scores a parameter)."""
    for ch in changes:
        try:
            original, delta = float(ch["original"]), float(ch["mutated"]) - float(ch["original"])
        except (TypeError, ValueError):
            continue
        if any(ch["parameter"] in f and delta * (float(f[ch["parameter"]]) - original) > 0 for f in fixes):
            return True
    return False


def documented_keys(report: dict[str, Any], module: str, fixes: Sequence[Mapping[str, float]]) -> list[str]:
    """The names among :func:`root_cause_keys` that are the documented root cause: the
    documented module, and for a fixable type (``fixes`` not empty) a documented fix's
    parameter moved that fix's way; for an unfixable one the verdict ``no_configuration_fix``.

    Args:
        report: the analysis's report.
        module: the documented responsible module.
        fixes: every documented fix (``GroundTruth.fixes``; empty when none exists).
    """
    if report.get("deviating_module") != module:
        return []
    if not fixes:
        return root_cause_keys(report) if report["verdict"] == "no_configuration_fix" else []
    if report["verdict"] != "misconfiguration" or not report.get("misconfiguration"):
        return []
    return [k for k, mis in _named_fixes(report) if _moves_a_fix_its_way(mis, fixes)]


def group_accidents(names: Sequence[str], keys: dict[str, list[str]]) -> list[dict[str, Any]]:
    """Groups of accidents by root cause (see the module docstring), largest first.

    Args:
        names: the analysed accidents.
        keys: per accident, its root cause names (the chosen one first).

    Returns:
        ``[{"root_cause": key, "accidents": [names], "by_alternative": [names]}]``:
        ``by_alternative`` are the accidents placed by a nearly-as-small fix's name.
    """
    chosen = Counter(keys[n][0] for n in names)
    left = list(names)
    groups = []
    while left:
        shared = Counter(k for n in left for k in keys[n])
        best = min(shared, key=lambda k: (-shared[k], -chosen[k], k))
        members = [n for n in left if best in keys[n]]
        groups.append({"root_cause": best, "accidents": members,
                       "by_alternative": [n for n in members if keys[n][0] != best]})
        left = [n for n in left if best not in keys[n]]
    groups.sort(key=lambda g: (-len(g["accidents"]), g["root_cause"]))
    return groups


def scores(groups: Sequence[dict[str, Any]], truth: dict[str, str | None],
           documented: dict[str, list[str]] | None = None) -> dict[str, Any] | None:
    """Completeness, purity and documented root causes against the documented types (see the
    module docstring); None when no grouped accident has a known type.

    Args:
        groups: as :func:`group_accidents` returns them.
        truth: per accident, its documented type or None.
        documented: per accident, its :func:`documented_keys` (missing: none known); without
            it the documented figures are left out.
    """
    known = [(g["root_cause"], n, truth[n]) for g in groups for n in g["accidents"] if truth.get(n)]
    if not known:
        return None
    per_type: dict[str, Counter[str]] = {}
    per_group: dict[str, Counter[str]] = {}
    for cause, _, t in known:
        per_type.setdefault(t, Counter())[cause] += 1  # type: ignore[index]
        per_group.setdefault(cause, Counter())[t] += 1  # type: ignore[index]
    types = {t: {"accidents": sum(c.values()), "largest_group": c.most_common(1)[0][0],
                 "in_largest": c.most_common(1)[0][1],
                 "completeness": c.most_common(1)[0][1] / sum(c.values()),
                 "groups": len(c)} for t, c in sorted(per_type.items(), key=lambda kv: _type_order(kv[0]))}
    grps = {g: {"accidents": sum(c.values()), "main_type": c.most_common(1)[0][0],
                "of_main_type": c.most_common(1)[0][1],
                "purity": c.most_common(1)[0][1] / sum(c.values()),
                "types": dict(sorted(c.items(), key=lambda kv: _type_order(kv[0])))}
            for g, c in per_group.items()}
    n = len(known)
    out = {"accidents_with_truth": n,
           "completeness": sum(t["in_largest"] for t in types.values()) / n,
           "purity": sum(g["of_main_type"] for g in grps.values()) / n,
           "worst_completeness": min(t["completeness"] for t in types.values()),
           "worst_purity": min(g["purity"] for g in grps.values()),
           "types": types, "groups": grps}
    if documented is not None:
        # a key's being documented depends on the type alone: any accident of the main type says
        for key, g in grps.items():
            g["documented"] = any(key in documented.get(name, []) for cause, name, t in known
                                  if cause == key and t == g["main_type"])
        right = sum(cause in documented.get(name, []) for cause, name, _ in known)
        out.update(groups_documented=sum(g["documented"] for g in grps.values()),
                   groups_with_truth=len(grps), accidents_documented=right,
                   documented_share=right / n)
    return out


def _type_order(t: str) -> tuple[int, str]:
    return (int(t[1:]), t) if t[:1] == "A" and t[1:].isdigit() else (10**6, t)
