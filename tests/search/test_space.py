import numpy as np
import pytest
from search_toy import SPACE

from rocas.errors import UsageError
from rocas.search.space import Mutation, MutationSpace, Variable


def test_encode_decode_round_trip():
    m = Mutation({"truck.speed": 7.5, "truck.model": "bus", "cone.enabled": False})
    assert SPACE.decode(SPACE.encode(m)) == m
    assert SPACE.decode(SPACE.encode(Mutation())) == Mutation()


def test_mask_genes_keep_originals():
    g = SPACE.encode(Mutation())
    g[1::2] = 0.99  # values far away, masks off
    assert SPACE.decode(g).values == {}


def test_distance_counts_properties_plus_l1_and_l2():
    assert SPACE.distance(Mutation()) == 0
    # an enum change (truck -> bus) + a bool flip: 2 properties + L1 of 1 + 1
    assert SPACE.distance(Mutation({"truck.model": "bus", "cone.enabled": False})) == 4
    # enums are nominal: any other choice is one step
    assert SPACE.distance(Mutation({"truck.model": "sedan"})) == 2
    # a real change of 10 % of its range: 1 + 0.1
    assert SPACE.distance(Mutation({"truck.speed": 14.0})) == pytest.approx(1.1)


def test_single_property_seeds_mutate_one_variable_each():
    seeds = SPACE.single_property_seeds(14, np.random.default_rng(0))
    sizes = [len(SPACE.decode(g).values) for g in seeds]
    assert all(s <= 1 for s in sizes) and sum(sizes) >= 12


def test_bad_variables_are_refused():
    with pytest.raises(UsageError):
        Variable("x", "e", "real", 1.0, low=2.0, high=1.0)
    with pytest.raises(UsageError):
        Variable("x", "e", "enum", "a", choices=("b", "c"))
    with pytest.raises(UsageError):
        MutationSpace((Variable("x", "e", "bool", True), Variable("x", "e", "bool", True)))
