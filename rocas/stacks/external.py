"""A stack run as an external process, the way the paper drives Apollo on LGSVL.

A stack file (TOML) declares the command and the parameter space::

    name = "lav-process"
    command = ["python", "-m", "rocas.rollout.command", "--stack", "lav"]
    parameters = "config.toml"      # or inline [parameters.<module>] tables

    # each parameter: name = { default = 0.1, range = [0, 1], unit = "", doc = "..." }

rocas runs ``COMMAND --scenario S.json --config C.json --out run.mcap`` once per simulation;
``C.json`` is ``{"params": {...overrides...}, "seed": N}``. The command writes an MCAP
recording carrying the ``rocas.run`` outcome record (as :func:`rocas.rollout.rollout`
does). Batches run as several processes at once; every result is cached under the input's
hash (command, scenario, overrides, seed), so a repeated simulation is not run again.

For an analysis the command also has a batch mode, ``COMMAND --batch B.json --out R.npz``:
``B.json`` is ``{"runs": [{"scenario": ..., "params": {...}, "seed": N}, ...]}`` (variants of
one scenario structure), ``R.npz`` holds what the searches read (``times`` (T + 1,), ``ego``
(N, T + 1, 5), ``actors`` (N, T + 1, A, 4), ``min_gap`` (N, T + 1), ``actor_ids`` (A,) and
``outcomes``, one ``rocas.run`` record per variant as JSON). ``rocas analyze --stack-file``
registers the stack under its name (:func:`rocas.stacks.registry.register`; workers get it with
their tasks) and analyses with it: a self-simulating stack
(:class:`rocas.stacks.base.SelfSimulating`) that the rollout hands whole scenarios, batches
split over ``processes`` processes. A stack file that names the registered stack its command
simulates (``stack = "lav"``) takes that stack's declarations (modules, channels, tracker,
limits, how replay reads its recordings): the analysis of a ``lav`` recording can then run
through the command.
"""

from __future__ import annotations

import concurrent.futures
import hashlib
import json
import os
import shutil
import subprocess
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rocas.errors import RecordingError, ScenarioError, UsageError
from rocas.scenarios.loader import scenario_to_dict
from rocas.scenarios.model import Scenario
from rocas.sim.engine import BatchResult, RunResult
from rocas.sim.oracles import Outcome
from rocas.stacks.base import RUN_METADATA, ParamSpec, StackParams


def read_parameters(data: Mapping[str, object], source: str) -> tuple[ParamSpec, ...]:
    """Parameter tables ``{module: {name: {default, range, unit, doc}}}`` -> specs."""
    specs = []
    for module, table in data.items():
        if not isinstance(table, Mapping):
            raise ScenarioError(f"{source}: parameters.{module}: expected a table")
        for name, d in table.items():
            try:
                low, high = d["range"]
                specs.append(ParamSpec(module, name, float(d["default"]), float(low),
                                       float(high), str(d.get("unit", "")),
                                       str(d.get("doc", ""))))
            except (KeyError, TypeError, ValueError) as exc:
                raise ScenarioError(f"{source}: {module}.{name}: expected "
                                    "{default, range = [low, high], unit, doc}",
                                    f"({exc})") from None
    return tuple(specs)


@dataclass(frozen=True)
class ExternalResult:
    """One external simulation: its recording, its outcome, whether it came from the cache."""

    recording: Path
    outcome: Outcome
    cached: bool


