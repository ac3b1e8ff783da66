"""Phase V: the regression test over perturbed variants and the robust-value sweep."""

from __future__ import annotations

import json
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from rocas._fs import write_text_atomic
from rocas.pipeline.evaluate import VariantTask, evaluate, is_accident, params_tuple, record
from rocas.pipeline.results import RegressionTest, RobustFix, StrongerValue, ValidationResult
from rocas.pipeline.rundir import Run
from rocas.pipeline.sequential import looks, regression_test
from rocas.scenarios.model import Scenario
from rocas.search.objectives import ego_dissimilarity
from rocas.search.space import MutationSpace


def perturbed_variants(scenario: Scenario, count: int, seed: int) -> list[Scenario]:
    """``count`` variants of ``scenario``: actor speeds scaled by U(0.95, 1.05), start
    positions moved by U(-2, 2) m, and a new simulation seed each."""
    import dataclasses

    rng = np.random.default_rng(seed + 7)
    out = []
    for k in range(count):
        actors = []
        for a in scenario.actors:
            scale = float(rng.uniform(0.95, 1.05))
            ds = float(rng.uniform(-2.0, 2.0))
            actors.append(dataclasses.replace(
                a, start_s_m=max(0.0, a.start_s_m + ds),
                speed_profile=tuple((t, v * scale) for t, v in a.speed_profile)))
        out.append(dataclasses.replace(scenario, actors=tuple(actors), seed=scenario.seed + 1 + k))
    return out


#: how far past the minimal fix the validation tries stronger values: fractions of the way from
#: the minimal fix to the end of each parameter's range in the fix's direction
STRONGER_FRACTIONS = (0.125, 0.25, 0.5, 0.75, 1.0)
#: the robust value is the closest to the minimal fix whose success rate over the variants is
#: within this of the best rate seen, and it is reported only when it beats the minimal fix's
#: rate by at least this much (0.05: ten of 200 variants)
ROBUST_TOLERANCE = 0.05


def validation_simulations(variants: int, stronger: int = len(STRONGER_FRACTIONS)) -> int:
    """Simulations of phase V at most: the variants with the original and the minimal fix, then
    each of ``stronger`` values on the accident itself and on every variant (none without
    variants; fewer when stronger values coincide, see stronger_fixes, or the sweep stops early,
    see phase_validation)."""
    return 2 * variants + stronger * (variants + 1) if variants else 0


def stronger_fixes(fix: Mapping[str, float], space: MutationSpace
                   ) -> list[tuple[float, dict[str, float]]]:
    """``(fraction, values)``: the fix moved each of STRONGER_FRACTIONS of the way on to the end
    of each parameter's range in the direction it moved (integer parameters rounded), closest
    first. A value equal to the fix or to a closer one is left out (it would only be simulated
    again): a fix already at the end of its range has no stronger value."""
    out: list[tuple[float, dict[str, float]]] = []
    seen = [dict(fix)]
    for f in STRONGER_FRACTIONS:
        values = {}
        for name, x in fix.items():
            var = space.variable(name)
            lo, hi = float(var.low), float(var.high)  # type: ignore[arg-type]
            end = hi if x > float(var.original) else lo
            # x + f * (end - x) can land a rounding error outside the range, which the ADS refuses
            v = min(max(x + f * (end - x), lo), hi)
            values[name] = float(round(v)) if var.kind == "int" else v
        if values not in seen:
            seen.append(values)
            out.append((f, values))
    return out


#: simulations of phase V per slice, in batches (of AnalyzeConfig.batch_size) per worker: after
#: each slice the progress bar advances and the finished simulations are checkpointed
VALIDATION_SLICE_BATCHES = 1
#: stronger values run on the variants together, in one wave of simulations: the second is
#: run before the first's rate says whether it is needed (when it is not, its simulations are
#: spent for nothing, but two values in one wave fill both cores of a small machine at a
#: batch size where each core runs near its best throughput)
SWEEP_VALUES_PER_WAVE = 2


