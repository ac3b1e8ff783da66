"""Two analyses side by side: what differs between the reports of two run directories.

``rocas compare RUN_A RUN_B`` answers "did my change to the stack (or another seed) change the
answer?": it reads each run directory's ``report.json`` (the analysis's stable output, never its
internal state) and lines up the answer (verdict, triggering entity, deviating module and walk,
confidence, misconfiguration, robust value, validation), the settings that produced it, and the
cost (seconds and simulations per phase).

A run directory comes from someone else as often as not: its report is read with a size and
depth limit and checked for the shape this module reads before anything is compared; names in
it are data (the renderers escape them).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rocas._json import rounded
from rocas._limits import load_json_file
from rocas.errors import InputError
from rocas.pipeline.report import accident_text, change, change_text
from rocas.pipeline.results import AccidentInfo

#: the fields of the answer, in the report's order; equal answers agree on all of them
ANSWER_FIELDS = ("verdict", "triggering entity", "deviating module", "misconfiguration")
#: report.json keys this module reads, with the JSON types each may hold (None: null allowed)
_SHAPE: dict[str, tuple[type | None, ...]] = {
    "verdict": (str,), "stack": (str, None), "settings": (dict, None), "accident": (dict, None),
    "triggering_entity": (dict, None), "deviating_module": (str, None), "path": (list, None),
    "confidence": (dict, None), "misconfiguration": (list,), "validation": (dict, None),
    "search_space": (dict, None), "evaluations": (dict,), "timings_s": (dict,),
}


@dataclass(frozen=True)
class FieldComparison:
    """One line of the comparison.

    Attributes:
        name: what is compared ("deviating module", "setting seed").
        a, b: the value of each analysis as the report words it ("" when it has none).
        same: whether the two agree (on the values, not only on their rounded wording).
    """

    name: str
    a: str
    b: str
    same: bool


@dataclass(frozen=True)
class PhaseCost:
    """One phase's cost in each analysis (None: the analysis has no such phase).

    Attributes:
        phase: the phase's name (``cyber``), or ``total``.
        seconds_a, seconds_b: wall time [s].
        simulations_a, simulations_b: simulations run.
    """

    phase: str
    seconds_a: float | None
    seconds_b: float | None
    simulations_a: int | None
    simulations_b: int | None


@dataclass(frozen=True)
class Comparison:
    """Two analyses compared.

    Attributes:
        run_a, run_b: the run directories.
        fields: the answer's fields, then every setting (in that order).
        costs: seconds and simulations per phase, then the total.
    """

    run_a: Path
    run_b: Path
    fields: tuple[FieldComparison, ...]
    costs: tuple[PhaseCost, ...]

    @property
    def differing(self) -> tuple[FieldComparison, ...]:
        """The fields on which the analyses differ."""
        return tuple(f for f in self.fields if not f.same)

    @property
    def same_answer(self) -> bool:
        """Whether the verdict, triggering entity, module and misconfiguration all agree."""
        return all(f.same for f in self.fields if f.name in ANSWER_FIELDS)

    def to_json(self) -> dict[str, Any]:
        """The ``--json`` document."""
        return {
            "run_a": str(self.run_a), "run_b": str(self.run_b), "same_answer": self.same_answer,
            "differs": [f.name for f in self.differing],
            "fields": {f.name: {"a": f.a, "b": f.b, "same": f.same} for f in self.fields},
            "costs": {c.phase: {"seconds_a": c.seconds_a, "seconds_b": c.seconds_b,
                                "simulations_a": c.simulations_a, "simulations_b": c.simulations_b}
                      for c in self.costs},
        }


def read_analysis_report(run_dir: str | os.PathLike[str]) -> dict[str, Any]:
    """The report.json of a finished analysis in ``run_dir``, its shape checked.

    Raises:
        InputError: ``run_dir`` is not a directory, holds no finished analysis, or its report
            is not one rocas wrote.
    """
    d = Path(run_dir)
    hint = "give the run directory of a finished 'rocas analyze', its --out"
    if not d.is_dir():
        raise InputError(f"{d}: not a directory", hint)
    path = d / "report.json"
    if not path.is_file():
        if (d / "state.json").is_file():
            raise InputError(f"{d}: the analysis has not finished (no report.json)",
                             "finish it with 'rocas analyze ... --resume'")
        raise InputError(f"{d}: no analysis here (no report.json)", hint)
    report = load_json_file(path, what="report")
    problem = _shape_problem(report)
    if problem:
        raise InputError(f"{path}: not a report of rocas analyze ({problem})", hint)
    return report


def _shape_problem(report: Any) -> str | None:
    if not isinstance(report, dict):
        return "not a JSON object"
    for key, types in _SHAPE.items():
        if key not in report:
            return f"no {key!r}"
        value = report[key]
        if not any(value is None if t is None else isinstance(value, t) for t in types):
            return f"{key!r} is a {type(value).__name__}"
    for key in ("evaluations", "timings_s"):
        for phase, v in report[key].items():
            if isinstance(v, bool) or not isinstance(v, int | float):
                return f"{key}.{phase} is not a number"
    for item in report["misconfiguration"]:
        if not isinstance(item, dict) or not {"parameter", "original", "mutated"} <= item.keys():
            return "a misconfiguration entry lacks parameter, original or mutated"
    trig = report["triggering_entity"]
    if trig is not None and not (isinstance(trig.get("properties"), list)
                                 and all(isinstance(p, dict) and {"original", "mutated"} <= p.keys()
                                         for p in trig["properties"])):
        return "the triggering entity's properties are not a list of changes"
    return None


def _trigger(report: dict[str, Any]) -> tuple[str, Any]:
    trig = report["triggering_entity"]
    if not trig:
        return "", None
    text = f"{trig.get('entity')} ({trig.get('kind')}): " + ", ".join(change(p, "->")
                                                                       for p in trig["properties"])
    return text, [trig.get("entity"), [(p.get("name"), p["original"], p["mutated"])
                                       for p in trig["properties"]]]


def _validation(report: dict[str, Any]) -> tuple[str, Any]:
    v = report["validation"] or {}
    if not v.get("variants"):
        return "", None
    rates = (v.get("success_rate_original"), v.get("success_rate_fixed"))
    if not all(isinstance(r, int | float) for r in rates):
        return "", None
    return (f"{v['variants']} variants: accident-free {100 * rates[0]:.0f} % (original) vs "
            f"{100 * rates[1]:.0f} % (fixed)", [v["variants"], *rates])


def _robust_words(report: dict[str, Any]) -> str:
    """The validation's robust value as report.md words it, from report.json's form."""
    v = report["validation"] or {}
    rob = v.get("robust_fix")
    if rob is None:
        return ("none: no stronger value avoids clearly more variants than the minimal fix"
                if v.get("stronger") else "not tried")
    originals = {m["parameter"]: m["original"] for m in report["misconfiguration"]}
    values = ", ".join(change_text(k, originals.get(k, "?"), x, "->")
                       for k, x in rob["fix"].items())
    return f"{values}: accident-free in {100 * rob['success_rate']:.0f} % of the variants"


def _answer_fields(report: dict[str, Any]) -> list[tuple[str, str, Any]]:
    """(name, wording, value) of each field of the answer."""
    mis = report["misconfiguration"]
    conf = report["confidence"] or {}
    ss = report["search_space"] or {}
    searched = (f"{ss['parameters_searched']} of {ss['parameters_total']} parameters"
                if ss.get("parameters_searched") else "")
    robust = (report["validation"] or {}).get("robust_fix")  # its value and its success rate
    rows: list[tuple[str, str, Any]] = [
        ("verdict", report["verdict"].replace("_", " "), report["verdict"]),
        ("stack", report["stack"] or "", report["stack"]),
        ("accident", accident_text(AccidentInfo(report["accident"].get("kind", "?"),
                                                report["accident"].get("time_s"),
                                                report["accident"].get("other")))
         if report["accident"] else "",
         report["accident"]),
        ("triggering entity", *_trigger(report)),
        ("deviating module", report["deviating_module"] or "", report["deviating_module"]),
        ("walk", " -> ".join(str(s) for s in report["path"] or []), report["path"]),
        ("confidence", f"{conf.get('level')}: {conf.get('note')}" if conf else "",
         [conf.get("level"), conf.get("note")]),
        ("misconfiguration", ", ".join(change(m, "->") for m in mis),
         [(m["parameter"], m["original"], m["mutated"]) for m in mis]),
        ("robust value", _robust_words(report) if report["validation"] else "", robust),
        ("validation", *_validation(report)),
        ("search space", searched, [ss.get("parameters_searched"), ss.get("parameters_total")]),
    ]
    return rows


def compare_reports(run_a: Path, report_a: dict[str, Any], run_b: Path,
                    report_b: dict[str, Any]) -> Comparison:
    """Compare two reports (as :func:`read_analysis_report` returns them)."""
    # values compared as report.json writes them (a report from before rocas rounded its
    # floats, 0.8549218750000002, is the same answer as 0.854921875)
    fields = [FieldComparison(name, ta, tb, rounded(va) == rounded(vb))
              for (name, ta, va), (_, tb, vb) in zip(_answer_fields(report_a),
                                                     _answer_fields(report_b), strict=True)]
    sa, sb = report_a["settings"] or {}, report_b["settings"] or {}
    for key in dict.fromkeys([*sa, *sb]):
        fields.append(FieldComparison(f"setting {key}", _word(sa.get(key)), _word(sb.get(key)),
                                      rounded(sa.get(key)) == rounded(sb.get(key))))
    ta, tb = report_a["timings_s"], report_b["timings_s"]
    ea, eb = report_a["evaluations"], report_b["evaluations"]
    costs = [PhaseCost(p, _num(ta.get(p)), _num(tb.get(p)), _int(ea.get(p)), _int(eb.get(p)))
             for p in dict.fromkeys([*ta, *tb, *ea, *eb])]
    costs.append(PhaseCost("total", sum(ta.values()), sum(tb.values()),
                           sum(int(v) for v in ea.values()), sum(int(v) for v in eb.values())))
    return Comparison(run_a, run_b, tuple(fields), tuple(costs))


def compare_runs(run_a: str | os.PathLike[str], run_b: str | os.PathLike[str]) -> Comparison:
    """Compare the finished analyses in two run directories.

    Raises:
        InputError: either directory holds no finished analysis (see :func:`read_analysis_report`).
    """
    a, b = Path(run_a), Path(run_b)
    return compare_reports(a, read_analysis_report(a), b, read_analysis_report(b))


def _word(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "on" if v else "off"
    return str(v)


def _num(v: Any) -> float | None:
    return float(v) if v is not None else None


def _int(v: Any) -> int | None:
    return int(v) if v is not None else None


__all__ = ["Comparison", "FieldComparison", "PhaseCost", "compare_reports", "compare_runs",
           "read_analysis_report"]
