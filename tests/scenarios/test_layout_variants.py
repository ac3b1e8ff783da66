"""The hand-authored layout variants (tests/scenarios/variants/layouts/): each catalog mechanism
re-authored on another road geometry, as a held-out-like set to measure rocas against.

Each file is re-simulated the way generated variants are kept (rocas.catalog.variants): the
defaults crash with the documented consequence and partner, every documented fix repairs it
(no collision or emergency, the ego within 0.5 m RMSE of the accident run until 3 s before it),
and the reference mutation in its ground truth avoids it."""

from __future__ import annotations

from pathlib import Path

import pytest

from rocas.catalog import accident_matches, fix_holds, mutate
from rocas.catalog.variants import load_variant, source_entry
from rocas.rollout import simulate_batch
from rocas.stacks.ads.params import PARAMETERS

LAYOUTS = Path(__file__).parent / "variants" / "layouts"
FILES = sorted(LAYOUTS.glob("*.toml"))


def test_the_set_covers_most_mechanisms_once():
    ids = [load_variant(f).truth.id for f in FILES]
    assert len(ids) == len(set(ids)) >= 8


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem.split("__")[0])
def test_a_layout_variant_keeps_its_entrys_mechanism(path):
    v = load_variant(path)
    src = source_entry(v)
    assert v.key == path.stem and v.key.startswith(src.key + "__layout_")
    for field in ("consequence", "collision_with", "module", "trigger_entity", "parameters",
                  "fixable"):
        assert getattr(v.truth, field) == getattr(src.truth, field), field
    # each fix moves a parameter the entry's fixes move, the same way from its default
    moved = {n: v_ for f in src.truth.fixes for n, v_ in f.items()}
    for fix in v.truth.fixes:
        for name, value in fix.items():
            default = PARAMETERS[name].default
            assert name in moved and (value - default) * (moved[name] - default) > 0, name
    # the reference mutates the same entity and fields as the entry's
    assert set(v.truth.reference) == set(src.truth.reference)
    assert next(iter(v.truth.reference.values())) == next(iter(src.truth.reference.values()))
    # another map: the ego drives another road
    lanes = {ln.id: ln.centerline for ln in v.scenario.lanes}
    src_lanes = {ln.id: ln.centerline for ln in src.scenario.lanes}
    assert [lanes[i] for i in v.scenario.ego.route] != \
        [src_lanes[i] for i in src.scenario.ego.route]


@pytest.mark.slow
@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem.split("__")[0])
def test_a_layout_variant_crashes_as_documented_and_its_fix_repairs_it(path):
    v = load_variant(path)
    fixes = [dict(f) for f in v.truth.fixes]
    ref = mutate(v.document, v.truth.reference, f"{path.name} reference")
    res = simulate_batch([v.scenario] * (1 + len(fixes)), params=[None, *fixes])
    acc = res.outcomes[0]
    assert accident_matches(v.truth, acc), acc.summary()
    ref_run = simulate_batch([ref]).outcomes[0]   # another structure when it edits the map
    assert not (ref_run.collided or ref_run.emergency), \
        f"the reference does not avoid it: {ref_run.summary()}"
    for j, fix in enumerate(fixes, start=1):
        assert fix_holds(acc, res.ego[0], res.outcomes[j], res.ego[j], res.times), \
            f"{fix}: {res.outcomes[j].summary()}"