def phase_validation(run: Run, fix: Mapping[str, float], module: str | None) -> ValidationResult:
    """The paper's regression test: K perturbed variants with the original configuration and
    with the minimal fix. Then the robust value: the fix moved further the same way
    (STRONGER_FRACTIONS), each stronger value run on the accident (it must still avoid it and
    keep the ego's earlier trajectory, h1) and, closest first, on the same variants.

    The original runs on the variants in looks (:mod:`rocas.pipeline.sequential`) and stops
    as soon as the minimal fix and the original are separated with confidence (a paired exact
    sign test, its level split over the looks); its success rate is then over the variants
    run (``original_variants``) and ``regression_test`` says where and why it stopped.

    The sweep stops as soon as its answer is settled, which gives the same robust value as
    running every stronger value (see :func:`sweep_settled`): a stronger value that fails on
    the accident is not a candidate and is not run on the variants, and once one value is
    certain to be the robust one (or the minimal fix certain to be robust enough) the values
    beyond it are left out. The report lists them with ``"skipped"`` and the reason.

    The simulations run in waves, each as few large batches as the executor's workers allow:
    the stronger values on the accident, the minimal fix on every variant and the original's
    first look; then the original's next look (while undecided) with the next
    SWEEP_VALUES_PER_WAVE stronger values still to run. Each wave runs in slices
    (VALIDATION_SLICE_BATCHES batches per worker); after each, the progress callback gets the
    running count (``evaluations``) and the most simulations the phase can still take
    (``simulations``), and what the finished ones found (accident or not, and h1 where the
    sweep needs it) is written to ``validation.ckpt``, so a resumed run goes on after the last
    finished slice. Results do not depend on the slicing."""
    done = run.get(ValidationResult)
    if done is not None:
        return done
    t0 = time.perf_counter()
    assert run.scenario is not None and run.original is not None
    variants = perturbed_variants(run.scenario, run.cfg.validation_variants, run.cfg.seed)
    n = len(variants)
    stronger = stronger_fixes(fix, run.cyber_space(module)) if n else []
    configs = [params_tuple(values) for _, values in stronger]
    planned = validation_simulations(n, len(stronger))
    found = _validation_checkpoint(run.out / "validation.ckpt", fix, n, planned,
                                   run.state.source_sha256, run.cfg.seed)
    sims = _Simulations(run, found, planned=planned)
    waves = _Waves(variants, configs, looks(n))
    first = sims.run([VariantTask(run.scenario, c, run.scenario.seed) for c in configs]
                     + [VariantTask(v, params_tuple(fix), v.seed) for v in variants]
                     + waves.original[:waves.schedule[0] if n else 0], h1_of=range(len(configs)),
                     recordings=record_fix(run, fix))
    on_accident = first[:len(configs)]
    h1 = [found["h1_m2"][str(i)] for i in range(len(configs))]
    waves.start([not acc and h <= run.cfg.h1_limit_m2 for acc, h in zip(on_accident, h1, strict=True)],
                 first[len(configs):len(configs) + n], first[len(configs) + n:], sims)
    while True:
        more, arms = waves.next_original(), waves.next_arms(sims)
        if not more and not arms:
            break
        waves.take(sims.run(more + [VariantTask(v, configs[j], v.seed) for j in arms
                                    for v in variants]), len(more), arms, sims)
    sims.report()
    sweep = tuple(StrongerValue(fraction=f, fix=values, avoids_accident=not on_accident[k],
                                h1_m2=round(h1[k], 6), success_rate=waves.rates[k],
                                skipped=waves.skipped[k] or None)
                  for k, (f, values) in enumerate(stronger))
    test = waves.test
    ok_orig = _rate(waves.orig_acc) if n else None
    if test is not None and test["stopped_early"]:
        worse = test["decision"] == "fix_worse"
    else:
        worse = bool(n and waves.ok_fixed < ok_orig)  # type: ignore[operator]
    result = ValidationResult(
        variants=n, success_rate_original=ok_orig, original_variants=len(waves.orig_acc),
        success_rate_fixed=waves.ok_fixed, fix_makes_it_worse=worse,
        regression_test=None if test is None else RegressionTest(**test), stronger=sweep,
        robust_fix=_robust(waves.ok_fixed, sweep, run.cfg.h1_limit_m2),
        simulations=sims.done, simulations_without_stopping=validation_simulations(n, len(stronger)))
    write_text_atomic(run.out / "validation.json", json.dumps(result.to_json(), indent=1))
    run.finish(result, time.perf_counter() - t0, sims.done)
    (run.out / "validation.ckpt").unlink(missing_ok=True)
    return result


