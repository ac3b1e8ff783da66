import json
import pickle

import pytest
import search_toy
from search_toy import SPACE

from rocas.errors import InputError, UsageError
from rocas.search import LocalExecutor, SearchConfig, SerialExecutor, make_executor, run_search
from rocas.search.minimize import shrink_magnitudes, shrink_set
from rocas.search.space import Mutation

CFG = SearchConfig(population=14, generations=6, seed=3)


def _search(executor, checkpoint=None, on_generation=None, cfg=CFG):
    def evaluate(mutations):
        return executor.map(search_toy.simulate, mutations)

    return run_search(SPACE, evaluate, cfg, n_objectives=2, checkpoint=checkpoint,
                      on_generation=on_generation)


def _summary(result):
    return [(c.mutation, c.objectives, c.constraint, c.generation) for c in result.candidates]


def test_search_finds_a_feasible_fix_on_the_front():
    res = _search(SerialExecutor())
    assert res.front and all(c.feasible for c in res.front)
    best = min(res.front, key=lambda c: c.objectives)
    assert len(best.mutation.values) == 1
    assert set(best.mutation.values) <= {"truck.speed", "cone.enabled"}


def test_same_result_whatever_the_executor_and_workers():
    serial = _summary(_search(SerialExecutor()))
    with LocalExecutor(workers=2) as pool:
        assert _summary(_search(pool)) == serial


def _interrupt_at(generation, ckpt):
    """A search stopped by Ctrl-C as generation ``generation`` is reported (before its
    checkpoint is written)."""
    def stop(stats):
        if stats.generation == generation:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        _search(SerialExecutor(), checkpoint=ckpt, on_generation=stop)


def test_resume_continues_to_the_same_result(tmp_path):
    full = _summary(_search(SerialExecutor()))
    ckpt = tmp_path / "search.pkl"
    _interrupt_at(3, ckpt)
    assert ckpt.exists()
    assert _summary(_search(SerialExecutor(), checkpoint=ckpt)) == full


def test_a_resume_replays_from_the_checkpoint_without_evaluating_again(tmp_path):
    ckpt = tmp_path / "search.ckpt"
    _interrupt_at(3, ckpt)
    saved = json.loads(ckpt.read_text())  # data, not a pickle
    assert saved["format"] == "rocas-search-checkpoint" and saved["generations"] == 2
    evaluated = []

    def evaluate(mutations):
        evaluated.extend(mutations)
        return [search_toy.simulate(m) for m in mutations]

    seen = []
    res = run_search(SPACE, evaluate, CFG, n_objectives=2, checkpoint=ckpt,
                     on_generation=lambda s: seen.append(s.generation))
    before = {Mutation(c["values"]) for c in saved["candidates"]}
    assert evaluated and not before & set(evaluated)
    assert seen == [3, 4, 5, 6]  # the replayed generations are not reported again
    assert len(res.candidates) == len(before) + len(evaluated)


def test_a_checkpoint_is_never_unpickled(tmp_path):
    ckpt = tmp_path / "search.ckpt"
    marker = tmp_path / "ran"

    class Payload:
        def __reduce__(self):
            return (open, (str(marker), "w"))

    ckpt.write_bytes(pickle.dumps(Payload()))
    with pytest.raises(InputError, match="damaged"):
        _search(SerialExecutor(), checkpoint=ckpt)
    assert not marker.exists()


def test_a_checkpoint_of_another_search_is_refused(tmp_path):
    from dataclasses import replace

    ckpt = tmp_path / "search.ckpt"

    _interrupt_at(2, ckpt)
    with pytest.raises(InputError, match="another search"):
        _search(SerialExecutor(), checkpoint=ckpt, cfg=replace(CFG, seed=4))


def test_the_search_can_stop_early_once_a_fix_is_known():
    from dataclasses import replace

    full = _search(SerialExecutor())
    first = min(c.generation for c in full.candidates if c.feasible)
    early = _search(SerialExecutor(), cfg=replace(CFG, stop_when_feasible_after=first))
    # the same generations up to the first one with a fix, then nothing more
    assert [g.generation for g in early.generations] == list(range(1, max(first, 1) + 1))
    assert _summary(early) == [x for x in _summary(full) if x[3] <= max(first, 1)]
    assert any(c.feasible for c in early.candidates) and early.evaluations < full.evaluations


def test_identical_mutations_are_simulated_once():
    calls = []

    def evaluate(mutations):
        calls.extend(mutations)
        return search_toy.batch(mutations)

    res = run_search(SPACE, evaluate, CFG, n_objectives=2)
    assert len(calls) == len(set(calls)) == res.evaluations


