"""The run directory of ``rocas analyze``, what its phases share, and resume.

Every phase writes its result into the run directory and records itself as done in
``state.json``; a resumed run rebuilds :class:`Run` from it and skips the finished phases.

Run directory::

    state.json        finished phases with their results, timings and evaluation counts
    scenario.json     the replayed scenario (the input of every later phase)
    accident.mcap     the replayed accident (recording mode)
    physical.ckpt     physical search checkpoint (while it runs)
    physical.json     the physical search: generations, chosen candidate
    reference.mcap    the accident-free reference execution
    diff.json         rocas diff between accident.mcap and reference.mcap
    cyber.ckpt / cyber.json
    fixed.mcap        the original scenario with the fixed configuration
    validation.ckpt   what the finished slices of the validation found (while it runs)
    validation.json   the regression test and the robust-value sweep
    report.json / report.md
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

from rocas._fs import check_writable, is_temporary, write_text_atomic
from rocas.errors import InputError, OutputError, UsageError
from rocas.pipeline.codec import ShapeError
from rocas.pipeline.config import PHASES, AnalyzeConfig, config_dict
from rocas.pipeline.cyber import cyber_space
from rocas.pipeline.evaluate import Accident, VariantResult
from rocas.pipeline.results import (
    RESULT_TYPES,
    Answer,
    DiffPhaseResult,
    PhaseResult,
    current_answer,
    revisions_of,
)
from rocas.scenarios.model import Scenario
from rocas.search.executor import Executor
from rocas.search.space import MutationSpace

Progress = Callable[[str, dict[str, Any]], None]


def noop(_: str, __: dict[str, Any]) -> None:
    pass


#: the layout of state.json this rocas writes and reads (1: phase results as free-form
#: objects, before they were typed)
SCHEMA_VERSION = 2

R = TypeVar("R")


@dataclass
class RunState:
    """What state.json holds: the input (``source`` label and the ``source_sha256`` of its
    content), the settings that change the result (``config``), each finished phase's result
    (phase -> a result of :mod:`rocas.pipeline.results`, in the order they finished), and per
    phase its time [s] and simulations."""

    source: str
    config: dict[str, Any]
    source_sha256: str | None = None
    results: dict[str, PhaseResult] = field(default_factory=dict)
    timings_s: dict[str, float] = field(default_factory=dict)
    evaluations: dict[str, int] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"version": SCHEMA_VERSION, "source": self.source, "config": self.config,
                               "done": {p: r.to_json() for p, r in self.results.items()},
                               "timings_s": self.timings_s, "evaluations": self.evaluations}
        if self.source_sha256 is not None:
            out["source_sha256"] = self.source_sha256
        return out


@dataclass
class Run:
    """Everything phases share (rebuilt on resume from the run directory)."""

    out: Path
    cfg: AnalyzeConfig
    executor: Executor
    progress: Progress
    state: RunState
    scenario: Scenario | None = None
    original: VariantResult | None = None
    accident: Accident | None = None
    accident_tick: int = 0
    #: work started ahead of the phase that needs it, on a worker while earlier phases run
    #: (name -> future): the phase takes it from here, or does the work itself if absent
    ahead: dict[str, Any] = field(default_factory=dict)

    @property
    def h1_horizon(self) -> int:
        """Samples of the ego trajectory h1 compares: [0, d - delta] (at least one)."""
        assert self.scenario is not None
        return max(1, self.accident_tick - int(round(self.cfg.delta_s / self.scenario.dt_s)))

    def cyber_space(self, module: str | None) -> MutationSpace:
        """The parameters the cyber phase searches (the module's, or all with --scope all) at
        the values in force in the accident run."""
        assert self.scenario is not None
        ego = self.scenario.ego  # cyber_space takes the defaults of what is not overridden
        return cyber_space(module if self.cfg.scope == "module" else None, ego.overrides,
                           ego.stack)

    def save(self) -> None:
        write_text_atomic(self.out / "state.json", json.dumps(self.state.to_json(), indent=2))

    def done(self, phase: str) -> bool:
        return phase in self.state.results

    def get(self, kind: type[R]) -> R | None:
        """The finished result of the phase whose result type is ``kind`` (None: not finished)."""
        return self.state.results.get(kind.PHASE)  # type: ignore[attr-defined]

    def result(self, kind: type[R]) -> R:
        """The finished result of the phase whose result type is ``kind``."""
        found = self.get(kind)
        if found is None:
            raise LookupError(f"phase {kind.PHASE} has not finished")  # type: ignore[attr-defined]
        return found

    def answer(self) -> Answer:
        """The current answer: the diff phase's with the later phases' revisions applied."""
        return current_answer(self.result(DiffPhaseResult), revisions_of(self.state.results))

    def finish(self, result: PhaseResult, seconds: float, evaluations: int = 0) -> None:
        """Record ``result`` as its phase's, with its time [s] and simulations, in state.json."""
        phase = result.PHASE
        self.state.results[phase] = result
        self.state.timings_s[phase] = round(seconds, 3)
        self.state.evaluations[phase] = evaluations
        self.save()


def source_identity(source: str | os.PathLike[str] | Scenario) -> tuple[str, str]:
    """``(label, sha256)`` of an analysis's input: the recording's resolved path and the
    digest of its bytes, or ``scenario:NAME`` and the digest of the scenario's canonical JSON.
    A run directory is resumed only with an input of the same digest.

    Raises:
        InputError: the recording cannot be read.
    """
    if isinstance(source, Scenario):
        from rocas.scenarios.loader import scenario_to_dict

        text = json.dumps(scenario_to_dict(source), sort_keys=True, separators=(",", ":"))
        return f"scenario:{source.name}", hashlib.sha256(text.encode()).hexdigest()
    path = Path(source)
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as f:
            while chunk := f.read(1 << 20):
                digest.update(chunk)
    except OSError as exc:
        raise InputError(f"cannot read {path}: {exc.strerror or exc}", "check the path") from None
    return str(path.resolve()), digest.hexdigest()


def damaged(out: Path, name: str, reason: str) -> InputError:
    return InputError(f"run directory {out} is damaged: {name} {reason}",
                      f"delete {out} to start again, or choose another --out")


def _state_problem(state: Any) -> str | None:
    """What is wrong with a decoded state.json's frame (None: nothing); the phases' results
    are checked by :func:`state_from_json`."""
    if not isinstance(state, dict):
        return "is not a rocas run state (not a JSON object)"
    version = state.get("version")
    if version != SCHEMA_VERSION:
        return (f"has layout {version!r} of another rocas version, not layout {SCHEMA_VERSION}"
                if isinstance(version, int) and not isinstance(version, bool)
                else "is not a rocas run state (no layout version)")
    for key in ("done", "config", "timings_s", "evaluations"):
        if not isinstance(state.get(key), dict):
            return f"is not a rocas run state ({key!r} is not an object)"
    if not isinstance(state.get("source"), str) or not isinstance(state.get("source_sha256", ""), str):
        return "is not a rocas run state ('source' is not text)"
    unknown = sorted(set(state["done"]) - set(PHASES))
    if unknown:
        return f"is not a rocas run state (unknown phase {unknown[0]!r})"
    for key, value in state["config"].items():
        if not isinstance(value, bool | int | float | str | type(None)):
            return f"has a setting {key!r} that is not a number or text"
    for table in ("timings_s", "evaluations"):
        for phase, value in state[table].items():
            if isinstance(value, bool) or not isinstance(value, int | float):
                return f"has {table}[{phase!r}] that is not a number"
    return None


def state_from_json(out: Path, state: Any) -> RunState:
    """A decoded state.json as a :class:`RunState`, each phase's result read as its type.

    Raises:
        InputError: it is of another layout or has the wrong shape (damaged: exit 3).
    """
    problem = _state_problem(state)
    if problem:
        raise damaged(out, "state.json", problem)
    results = {}
    for phase, data in state["done"].items():
        try:
            results[phase] = RESULT_TYPES[phase].from_json(data)
        except ShapeError as exc:
            part = f"whose {exc.where}" if exc.where else "that"
            raise damaged(out, "state.json", f"has a result of phase {phase!r} {part} {exc.why}") from None
    return RunState(state["source"], state["config"], state.get("source_sha256"), results,
                    state["timings_s"], state["evaluations"])


def read_state(out: Path) -> RunState:
    """``out/state.json``, read as its types (:func:`state_from_json`).

    Raises:
        InputError: it cannot be read, is not JSON, is too large or too deep, or is not a run
            state of this layout (the run directory is damaged: exit 3).
    """
    from rocas._limits import loads_json, read_text_limited

    path = out / "state.json"
    try:
        text = read_text_limited(path, what="run state")
    except InputError as exc:
        raise damaged(out, "state.json", f"cannot be read ({exc.message})") from None
    try:
        state = loads_json(text, origin="state.json")
    except InputError as exc:
        raise damaged(out, "state.json", f"is not valid JSON ({exc.message})") from None
    return state_from_json(out, state)


def _remove_debris(out: Path) -> None:
    """Remove the temporaries of writes a killed process left (``.NAME.XXXX.part``)."""
    for p in out.iterdir():
        if is_temporary(p) and p.is_file():
            p.unlink(missing_ok=True)


def _fmt_setting(v: Any) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


def prepare_run_dir(out: Path, resume: bool, source: str, cfg: AnalyzeConfig,
                    source_sha256: str | None = None) -> RunState:
    """Create or reopen a run directory; returns its state.

    A run directory is resumed only with the same settings (those that change the result; not
    the executor or its workers) and the same input: the same ``source_sha256`` (content), or,
    for a run directory written before inputs were identified by content, the same ``source``
    label (path). Temporaries of writes a killed run left behind (``.NAME.XXXX.part``) are
    removed, and are not taken for foreign content.

    Raises:
        UsageError: ``out`` holds an analysis but ``resume`` is False, or one of another input
            or other settings, or other files.
        InputError: ``out/state.json`` is damaged.
        OutputError: ``out`` cannot be made or written.
    """
    state_path = out / "state.json"
    config = config_dict(cfg)
    if state_path.exists():
        if not resume:
            raise UsageError(f"run directory {out} already holds an analysis",
                             "continue it with --resume, or choose another --out")
        state = read_state(out)
        if state.source_sha256 is not None:
            same_input = state.source_sha256 == source_sha256
        else:  # an input without a digest: by its label
            same_input = state.source == source
        if not same_input:
            raise UsageError(f"run directory {out} holds the analysis of another input: it was "
                             f"started on {state.source}, and {source} has other content",
                             "choose another --out, or resume with the input it was started with")
        # a setting added after the run was started has its default, which is what that run used
        default = config_dict(AnalyzeConfig())
        stored = {**default, **{k: v for k, v in state.config.items() if k in default}}
        differ = [f"{k} {_fmt_setting(config[k])} vs {_fmt_setting(stored[k])}"
                  for k in config if config[k] != stored[k]]
        if differ:
            raise UsageError(f"run directory {out} holds an analysis with other settings "
                             f"(given vs stored: {', '.join(differ)})",
                             "choose another --out, or resume with the options it was started with")
        _remove_debris(out)
        return state
    if out.exists() and not out.is_dir():
        raise OutputError(f"cannot make run directory {out}: a file of that name exists",
                          "choose another --out")
    if out.exists():
        if any(not is_temporary(p) for p in out.iterdir()):
            raise UsageError(f"{out} exists and is not a rocas run directory", "choose another --out")
        _remove_debris(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        check_writable(out / "state.json")
    except OSError as exc:
        raise OutputError(f"cannot make run directory {out}: {exc.strerror or exc}",
                          "choose a writable place for --out") from exc
    return RunState(source, config, source_sha256)



def remove_if_empty(folders: list[Path]) -> None:
    """Remove ``folders`` (deepest first) where they are empty; never anything else."""
    for d in folders:
        try:
            d.rmdir()
        except OSError:
            return



def finished_phases(out: Path) -> list[str]:
    """The phases state.json in ``out`` records as finished, read leniently (for a message
    after an interruption: [] when it cannot be read)."""
    try:
        state = json.loads((out / "state.json").read_text(encoding="utf-8"))
        return [str(p) for p in state["done"]]
    except (OSError, ValueError, KeyError, TypeError):
        return []
