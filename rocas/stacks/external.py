"""A stack run as an external process, the way the paper drives Apollo on LGSVL.

A stack file (TOML) declares the command and the parameter space::

    name = "lav-process"
    command = ["python", "-m", "rocas.stacks.lav.run"]
    parameters = "config.toml"      # or inline [parameters.<module>] tables

    # each parameter: name = { default = 0.1, range = [0, 1], unit = "", doc = "..." }

rocas runs ``COMMAND --scenario S.json --config C.json --out run.mcap`` once per simulation;
``C.json`` is ``{"params": {...overrides...}, "seed": N}``. The command writes an MCAP
recording carrying the ``rocas.run`` outcome record (as :func:`rocas.stacks.rollout.rollout`
does). Batches run as several processes at once; every result is cached under the input's
hash (command, scenario, overrides, seed), so a repeated simulation is not run again.
"""

from __future__ import annotations

import concurrent.futures
import hashlib
import json
import os
import shutil
import subprocess
import tempfile
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from rocas.errors import RecordingError, ScenarioError, UsageError
from rocas.scenarios.loader import scenario_to_dict
from rocas.scenarios.model import Scenario
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

    @classmethod
    def from_file(cls, path: str | os.PathLike[str], cache_dir: str | os.PathLike[str]
                  ) -> ExternalStack:
        path = Path(path)
        try:
            data = tomllib.loads(path.read_text(encoding="utf-8"))
        except (OSError, tomllib.TOMLDecodeError) as exc:
            raise UsageError(f"{path}: cannot read the stack file ({exc})") from None
        command = data.get("command")
        if not (isinstance(command, list) and command and all(isinstance(c, str)
                                                               for c in command)):
            raise UsageError(f"{path}: 'command' must be a non-empty list of strings",
                             'command = ["my-sim"]')
        params = data.get("parameters", {})
        if isinstance(params, str):
            params_path = path.parent / params
            params = tomllib.loads(params_path.read_text(encoding="utf-8"))
        return cls(str(data.get("name", path.stem)), tuple(command),
                   read_parameters(params, str(path)), Path(cache_dir))

    def key(self, scenario: Scenario, overrides: Mapping[str, float], seed: int) -> str:
        """The input hash a result is cached under."""
        blob = json.dumps({"command": self.command, "scenario": scenario_to_dict(scenario),
                           "params": dict(sorted(overrides.items())), "seed": seed},
                          sort_keys=True).encode()
        return hashlib.sha256(blob).hexdigest()[:32]

    def run(self, scenario: Scenario, params: Mapping[str, float] | None = None,
            seed: int | None = None) -> ExternalResult:
        """One simulation (from the cache when its inputs were run before)."""
        seed = scenario.seed if seed is None else seed
        overrides = StackParams(self.parameters, params, source=f"{self.name} config"
                                ).overrides()
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
            argv = [*self.command, "--scenario", str(s_path), "--config", str(c_path),
                    "--out", str(run_path)]
            try:
                proc = subprocess.run(argv, capture_output=True, text=True,
                                      timeout=self.timeout_s, check=False)
            except (OSError, subprocess.TimeoutExpired) as exc:
                raise UsageError(f"stack {self.name}: cannot run {argv[0]} ({exc})") from None
            if proc.returncode != 0 or not run_path.exists():
                last = (proc.stderr.strip().splitlines() or ["no output"])[-1]
                raise UsageError(f"stack {self.name}: {argv[0]} exited {proc.returncode}: "
                                 f"{last}", "run the command by hand with these inputs")
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


def read_outcome(path: str | os.PathLike[str]) -> Outcome:
    """The ``rocas.run`` record of a recording as an :class:`Outcome`."""
    from rocas.recording.reader import open_recording

    meta = dict(open_recording(str(path)).scan().metadata).get(RUN_METADATA)
    if meta is None:
        raise RecordingError(f"{path}: no {RUN_METADATA} metadata record",
                             "an external stack must write the run's outcome")

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