def test_shrink_set_drops_irrelevant_variables():
    fix = Mutation({"truck.speed": 3.0, "car.x": 10.0, "weather.fog": 40.0, "ped.speed": 0.1})

    def holds(ms):
        return [search_toy.avoided(m) for m in ms]

    small, n = shrink_set(fix, holds)
    assert small == Mutation({"truck.speed": 3.0}) and n > 0


def test_shrink_magnitudes_moves_towards_the_boundary():
    def holds(ms):
        return [search_toy.avoided(m) for m in ms]

    small, _ = shrink_magnitudes(Mutation({"truck.speed": 2.0}), SPACE, holds, rounds=3)
    assert 7.9 <= small.values["truck.speed"] <= 8.0


def test_a_screening_that_suffices_ends_the_search_with_the_same_result_at_every_seed():
    """Two ends of each range screened, then no generation: what the screening found does not
    depend on the seed; without the predicate the genetic search goes on and does."""
    def run(seed, suffices):
        cfg = SearchConfig(population=8, generations=3, seed=seed, screen=True)
        return run_search(SPACE, search_toy.batch, cfg, n_objectives=2,
                          screening_suffices=suffices)

    def any_fix(cands):
        return any(c.feasible for c in cands)

    runs = [run(seed, any_fix) for seed in (0, 1, 2)]
    assert all(c.generation == 0 for r in runs for c in r.candidates)
    assert len({frozenset((c.mutation, c.objectives) for c in r.candidates) for r in runs}) == 1
    assert runs[0].feasible
    assert max(c.generation for c in run(0, lambda cands: False).candidates) > 0


def test_the_screening_looks_halfway_inside_a_range_that_its_ends_overshoot():
    """A fix only between the original and an end (here the truck between 4 and 8 m/s, its
    original 12 m/s, its range 0-20): the ends alone miss it (0 m/s 'brakes hard elsewhere'),
    halfway to the low end (6 m/s) finds it, with no generation and the same at every seed."""
    from rocas.search.ga import screening_genomes

    def simulate(m):
        objectives, _ = search_toy.simulate(m)
        v = float(m.values.get("truck.speed", 12.0))
        return objectives, (-1.0 if 4.0 <= v < 8.0 else 1.0)

    screened = [SPACE.decode(g) for g in screening_genomes(SPACE, 0)]
    # both ends of everything, halfway for the real variables only (not the enum, the bool)
    assert {Mutation({"truck.speed": v}) for v in (0.0, 6.0, 16.0, 20.0)} <= set(screened)
    assert len(screened) == 4 * 5 + 2 * 2
    results = []
    for seed in (0, 1):
        cfg = SearchConfig(population=8, generations=3, seed=seed, screen=True)
        res = run_search(SPACE, lambda ms: [simulate(m) for m in ms], cfg, n_objectives=2,
                         screening_suffices=lambda cands: any(c.feasible for c in cands))
        assert all(c.generation == 0 for c in res.candidates)
        assert [c.mutation for c in res.feasible] == [Mutation({"truck.speed": 6.0})]
        results.append(frozenset((c.mutation, c.objectives) for c in res.candidates))
    assert results[0] == results[1]


def test_executor_registry():
    assert make_executor("serial").name == "serial"
    with pytest.raises(UsageError, match="unknown executor"):
        make_executor("cluster")
    with pytest.raises(UsageError):
        LocalExecutor(workers=0)


def test_a_contiguous_shrink_stops_at_the_first_value_that_fails():
    """A value that holds beyond one that fails is an isolated pocket: the plain shrink jumps
    to it, the contiguous one stays on the interval it holds on (physical references). The
    grid from 2 towards the original 12 is 3.25, 4.5, 5.75, 7, 8.25, 9.5, 10.75."""
    def holds(ms):
        return [m.values["truck.speed"] <= 5.75 + 1e-9 or abs(m.values["truck.speed"] - 10.75) < 1e-9
                for m in ms]

    rounds = []
    jumped, _ = shrink_magnitudes(Mutation({"truck.speed": 2.0}), SPACE, holds, rounds=1)
    stayed, _ = shrink_magnitudes(Mutation({"truck.speed": 2.0}), SPACE, holds, rounds=1,
                                  contiguous=True, on_round=rounds.append)
    assert jumped.values["truck.speed"] == pytest.approx(10.75)
    assert stayed.values["truck.speed"] == pytest.approx(5.75)
    assert rounds == [stayed]


def test_a_deep_or_huge_checkpoint_is_damage_not_a_crash(tmp_path):
    ckpt = tmp_path / "search.ckpt"
    ckpt.write_text("[" * 100000 + "]" * 100000)
    with pytest.raises(InputError, match="damaged .*nested more than 64 levels"):
        _search(SerialExecutor(), checkpoint=ckpt)
    ckpt.unlink()
    ckpt.symlink_to("/dev/zero")
    with pytest.raises(InputError, match="cannot read search checkpoint .*too large"):
        _search(SerialExecutor(), checkpoint=ckpt)
