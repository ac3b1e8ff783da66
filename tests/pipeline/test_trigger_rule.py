"""The rule that picks the triggering entity from the physical search's Pareto front."""


def test_the_trigger_rule_prefers_changing_a_property_to_removing_the_entity():
    from rocas.pipeline.physical import physical_space
    from rocas.pipeline.physical_phase import _choose_trigger
    from rocas.scenarios.catalog import entry
    from rocas.search.ga import Candidate, SearchResult
    from rocas.search.space import Mutation

    space = physical_space(entry("A10").scenario)
    off = Candidate(Mutation({"light.tl_skew.enabled": False}), (-1.6, 0.0, 2.0), -1.0, 0)
    yellow = Candidate(Mutation({"light.tl_skew.policy": "fixed_yellow"}), (-1.6, 0.0, 2.0), -1.0, 0)
    res = SearchResult(candidates=[off, yellow], front=[off, yellow])
    assert _choose_trigger(res, space) is yellow
    # the earlier keys still come first: a smaller change wins even if it removes the entity
    smaller = Candidate(off.mutation, (-1.6, 0.0, 1.5), -1.0, 0)
    res = SearchResult(candidates=[smaller, yellow], front=[smaller, yellow])
    assert _choose_trigger(res, space) is smaller


def test_the_similarity_margin_scales_with_f2():
    """f2 is a mean squared distance: on A3 the fog (f2 21.0 m^2) and the truck's speed
    (25.8 m^2) are equally similar references at that scale, and the truck, close and in front
    of the ego, is the more suspicious; at small f2 the margin stays 1 m^2."""
    from rocas.pipeline.physical import physical_space
    from rocas.pipeline.physical_phase import F2_TOLERANCE_M2, _choose_trigger, f2_tolerance
    from rocas.scenarios.catalog import entry
    from rocas.search.ga import Candidate, SearchResult
    from rocas.search.space import Mutation

    assert f2_tolerance(0.0) == F2_TOLERANCE_M2
    assert f2_tolerance(2.0) == 3.0
    assert f2_tolerance(21.0) > 25.8 > 21.0 + F2_TOLERANCE_M2

    space = physical_space(entry("A3").scenario)
    truck = next(v.name for v in space.variables if v.name.endswith(".speed_scale"))
    fog = Candidate(Mutation({"weather.fog_density": 39.1}), (-0.2, 21.0, 1.39), -1.0, 0)
    faster = Candidate(Mutation({truck: 1.07}), (-2.14, 25.8, 1.05), -1.0, 0)
    far = Candidate(Mutation({truck: 1.4}), (-2.14, 40.0, 1.4), -1.0, 0)
    assert _choose_trigger(SearchResult(candidates=[fog, faster], front=[fog, faster]), space) is faster
    assert _choose_trigger(SearchResult(candidates=[fog, far], front=[fog, far]), space) is fog
