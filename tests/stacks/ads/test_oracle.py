"""Module substitution: ground-truth perception and prediction behind AdsStack(oracle_modules)."""

import numpy as np
import pytest

from rocas.catalog import entry
from rocas.errors import UsageError
from rocas.rollout import resolve, simulate_batch
from rocas.sim.engine import rollout
from rocas.sim.world import compile_batch, light_state
from rocas.stacks.ads import classifier
from rocas.stacks.ads.oracle import SUBSTITUTABLE
from rocas.stacks.ads.perception import sim_light_to_tl
from rocas.stacks.ads.prediction import perceived_world_state
from rocas.stacks.ads.run import AdsRun
from rocas.stacks.ads.stack import oracle_masks
from rocas.stacks.base import batch_params
from rocas.stacks.registry import get_stack


def _outputs(scenario, oracle_modules):
    """One run with its stack outputs at every perception step: {tick: TickOutputs}."""
    world = compile_batch([scenario], [scenario.seed])
    run = AdsRun(world, batch_params([resolve(get_stack("ads"), scenario)]), oracle_modules)
    seen = {}

    def keep(tick):
        if run.out.perception is not None:
            seen[tick] = run.out

    res = rollout(world, [scenario], run, on_tick=keep)
    return world, res, seen


def test_substitution_leaves_the_other_variants_of_a_batch_untouched():
    sc = entry("A12").scenario
    alone = simulate_batch(sc, track_outputs=True)
    sets = [frozenset(), frozenset({"perception"}), frozenset({"prediction"})]
    mixed = simulate_batch(sc, params=[None] * 3, oracle_modules=sets, track_outputs=True)
    # the ADS as it is, whatever else the batch substitutes: bit for bit
    assert np.array_equal(mixed.ego[0], alone.ego[0])
    assert np.array_equal(mixed.digests[0], alone.digests[0])
    assert mixed.outcomes[0] == alone.outcomes[0]
    # a substituted variant is the same in a batch and alone
    for i in (1, 2):
        single = simulate_batch(sc, oracle_modules=sets[i], track_outputs=True)
        assert np.array_equal(mixed.ego[i], single.ego[0])
        assert np.array_equal(mixed.digests[i], single.digests[0])
    # and substitution changes what the modules publish
    assert mixed.digests[1, 2] != alone.digests[0, 2]   # perception
    assert mixed.digests[2, 3] != alone.digests[0, 3]   # prediction


def test_ground_truth_prediction_is_what_the_actors_do():
    # A4's actors keep to their routes and speed profiles: their forecast is exact
    sc = entry("A4").scenario
    world, res, seen = _outputs(sc, frozenset({"prediction"}))
    assert not world.actor_reactive.any()
    dt = world.dt_s
    checked = 0
    for tick, out in seen.items():
        pred = out.prediction
        for k in np.flatnonzero(pred.traj_valid[0]):
            i = tick + int(round(pred.traj_t[0, k] / dt))
            if i >= res.actors.shape[1]:
                break
            moving = ~pred.is_static[0, :len(world.actor_ids)]
            np.testing.assert_allclose(pred.traj_x[0, :len(world.actor_ids), k][moving],
                                       res.actors[0, i, moving, 0], atol=1e-9)
            np.testing.assert_allclose(pred.traj_y[0, :len(world.actor_ids), k][moving],
                                       res.actors[0, i, moving, 1], atol=1e-9)
            checked += int(moving.sum())
    assert checked > 100


def test_ground_truth_perception_publishes_the_true_world():
    sc = entry("A9").scenario
    world, res, seen = _outputs(sc, frozenset({"perception"}))
    na = len(world.actor_ids)
    for tick, out in seen.items():
        per = out.perception
        x, y, *_ = perceived_world_state(per)
        assert per.published.all()
        np.testing.assert_allclose(x[0, :na], res.actors[0, tick, :, 0], atol=1e-9)
        np.testing.assert_allclose(y[0, :na], res.actors[0, tick, :, 1], atol=1e-9)
    # the red truck is never close in the ego's corridor: the true brake signal stays off,
    # where the learned classifier fires (the documented A9 accident)
    assert not any(out.perception.brake[0] for out in seen.values())
    _, _, real = _outputs(sc, frozenset())
    assert any(out.perception.brake[0] for out in real.values())


def test_ground_truth_light_is_the_ego_routes_own():
    sc = entry("A10").scenario
    world, _, seen = _outputs(sc, frozenset({"perception"}))
    own = np.flatnonzero(np.isfinite(world.light_stop_route_s))
    selected = {int(out.perception.tl_selected[0]) for out in seen.values()}
    assert selected - {-1} and selected - {-1} <= set(own.tolist())
    for tick, out in seen.items():
        j = int(out.perception.tl_selected[0])
        if j >= 0:
            true = sim_light_to_tl(light_state(world, tick * world.dt_s))[0, j]
            assert out.perception.tl_color[0, j] == true


def test_brake_worthy_is_close_ahead_in_the_corridor():
    ahead = np.array([5.0, 5.0, 12.0, -6.0])
    lateral = np.array([0.5, 4.0, 0.0, 0.0])
    got = classifier.brake_worthy(ahead, lateral, np.full(4, 4.5), np.full(4, 1.9), np.zeros(4))
    assert got.tolist() == [True, False, False, False]


@pytest.mark.parametrize("value, message", [
    (frozenset({"planning"}), "no ground-truth substitute"),
    (("perception",), "sequence of strings"),
    ([frozenset()] * 3, "3 sets for 2 variants"),
])
def test_oracle_modules_are_checked(value, message):
    with pytest.raises(UsageError, match=message):
        oracle_masks(value, 2)


def test_oracle_masks_per_variant():
    masks = oracle_masks([frozenset(), frozenset({"prediction"})], 2)
    assert set(masks) == set(SUBSTITUTABLE)
    assert masks["perception"].tolist() == [False, False]
    assert masks["prediction"].tolist() == [False, True]


def test_reactive_rollouts_are_reused_only_when_the_ego_cannot_matter(monkeypatch):
    # A9's truck keeps a distance (reactive): its forecast is rolled forward from its current
    # state; reusing an earlier rollout must give the same bits as rolling at every step
    import dataclasses

    from rocas.stacks.ads import oracle

    sc = dataclasses.replace(entry("A9").scenario, duration_s=6.0)
    step = oracle.step_actors
    calls = {}
    runs = {}
    for reuse in (True, False):
        count = [0]

        def counted(*args, _count=count, **kwargs):
            _count[0] += 1
            return step(*args, **kwargs)

        monkeypatch.setattr(oracle, "REUSE_ROLLOUTS", reuse)
        monkeypatch.setattr(oracle, "step_actors", counted)
        runs[reuse] = simulate_batch(sc, oracle_modules=frozenset({"prediction"}),
                                     track_outputs=True)
        calls[reuse] = count[0]
    assert compile_batch([sc], [sc.seed]).actor_reactive.any()
    assert np.array_equal(runs[True].ego, runs[False].ego)
    assert np.array_equal(runs[True].digests, runs[False].digests)
    assert calls[True] < calls[False] / 2