class _Waves:
    """What phase V knows between its waves of simulations: the original's runs on the
    variants so far (``orig_acc``: accident flags) and the regression test over them
    (``test``), the minimal fix's success rate (``ok_fixed``), and per stronger value whether
    it is a candidate (``valid``), its success rate over the variants (``rates``, None: not
    run) and why it was left out (``skipped``); ``k``: the next stronger value to consider."""

    def __init__(self, variants: list[Scenario], configs: list[Any], schedule: list[int]) -> None:
        self.n, self.configs, self.schedule = len(variants), configs, schedule
        self.original = [VariantTask(v, (), v.seed) for v in variants]
        self.rates: list[float | None] = [None] * len(configs)
        self.skipped: list[str | None] = [None] * len(configs)
        self.valid: list[bool] = []
        self.fixed_ok: list[bool] = []
        self.orig_acc: list[bool] = []
        self.ok_fixed: float | None = None
        self.test: dict[str, Any] | None = None
        self.k = 0

    def start(self, valid: list[bool], fixed_acc: list[bool], orig_acc: list[bool],
              sims: _Simulations) -> None:
        """The first wave's findings: which stronger values avoid the accident and keep the
        ego's earlier trajectory (``valid``), the minimal fix's and the original's first
        look's accident flags on the variants."""
        n = self.n
        self.valid, self.orig_acc = valid, orig_acc
        sims.planned -= n * valid.count(False)
        self.ok_fixed = _rate(fixed_acc) if n else None
        self.fixed_ok = [not a for a in fixed_acc]
        self.skipped = [None if ok else "it does not avoid the accident or it changes the ego's "
                        "trajectory before it" for ok in valid]
        self.test = regression_test([not a for a in orig_acc], self.fixed_ok, n) if n else None
        if self.test is not None and self.test["stopped_early"]:
            sims.planned -= n - len(orig_acc)

    def next_original(self) -> list[VariantTask]:
        """The original's next look on the variants (none once the test has decided)."""
        done = len(self.orig_acc)
        if self.test is None or self.test["decision"] is not None or done >= self.n:
            return []
        return self.original[done:self.schedule[self.schedule.index(done) + 1]]

    def next_arms(self, sims: _Simulations) -> list[int]:
        """The next SWEEP_VALUES_PER_WAVE candidate stronger values to run on the variants;
        none (and the rest marked skipped) once the robust value is settled."""
        arms: list[int] = []
        while self.k < len(self.configs) and len(arms) < SWEEP_VALUES_PER_WAVE:
            k = self.k
            if self.valid[k] and not arms and sweep_settled(
                    self.ok_fixed, [r for r in self.rates if r is not None]):
                for j in range(k, len(self.configs)):
                    if self.valid[j]:
                        self.skipped[j] = "the robust value was settled by the closer values"
                        sims.planned -= self.n
                self.k = len(self.configs)
                break
            if self.valid[k]:
                arms.append(k)
            self.k += 1
        return arms

    def take(self, wave: list[bool], looked: int, arms: list[int], sims: _Simulations) -> None:
        """A wave's accident flags: ``looked`` runs of the original, then each arm's variants."""
        n = self.n
        self.orig_acc = self.orig_acc + wave[:looked]
        for i, j in enumerate(arms):
            self.rates[j] = _rate(wave[looked + i * n:looked + (i + 1) * n])
        if looked:
            self.test = regression_test([not a for a in self.orig_acc], self.fixed_ok, n)
            if self.test["stopped_early"]:
                sims.planned -= n - len(self.orig_acc)


def record_fix(run: Run, fix: Mapping[str, float]) -> list[tuple[VariantTask, Path]]:
    """The recording of the accident with the fix (``fixed.mcap``), unless it was made: phase
    V records it as an extra row of its first batch (a few milliseconds there; alone, a whole
    rollout's fixed cost), the very file a run of its own writes."""
    path = run.out / "fixed.mcap"
    assert run.scenario is not None
    if path.exists():
        return []
    return [(VariantTask(run.scenario, params_tuple(fix), run.scenario.seed), path)]


