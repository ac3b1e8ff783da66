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
from typing import Any

import numpy as np

from rocas._fs import check_writable, is_temporary, write_text_atomic
from rocas.errors import InputError, OutputError, UsageError
from rocas.pipeline.config import PHASES, AnalyzeConfig, config_dict
from rocas.pipeline.cyber import cyber_space
from rocas.pipeline.evaluate import Accident, VariantResult
from rocas.scenarios.model import Scenario
from rocas.search.executor import Executor
from rocas.search.space import MutationSpace

Progress = Callable[[str, dict[str, Any]], None]


def noop(_: str, __: dict[str, Any]) -> None:
    pass


@dataclass
class Run:
    """Everything phases share (rebuilt on resume from the run directory)."""

    out: Path
    cfg: AnalyzeConfig
    executor: Executor
    progress: Progress
    state: dict[str, Any]
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
        write_text_atomic(self.out / "state.json", json.dumps(self.state, indent=2, default=jsonable))

    def done(self, phase: str) -> bool:
        return phase in self.state["done"]

    def finish(self, phase: str, result: dict[str, Any], seconds: float, evaluations: int = 0) -> None:
        self.state["done"][phase] = result
        self.state["timings_s"][phase] = round(seconds, 3)
        self.state["evaluations"][phase] = evaluations
        self.save()


def jsonable(x: Any) -> Any:
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(type(x).__name__)



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


#: what the pipeline reads of each finished phase's stored result before anything else: the
#: key, the types it may have, and whether it must be there (the rest is checked where it is
#: read, and anything still wrong is damage too: rocas.pipeline.analyze)
_PHASE_FIELDS: dict[str, tuple[tuple[str, tuple[type, ...], bool], ...]] = {
    "replay": (("reproduced", (bool,), True), ("accident", (dict, type(None)), False)),
    "physical": (("chosen", (dict,), False), ("evaluations", (int,), False)),
    "diff": (("deviating_module", (str, type(None)), True), ("path", (list,), False),
             ("control_channel", (str, type(None)), False)),
    "confidence": (("level", (str, type(None)), False),),
    "cyber": (("fix", (dict,), False), ("module", (str, type(None)), False)),
    "validation": (),
}


def _state_problem(state: Any) -> str | None:
    """What is wrong with a decoded state.json (None: nothing rocas relies on)."""
    if not isinstance(state, dict):
        return "is not a rocas run state (not a JSON object)"
    for key in ("done", "config", "timings_s", "evaluations"):
        if not isinstance(state.get(key), dict):
            return f"is not a rocas run state ({key!r} is not an object)"
    if not isinstance(state.get("source", ""), str) or not isinstance(state.get("source_sha256", ""), str):
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
    for phase, result in state["done"].items():
        if not isinstance(result, dict):
            return f"has a result of phase {phase!r} that is not an object"
        for key, types, required in _PHASE_FIELDS.get(phase, ()):
            if key not in result:
                if required:
                    return f"has a result of phase {phase!r} without {key!r}"
                continue
            value = result[key]
            if not isinstance(value, types) or (bool not in types and isinstance(value, bool)):
                return f"has a result of phase {phase!r} whose {key!r} has the wrong type"
    cyber = state["done"].get("cyber", {})
    fix = cyber.get("fix") if isinstance(cyber, dict) else None
    if fix is not None and not all(isinstance(k, str) and isinstance(v, int | float)
                                   and not isinstance(v, bool) for k, v in fix.items()):
        return "has a fix that is not a mapping of parameter names to numbers"
    return None


def read_state(out: Path) -> dict[str, Any]:
    """``out/state.json``, checked for what rocas relies on (types, known phases).

    Raises:
        InputError: it cannot be read, is not JSON, is too large or too deep, or is not a run
            state (the run directory is damaged: exit 3).
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
    problem = _state_problem(state)
    if problem:
        raise damaged(out, "state.json", problem)
    return state


def _remove_debris(out: Path) -> None:
    """Remove the temporaries of writes a killed process left (``.NAME.XXXX.part``)."""
    for p in out.iterdir():
        if is_temporary(p) and p.is_file():
            p.unlink(missing_ok=True)


def _fmt_setting(v: Any) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


def prepare_run_dir(out: Path, resume: bool, source: str, cfg: AnalyzeConfig,
                    source_sha256: str | None = None) -> dict[str, Any]:
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
        if "source_sha256" in state:
            same_input = state["source_sha256"] == source_sha256
        else:  # written before inputs were identified by content: by path, as then
            same_input = state.get("source") == source
        if not same_input:
            raise UsageError(f"run directory {out} holds the analysis of another input: it was "
                             f"started on {state.get('source')}, and {source} has other content",
                             "choose another --out, or resume with the input it was started with")
        # a setting added after the run was started has its default, which is what that run used
        default = config_dict(AnalyzeConfig())
        stored = {**default, **{k: v for k, v in state["config"].items() if k in default}}
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
    state = {"version": 1, "source": source, "config": config, "done": {}, "timings_s": {},
             "evaluations": {}}
    if source_sha256 is not None:
        state["source_sha256"] = source_sha256
    return state



def remove_if_empty(folders: list[Path]) -> None:
    """Remove ``folders`` (deepest first) where they are empty; never anything else."""
    for d in folders:
        try:
            d.rmdir()
        except OSError:
            return

