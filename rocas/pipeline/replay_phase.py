"""Phase I: the accident replayed (a recording) or simulated (a scenario)."""

from __future__ import annotations

import dataclasses
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from rocas._fs import write_text_atomic
from rocas._limits import loads_json, read_text_limited
from rocas.errors import InputError
from rocas.pipeline.evaluate import Accident, VariantResult, VariantTask, evaluate, is_accident
from rocas.pipeline.results import AccidentInfo, ReplayResult
from rocas.pipeline.rundir import Run, damaged
from rocas.scenarios.model import Scenario


def phase_replay(run: Run, scenario: Scenario | None, recording: Path | None) -> ReplayResult:
    """Replay ``recording`` (or simulate ``scenario``) as the accident, or on resume read back
    the replayed scenario; sets ``run.scenario``, ``run.original``, ``run.accident`` and
    ``run.accident_tick``. Returns the phase's result."""
    ran: tuple[Any, np.ndarray, np.ndarray] | None = None  # (outcome, ego, actors) of the run
    done = run.get(ReplayResult)
    if done is not None:
        run.scenario = _stored_scenario(run)
        result = done
    else:
        t0 = time.perf_counter()
        if recording is not None:
            scenario, result, ran = _replay_recording(run, recording)
        else:
            assert scenario is not None
            if run.cfg.stack is not None:  # another registered stack drives the accident
                from rocas.rollout import drive_with

                scenario = drive_with(scenario, run.cfg.stack)
            result, ran = _simulate_scenario(run, scenario)
        run.scenario = scenario
        _write(run, scenario, result)
        run.finish(result, time.perf_counter() - t0, 1)
    _set_original(run, ran)
    return result


def _stored_scenario(run: Run) -> Scenario:
    """The replayed scenario a resumed run reads back (bounded: it may come from someone else).

    Raises:
        InputError: scenario.json cannot be read or is not a scenario (damaged).
    """
    from rocas.scenarios.loader import scenario_from_dict

    try:
        text = read_text_limited(run.out / "scenario.json", what="scenario")
    except InputError as exc:
        raise damaged(run.out, "scenario.json", f"cannot be read ({exc.message})") from None
    try:
        return scenario_from_dict(loads_json(text, origin="scenario.json"))
    except (InputError, ValueError, TypeError, AttributeError) as exc:
        why = exc.message if isinstance(exc, InputError) else exc
        raise damaged(run.out, "scenario.json", f"is not a valid scenario ({why})") from None


def _accident_info(acc: Any) -> AccidentInfo | None:
    return None if acc is None else AccidentInfo(acc.kind, acc.time_s, acc.other)


def _replay_recording(run: Run, recording: Path) -> tuple[Scenario, ReplayResult, tuple[Any, ...]]:
    """The recording replayed: its scenario, the replay figures of the report (the recorded
    accident, the replay's, how closely the ego followed its recorded pose, and the damage the
    reader found) and the run's (outcome, ego, actors)."""
    import rocas.replay as replay_mod
    from rocas.rollout import drive_with

    recon = replay_mod.reconstruct(recording)
    if run.cfg.stack is not None:  # another registered stack drives the accident
        recon = dataclasses.replace(recon, scenario=drive_with(recon.scenario, run.cfg.stack))
    report = replay_mod.replay(recon, output=run.out / "accident.mcap")
    assert report.ego is not None and report.actors is not None
    warnings = list(recon.warnings)
    if report.only_emergency:
        warnings.append(
            f"{recording}: the replay reproduces the emergency at "
            f"{report.accident.time_s:.2f} s that preceded the recorded collision at "
            f"{report.original.time_s:.2f} s, but not the collision (smallest gap "
            f"{report.outcome.min_separation_m:.2f} m): the analysis explains the "
            "emergency")
    result = ReplayResult(
        source="recording", reproduced=bool(report.reproduced),
        recorded_accident=_accident_info(report.original), accident=_accident_info(report.accident),
        ego_rmse_m=report.ego_rmse_m, compared_until_s=report.compared_until_s,
        only_emergency=report.only_emergency, warnings=tuple(warnings), complete=recon.complete,
        stack=recon.scenario.ego.stack)
    return recon.scenario, result, (report.outcome, report.ego, report.actors)


def _simulate_scenario(run: Run, scenario: Scenario) -> tuple[ReplayResult, tuple[Any, ...]]:
    """The scenario simulated as the accident: the phase's result and (outcome, ego, actors)."""
    from rocas.rollout import simulate

    res = simulate(scenario, output=run.out / "accident.mcap")
    acc = Accident.of(res.outcome)
    result = ReplayResult(source="scenario", reproduced=is_accident(res.outcome),
                          recorded_accident=None,
                          accident=None if acc is None else AccidentInfo.from_json(acc.to_json()),
                          ego_rmse_m=0.0, stack=scenario.ego.stack)
    return result, (res.outcome, res.ego, res.actors)


def _write(run: Run, scenario: Scenario, result: ReplayResult) -> None:
    from rocas.scenarios.loader import scenario_to_dict

    write_text_atomic(run.out / "scenario.json", json.dumps(scenario_to_dict(scenario), indent=1))
    write_text_atomic(run.out / "replay.json", json.dumps(result.to_json(), indent=1))


def _set_original(run: Run, ran: tuple[Any, ...] | None) -> None:
    """The original run: the one just recorded (same scenario, no overrides, the scenario's
    seed; recording mode steps the very same loop: it is not simulated twice), or on resume
    re-simulated (deterministic) rather than stored."""
    assert run.scenario is not None
    if ran is not None:
        outcome, ego, actors = ran
        orig = VariantResult(outcome, np.ascontiguousarray(ego[:, :2]),
                             np.ascontiguousarray(actors[:, :, :2]))
    else:
        (orig,) = evaluate(run.executor, [VariantTask(run.scenario, (), run.scenario.seed)])
    run.original = orig
    run.accident = Accident.of(orig.outcome)
    dt = run.scenario.dt_s
    run.accident_tick = int(round(run.accident.time_s / dt)) if run.accident else 0