def _rate(accidents: list[bool]) -> float:
    """The share of runs without an accident."""
    return sum(not a for a in accidents) / len(accidents)


def _qualifies(rate: float, best: float, minimal: bool) -> bool:
    """Whether a success rate is within ROBUST_TOLERANCE of the best: for the minimal fix,
    strictly (a stronger value that is exactly the tolerance better is preferred)."""
    return rate > best - ROBUST_TOLERANCE if minimal else rate >= best - ROBUST_TOLERANCE


def sweep_settled(fixed_rate: float | None, rates: list[float]) -> bool:
    """Whether the robust value is already decided by the minimal fix's success rate and the
    ``rates`` of the valid stronger values so far (closest first), whatever the rates of the
    values still to come: some value (the minimal fix counts as the first) is within the
    tolerance even of a perfect rate, and every closer one falls short even of the best seen so
    far. The best can only grow, so these stay true: :func:`_robust` of the whole sweep picks
    the same value."""
    if fixed_rate is None:
        return True
    seen = [fixed_rate] + rates
    best = max(seen)
    for i, r in enumerate(seen):
        if _qualifies(r, 1.0, minimal=i == 0):
            return True
        if _qualifies(r, best, minimal=i == 0):
            return False  # this one's fate depends on the values to come
    return False


class _Simulations:
    """Runs phase V's simulations in slices, checkpointed, resuming from what a checkpoint
    holds (results in task order, so a resumed run takes the saved prefix and goes on)."""

    def __init__(self, run: Run, found: dict[str, Any], planned: int) -> None:
        self.run_, self.found, self.planned, self.done = run, found, planned, 0
        self._said: tuple[int, int] | None = None

    def run(self, tasks: list[VariantTask], h1_of: range = range(0),
            recordings: list[tuple[VariantTask, Path]] | None = None) -> list[bool]:
        """The tasks' accident flags; ``recordings`` (``(task, MCAP path)``) are recorded as
        extra rows of the first batch run (or alone, when every task was done before an
        interruption)."""
        run, found, first = self.run_, self.found, self.done
        recordings = list(recordings or [])
        step = run.cfg.batch_size * VALIDATION_SLICE_BATCHES * max(1, getattr(run.executor, "workers", 1))
        while self.done < first + len(tasks):
            if len(found["accident"]) > self.done:  # finished before an interruption
                upto = min(len(found["accident"]), first + len(tasks))
                self.spot_check(tasks, first, range(self.done, upto), h1_of)
                self.done = upto
                continue
            self.report()
            chunk = tasks[self.done - first:self.done - first + step]
            results = evaluate(run.executor, chunk, run.cfg.batch_size, recordings)
            recordings = []
            for i, r in enumerate(results, self.done):
                found["accident"].append(is_accident(r.outcome))
                if i - first in h1_of:
                    assert run.original is not None
                    found["h1_m2"][str(i)] = ego_dissimilarity(run.original.ego_xy, r.ego_xy,
                                                               run.h1_horizon)
            self.done += len(chunk)
            write_text_atomic(run.out / "validation.ckpt", json.dumps(found))
        record(recordings)
        return found["accident"][first:first + len(tasks)]

    def spot_check(self, tasks: list[VariantTask], first: int, taken: range, h1_of: range) -> None:
        """Run again SPOT_CHECKS of the simulations a checkpoint says were done (chosen at
        random where the checkpoint's writer cannot foresee it) and refuse the checkpoint as
        damage if one comes out otherwise: the simulation is deterministic, so a checkpoint
        rocas wrote always agrees, and one written to steer the verdict is caught with
        probability 1 - (1 - share altered)^SPOT_CHECKS per wave."""
        import random

        from rocas.pipeline.rundir import damaged

        if not taken:
            return
        picks = sorted(random.SystemRandom().sample(taken, min(SPOT_CHECKS, len(taken))))
        run = self.run_
        results = evaluate(run.executor, [tasks[i - first] for i in picks], run.cfg.batch_size)
        for i, r in zip(picks, results, strict=True):
            same = is_accident(r.outcome) == self.found["accident"][i]
            if same and i - first in h1_of and str(i) in self.found["h1_m2"]:
                assert run.original is not None
                h1 = ego_dissimilarity(run.original.ego_xy, r.ego_xy, run.h1_horizon)
                same = bool(np.isclose(h1, self.found["h1_m2"][str(i)], rtol=1e-9, atol=1e-12))
            if not same:
                raise damaged(run.out, "validation.ckpt",
                              f"does not match the simulations it records (simulation {i} run "
                              "again comes out otherwise)")

    def report(self) -> None:
        """Tell the progress callback how far the phase is (when that changed)."""
        if self._said == (self.planned, self.done):
            return
        self._said = (self.planned, self.done)
        self.run_.progress("validation", {"variants": self.found["variants"],
                                          "simulations": self.planned, "evaluations": self.done})