@dataclass(frozen=True)
class ExternalStack:
    """A stack behind a command. ``cache_dir`` keeps recordings by input hash."""

    name: str
    command: tuple[str, ...]
    parameters: tuple[ParamSpec, ...]
    cache_dir: Path
    timeout_s: float = 600.0
    #: the registered stack the command simulates (its recordings name it), or None
    stack: str | None = None
    #: processes a batch is split over at most
    processes: int = 2
    #: variants a process gets at least: starting one costs about 2 s (Python and imports),
    #: what lav simulates of a 14 s scenario in about 100 variants (tests/benchmarks/
    #: bench_external.py), so a smaller batch runs in one process
    min_per_process: int = 64

    @classmethod
    def from_file(cls, path: str | os.PathLike[str], cache_dir: str | os.PathLike[str]
                  ) -> ExternalStack:
        from rocas._limits import load_toml_file
        from rocas.errors import InputError

        path = Path(path)
        try:
            data = load_toml_file(path, what="stack file")
        except InputError as exc:
            raise UsageError(f"cannot read the stack file: {exc.message}",
                             exc.hint or "check --stack-file") from None
        command = data.get("command")
        if not (isinstance(command, list) and command and all(isinstance(c, str)
                                                               for c in command)):
            raise UsageError(f"{path}: 'command' must be a non-empty list of strings",
                             'command = ["my-sim"]')
        params = data.get("parameters", {})
        if isinstance(params, str):
            params_path = path.parent / params
            try:
                params = load_toml_file(params_path, what="parameters file")
            except InputError as exc:
                raise UsageError(f"{path}: its parameters file cannot be read: {exc.message}",
                                 f"'parameters' names a TOML file beside the stack file, "
                                 f"here {params_path}") from None
        stack = data.get("stack")
        if stack is not None and not isinstance(stack, str):
            raise UsageError(f"{path}: 'stack' must be a stack name", 'stack = "lav"')
        return cls(str(data.get("name", path.stem)), tuple(command),
                   read_parameters(params, str(path)), Path(cache_dir), stack=stack)

    def key(self, scenario: Scenario, overrides: Mapping[str, float], seed: int) -> str:
        """The input hash a result is cached under."""
        blob = json.dumps({"command": self.command, "scenario": scenario_to_dict(scenario),
                           "params": dict(sorted(overrides.items())), "seed": seed},
                          sort_keys=True).encode()
        return hashlib.sha256(blob).hexdigest()[:32]

    def _overrides(self, params: Mapping[str, float] | None) -> dict[str, float]:
        return StackParams(self.parameters, params, source=f"{self.name} config").overrides()

    def _call(self, args: list[str]) -> None:
        argv = [*self.command, *args]
        try:
            proc = subprocess.run(argv, capture_output=True, text=True, timeout=self.timeout_s,
                                  check=False)
        except (OSError, subprocess.TimeoutExpired) as exc:
            raise UsageError(f"stack {self.name}: cannot run {argv[0]} ({exc})") from None
        if proc.returncode != 0:
            last = (proc.stderr.strip().splitlines() or ["no output"])[-1]
            raise UsageError(f"stack {self.name}: {argv[0]} exited {proc.returncode}: {last}",
                             "run the command by hand with these inputs")

    def run(self, scenario: Scenario, params: Mapping[str, float] | None = None,
            seed: int | None = None) -> ExternalResult:
        """One simulation (from the cache when its inputs were run before)."""
        seed = scenario.seed if seed is None else seed
        overrides = self._overrides(params)
        key = self.key(scenario, overrides, seed)
        out = self.cache_dir / f"{key}.mcap"
        if out.exists():
            return ExternalResult(out, read_outcome(out), True)
        self.cache_dir.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(prefix="rocas-ext-") as tmp:
            s_path, c_path = Path(tmp, "scenario.json"), Path(tmp, "config.json")
            s_path.write_text(json.dumps(scenario_to_dict(scenario)), encoding="utf-8")
            c_path.write_text(json.dumps({"params": overrides, "seed": seed}), encoding="utf-8")
            run_path = Path(tmp, "run.mcap")
            self._call(["--scenario", str(s_path), "--config", str(c_path), "--out",
                        str(run_path)])
            if not run_path.exists():
                raise UsageError(f"stack {self.name}: {self.command[0]} wrote no recording",
                                 "run the command by hand with these inputs")
            shutil.move(str(run_path), str(out.with_suffix(".part")))
            os.replace(out.with_suffix(".part"), out)
        return ExternalResult(out, read_outcome(out), False)

    def run_batch(self, scenarios: Sequence[Scenario],
                  params: Sequence[Mapping[str, float] | None] | None = None,
                  seeds: Sequence[int | None] | None = None, *, processes: int = 2
                  ) -> list[ExternalResult]:
        """N simulations, at most ``processes`` at a time; results in input order."""
        n = len(scenarios)
        params = list(params) if params is not None else [None] * n
        seeds = list(seeds) if seeds is not None else [None] * n
        with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, processes)) as pool:
            return list(pool.map(self.run, scenarios, params, seeds))


    def simulate_batch(self, scenarios: Sequence[Scenario],
                       params: Sequence[Mapping[str, float] | None],
                       seeds: Sequence[int]) -> BatchResult:
        """N variants of one scenario structure through the command's batch mode (no
        digests). Cached variants are read back; the others are split over up to
        ``processes`` processes of at least ``min_per_process`` variants, one batch each."""
        keys = [self.key(s, self._overrides(p), seed)
                for s, p, seed in zip(scenarios, params, seeds, strict=True)]
        rows: dict[str, dict[str, Any]] = {}
        for k in dict.fromkeys(keys):
            if (self.cache_dir / f"{k}.rows.npz").exists():
                rows[k] = _load_rows(self.cache_dir / f"{k}.rows.npz")
        todo = [i for i, k in enumerate(keys) if k not in rows and keys.index(k) == i]
        if todo:
            self.cache_dir.mkdir(parents=True, exist_ok=True)
            parts = max(1, min(self.processes, len(todo) // max(1, self.min_per_process)))
            chunks = [todo[j::parts] for j in range(parts)]
            with concurrent.futures.ThreadPoolExecutor(max_workers=parts) as pool:
                for chunk, got in zip(chunks, pool.map(
                        lambda c: self._batch([scenarios[i] for i in c],
                                              [params[i] for i in c], [seeds[i] for i in c]),
                        chunks), strict=True):
                    for i, r in zip(chunk, got, strict=True):
                        path = self.cache_dir / f"{keys[i]}.rows.npz"
                        _save_rows(path, r)
                        rows[keys[i]] = r
        first = rows[keys[0]]
        return BatchResult(times=first["times"],
                       ego=np.stack([rows[k]["ego"] for k in keys]),
                       actors=np.stack([rows[k]["actors"] for k in keys]),
                       min_gap=np.stack([rows[k]["min_gap"] for k in keys]),
                       outcomes=[rows[k]["outcome"] for k in keys], digests=None,
                       actor_ids=first["actor_ids"])

    def simulate_one(self, scenario: Scenario, params: Mapping[str, float] | None,
                     seed: int | None, *, output: str | os.PathLike[str] | None = None
                     ) -> RunResult:
        """One run: the rows from the batch mode, the recording (when asked for) from the
        single-run mode, copied to ``output``."""
        seed = scenario.seed if seed is None else seed
        r = self.simulate_batch([scenario], [params], [seed])
        recording, messages = None, 0
        if output is not None:
            from rocas.recording.formats import open_recording

            one = self.run(scenario, params, seed)
            part = f"{os.fspath(output)}.part"
            shutil.copyfile(one.recording, part)
            os.replace(part, output)
            recording = os.fspath(output)
            messages = sum(1 for _ in open_recording(recording).messages())
        return RunResult(r.outcomes[0], r.times, r.ego[0], r.actors[0], r.min_gap[0],
                         recording, messages)

    # -- what the stack the command simulates declares ---------------------------------
    def _declared(self, what: str, default: Any) -> Any:
        if self.stack is None:
            return default
        from rocas.stacks.registry import get_stack

        return getattr(get_stack(self.stack), what, default)

    @property
    def modules(self) -> tuple[str, ...]:
        return tuple(self._declared("modules", tuple(dict.fromkeys(p.module
                                                                    for p in self.parameters))))

    @property
    def channels(self) -> tuple[Any, ...]:
        return tuple(self._declared("channels", ()))

    def __getattr__(self, name: str) -> Any:
        if name in _DECLARED:  # the stood-in stack's declarations (rocas.stacks.base)
            found = self._declared(name, None)
            if found is not None:
                return found
        raise AttributeError(name)

    def _batch(self, scenarios: Sequence[Scenario], params: Sequence[Mapping[str, float] | None],
               seeds: Sequence[int]) -> list[dict[str, Any]]:
        """One process of the batch mode: per variant its rows and outcome."""
        runs = [{"scenario": scenario_to_dict(s), "params": self._overrides(p), "seed": int(seed)}
                for s, p, seed in zip(scenarios, params, seeds, strict=True)]
        with tempfile.TemporaryDirectory(prefix="rocas-ext-") as tmp:
            b_path, r_path = Path(tmp, "batch.json"), Path(tmp, "rows.npz")
            b_path.write_text(json.dumps({"runs": runs}), encoding="utf-8")
            self._call(["--batch", str(b_path), "--out", str(r_path)])
            try:
                with np.load(r_path, allow_pickle=False) as z:
                    data = {k: z[k] for k in z.files}
            except (OSError, ValueError) as exc:
                raise RecordingError(f"stack {self.name}: unreadable batch result ({exc})",
                                     "the batch mode writes an .npz (see rocas.stacks.external)"
                                     ) from None
        outcomes = json.loads(str(data["outcomes"]))
        ids = tuple(str(a) for a in data["actor_ids"])
        return [{"times": data["times"], "ego": data["ego"][i], "actors": data["actors"][i],
                 "min_gap": data["min_gap"][i], "outcome": outcome_from_record(outcomes[i]),
                 "actor_ids": ids} for i in range(len(runs))]


def _save_rows(path: Path, r: Mapping[str, Any]) -> None:
    from rocas.sim.recorder import outcome_metadata

    part = path.with_suffix(".part.npz")
    np.savez(part, times=r["times"], ego=r["ego"], actors=r["actors"], min_gap=r["min_gap"],
             actor_ids=np.array(r["actor_ids"], dtype=str),
             outcome=np.array(json.dumps(outcome_metadata(r["outcome"]))))
    os.replace(part, path)


def _load_rows(path: Path) -> dict[str, Any]:
    with np.load(path, allow_pickle=False) as z:
        return {"times": z["times"], "ego": z["ego"], "actors": z["actors"],
                "min_gap": z["min_gap"], "actor_ids": tuple(str(a) for a in z["actor_ids"]),
                "outcome": outcome_from_record(json.loads(str(z["outcome"])))}


#: what an external stack takes from the stack its command simulates (``stack = NAME``)
_DECLARED = ("read_motion", "tracker", "braking_limits", "sensing_limits", "pace_limits",
             "catalog")


def read_outcome(path: str | os.PathLike[str]) -> Outcome:
    """The ``rocas.run`` record of a recording as an :class:`Outcome`."""
    from rocas.recording.formats import open_recording

    meta = dict(open_recording(str(path)).scan().metadata).get(RUN_METADATA)
    if meta is None:
        raise RecordingError(f"{path}: no {RUN_METADATA} metadata record",
                             "an external stack must write the run's outcome")
    return outcome_from_record(meta)


def outcome_from_record(meta: Mapping[str, str]) -> Outcome:
    """A ``rocas.run`` record (strings, as :func:`rocas.sim.recorder.outcome_metadata`
    writes them) as an :class:`Outcome`."""

    def opt(k: str) -> float | None:
        return float(meta[k]) if meta.get(k) else None

    pos = json.loads(meta["collision_position"]) if meta.get("collision_position") else None
    hb, es = opt("hard_brake_time_s"), opt("estop_time_s")
    return Outcome(
        collided=meta["collided"] == "true", collision_time_s=opt("collision_time_s"),
        collision_with=meta.get("collision_with") or None,
        collision_kind=meta.get("collision_kind") or None,
        collision_position=tuple(pos) if pos else None,
        hard_brake=hb is not None, hard_brake_time_s=hb, estop=es is not None,
        estop_time_s=es, unexpected_stop=meta["unexpected_stop"] == "true",
        emergency=meta["emergency"] == "true", max_decel_mps2=float(meta["max_decel_mps2"]),
        min_separation_m=float(meta["min_separation_m"]),
        route_completion=float(meta["route_completion"]))
