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
from rocas.pipeline.rundir import Run, damaged
from rocas.scenarios.model import Scenario


def phase_replay(run: Run, scenario: Scenario | None, recording: Path | None) -> None:
    from rocas.rollout import drive_with, simulate
    from rocas.scenarios.loader import scenario_from_dict, scenario_to_dict

    ran: tuple[Any, np.ndarray, np.ndarray] | None = None  # (outcome, ego, actors) of the run
    if run.done("replay"):
        try:
            text = read_text_limited(run.out / "scenario.json", what="scenario")
        except InputError as exc:
            raise damaged(run.out, "scenario.json", f"cannot be read ({exc.message})") from None
        try:  # bounded in size and depth: a run directory may come from someone else
            run.scenario = scenario_from_dict(loads_json(text, origin="scenario.json"))
        except (InputError, ValueError, TypeError, AttributeError) as exc:
            why = exc.message if isinstance(exc, InputError) else exc
            raise damaged(run.out, "scenario.json", f"is not a valid scenario ({why})") from None
    else:
        t0 = time.perf_counter()
        result: dict[str, Any] = {}
        if recording is not None:
            import rocas.replay as replay_mod

            recon = replay_mod.reconstruct(recording)
            if run.cfg.stack is not None:  # another registered stack drives the accident
                recon = dataclasses.replace(recon, scenario=drive_with(recon.scenario,
                                                                       run.cfg.stack))
            report = replay_mod.replay(recon, output=run.out / "accident.mcap")
            scenario = recon.scenario
            assert report.ego is not None and report.actors is not None
            ran = (report.outcome, report.ego, report.actors)
            # the replay figures of the report: the recorded accident (None: the recording
            # holds none), the replay's, and how closely the ego followed its recorded pose
            result = {"source": "recording", "reproduced": bool(report.reproduced),
                      "recorded_accident": report.original.to_dict() if report.original else None,
                      "accident": report.accident.to_dict() if report.accident else None,
                      "ego_rmse_m": report.ego_rmse_m, "compared_until_s": report.compared_until_s,
                      "only_emergency": report.only_emergency,
                      # damage the reader found: the analysis used less than the whole recording
                      "warnings": list(recon.warnings), "complete": recon.complete}
            if report.only_emergency:
                result["warnings"].append(
                    f"{recording}: the replay reproduces the emergency at "
                    f"{report.accident.time_s:.2f} s that preceded the recorded collision at "
                    f"{report.original.time_s:.2f} s, but not the collision (smallest gap "
                    f"{report.outcome.min_separation_m:.2f} m): the analysis explains the "
                    "emergency")
        else:
            assert scenario is not None
            if run.cfg.stack is not None:
                scenario = drive_with(scenario, run.cfg.stack)
            res = simulate(scenario, output=run.out / "accident.mcap")
            ran = (res.outcome, res.ego, res.actors)
            acc = Accident.of(res.outcome)
            result = {"source": "scenario", "reproduced": is_accident(res.outcome),
                      "recorded_accident": None, "accident": acc.to_json() if acc else None,
                      "ego_rmse_m": 0.0}
        run.scenario = scenario
        result["stack"] = scenario.ego.stack  # the system under test the searches re-run
        write_text_atomic(run.out / "scenario.json", json.dumps(scenario_to_dict(scenario), indent=1))
        write_text_atomic(run.out / "replay.json", json.dumps(result, indent=1))
        run.finish("replay", result, time.perf_counter() - t0, 1)
    if ran is not None:
        # the run just recorded is the original run (same scenario, no overrides, the
        # scenario's seed; recording mode steps the very same loop): it is not simulated twice
        outcome, ego, actors = ran
        orig = VariantResult(outcome, np.ascontiguousarray(ego[:, :2]),
                             np.ascontiguousarray(actors[:, :, :2]))
    else:
        # a resumed run: the original's trajectories are re-simulated (deterministic) rather
        # than stored
        (orig,) = evaluate(run.executor, [VariantTask(run.scenario, (), run.scenario.seed)])
    run.original = orig
    run.accident = Accident.of(orig.outcome)
    dt = run.scenario.dt_s
    run.accident_tick = int(round(run.accident.time_s / dt)) if run.accident else 0
