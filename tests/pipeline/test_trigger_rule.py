"""The rule that picks the triggering entity from the physical search's Pareto front."""


def test_the_trigger_rule_prefers_changing_a_property_to_removing_the_entity():
    from rocas.pipeline.analyze import _choose_trigger
    from rocas.pipeline.physical import physical_space
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