#: simulations of a resumed wave that are run again to check the checkpoint (see
#: _Simulations.spot_check)
SPOT_CHECKS = 4


def _validation_checkpoint(path: Path, fix: Mapping[str, float], variants: int, planned: int,
                           source_sha256: str | None = None, seed: int | None = None
                           ) -> dict[str, Any]:
    """What the finished slices of phase V found, in task order (``accident``: one flag per
    simulation; ``h1_m2``: task index -> h1 of the stronger values' runs on the accident); empty
    when there is no checkpoint, or one of another fix, size, input, seed or format (then it is
    started afresh: the order of the tasks follows from the results, so a prefix is all there
    is).

    Raises:
        InputError: the checkpoint is of this validation but its content has the wrong types
            or lengths (the run directory is damaged).
    """
    from rocas._limits import loads_json, read_text_limited
    from rocas.errors import InputError
    from rocas.pipeline.rundir import damaged

    fresh = {"format": 4, "fix": dict(fix), "variants": variants, "source_sha256": source_sha256,
             "seed": seed, "accident": [], "h1_m2": {}}
    if not path.exists():
        return fresh
    try:
        saved = loads_json(read_text_limited(path, what="checkpoint"), origin=path.name)
    except InputError:
        return fresh  # a write cut short: its slices are run again
    identity = ("format", "fix", "variants", "source_sha256", "seed")
    if not isinstance(saved, dict) or any(saved.get(k) != fresh[k] for k in identity):
        return fresh
    accident, h1 = saved.get("accident"), saved.get("h1_m2")
    if not (isinstance(accident, list) and all(isinstance(a, bool) for a in accident)
            and len(accident) <= planned):
        raise damaged(path.parent, path.name, f"does not hold at most {planned} accident flags")
    if not (isinstance(h1, dict) and all(
            isinstance(k, str) and k.isdigit() and int(k) < len(accident)
            and isinstance(v, int | float) and not isinstance(v, bool) and np.isfinite(v)
            for k, v in h1.items())):
        raise damaged(path.parent, path.name, "holds h1 values that are not finite numbers of "
                                              "simulations it records")
    return {**fresh, "accident": accident, "h1_m2": h1}


def _robust(fixed_rate: float | None, sweep: tuple[StrongerValue, ...], h1_limit: float
            ) -> RobustFix | None:
    """The value closest to the minimal fix whose success rate is within ROBUST_TOLERANCE of the
    best rate among it and the stronger values that still avoid the accident and keep the ego's
    earlier trajectory (and were run on the variants); None when that is the minimal fix itself
    (no stronger value avoids clearly more variants)."""
    if fixed_rate is None:
        return None
    valid = [s for s in sweep if s.avoids_accident and s.h1_m2 <= h1_limit
             and s.success_rate is not None]
    best = max([fixed_rate] + [s.success_rate for s in valid])  # type: ignore[misc]
    if _qualifies(fixed_rate, best, minimal=True):
        return None
    pick = next(s for s in valid if _qualifies(s.success_rate, best, minimal=False))  # type: ignore[arg-type]
    return RobustFix(fix=pick.fix, success_rate=pick.success_rate, fraction=pick.fraction)  # type: ignore[arg-type]
