"""Algorithm 1 on the paper's Appendix A example."""

import pytest

from rocas.analysis.cmg import CHANNEL, MODULE, build_cmg, parse_cmg
from rocas.analysis.pinpoint import find_initial_module

APOLLO = parse_cmg({"modules": {
    "perception": {"writes": ["/apollo/perception/obstacles"]},
    "prediction": {"reads": ["/apollo/perception/obstacles"], "writes": ["/apollo/prediction"]},
    "planning": {"reads": ["/apollo/perception/obstacles", "/apollo/prediction",
                           "/apollo/canbus/chassis"], "writes": ["/apollo/planning"]},
    "control": {"reads": ["/apollo/planning", "/apollo/canbus/chassis"],
                "writes": ["/apollo/control"]},
    "canbus": {"reads": ["/apollo/control"], "writes": ["/apollo/canbus/chassis"]},
}})
APPENDIX_A = {
    "/apollo/prediction": 4.5,
    "/apollo/planning": 7.0,
    "/apollo/canbus/chassis": 1.5,
    "/apollo/control": 7.1,
    "/apollo/perception/obstacles": None,
}


def _run(t_star, delta=3.0):
    return find_initial_module(build_cmg([], APOLLO), t_star, "/apollo/control", delta)


def test_appendix_a_finds_prediction_with_the_paper_walk():
    r = _run(APPENDIX_A)
    assert r.deviating_module == "prediction"
    assert r.path == ("/apollo/control", "control", "/apollo/planning", "planning",
                      "/apollo/prediction", "prediction")
    removed = {(e.source, e.target) for e in r.removed_edges}
    assert ((CHANNEL, "/apollo/canbus/chassis"), (MODULE, "control")) in removed
    assert "canbus" not in r.reachable
    assert "not reachable" in r.exclusions["canbus"]
    assert r.t_star[(MODULE, "canbus")] == 1.5


def test_module_t_star_is_the_min_over_written_channels():
    r = _run(APPENDIX_A)
    assert r.t_star[(MODULE, "planning")] == 7.0
    assert r.t_star[(MODULE, "perception")] is None


def test_a_small_delta_cuts_the_walk_short():
    r = _run(APPENDIX_A, delta=0.5)  # 4.5 is not within [6.5, 7.0]
    assert r.deviating_module == "planning"


def test_no_change_on_the_control_channel_starts_from_what_it_depends_on():
    # no window can be measured from an undefined t*: the earliest module the control channel
    # depends on is the answer, except canbus, which reads /apollo/control (its chassis change
    # at 1.5 s may be the vehicle's response to the commands)
    r = _run({**APPENDIX_A, "/apollo/control": None})
    assert r.deviating_module == "prediction"
    assert r.path == ("/apollo/control", "control", "/apollo/planning", "planning",
                      "/apollo/prediction", "prediction")
    assert "/apollo/control has no change point" in r.fallback
    assert "reads /apollo/control" in r.exclusions["canbus"]
    assert "later than prediction" in r.exclusions["planning"]


def test_the_paper_walk_has_no_fallback():
    assert _run(APPENDIX_A).fallback is None


def test_no_change_anywhere_means_no_module():
    r = _run(dict.fromkeys(APPENDIX_A))
    assert r.deviating_module is None
    assert r.path == ()


def test_commands_that_differ_from_the_start_are_explained_only_by_earlier_change_points():
    # /apollo/control differs from 0.1 s on, with no change point: prediction (0.1 s) can
    # explain it, planning (3.7 s) cannot, and canbus reads the commands
    t = {"/apollo/perception/obstacles": None, "/apollo/prediction": 0.1,
         "/apollo/planning": 3.7, "/apollo/control": None, "/apollo/canbus/chassis": 0.2}
    r = find_initial_module(build_cmg([], APOLLO), t, "/apollo/control", 3.0,
                            control_onset_s=0.1)
    assert r.deviating_module == "prediction"
    assert "differ from 0.1 s on" in r.fallback
    assert "outside [-2.9, 0.1] s" in r.exclusions["planning"]
    # nothing upstream departs before the commands do: no answer rather than a consequence
    late = {**t, "/apollo/prediction": 8.3}
    r = find_initial_module(build_cmg([], APOLLO), late, "/apollo/control", 3.0,
                            control_onset_s=0.1)
    assert r.deviating_module is None


def test_a_control_change_point_in_the_first_bin_walks_as_the_fallback():
    # a campaign A1 variant (ego 2.4 m from the stop line, the creeping car in view, the
    # reference's car faster from the start): every channel differs from 0.1-0.2 s; /control
    # has a change point only because the first bin (t = 0) is shared, planning's departure is
    # in its baseline (first change point 3.7 s), and the paper's walk stopped at control
    t = {"/apollo/perception/obstacles": None, "/apollo/prediction": 0.1,
         "/apollo/planning": 3.7, "/apollo/control": 0.1, "/apollo/canbus/chassis": 0.2}
    cmg = build_cmg([], APOLLO)
    paper = find_initial_module(cmg, t, "/apollo/control", 3.0, control_onset_s=0.1)
    assert paper.deviating_module == "control" and paper.fallback is None
    r = find_initial_module(cmg, t, "/apollo/control", 3.0, control_onset_s=0.1, bin_s=0.1)
    assert r.deviating_module == "prediction"
    assert "first bin after the start" in r.fallback
    assert "same change point as prediction" in r.exclusions["control"]
    assert "outside [-2.9, 0.1] s" in r.exclusions["planning"]
    assert "reads /apollo/control" in r.exclusions["canbus"]
    # a change point one bin later has a shared stretch before it: the paper's walk
    later = find_initial_module(cmg, {**t, "/apollo/control": 0.2, "/apollo/canbus/chassis": 0.3},
                                "/apollo/control", 3.0,
                                control_onset_s=0.2, bin_s=0.1)
    assert later.fallback is None and later.deviating_module == "control"


def test_fallback_ties_go_upstream():
    # perception and prediction depart in the same bin (the obstacle list and the forecasts
    # of a car that starts to slow down); the control channel never does
    r = _run({"/apollo/perception/obstacles": 5.3, "/apollo/prediction": 5.3,
              "/apollo/planning": 8.5, "/apollo/control": None, "/apollo/canbus/chassis": None})
    assert r.deviating_module == "perception"


def test_edge_window_is_inclusive():
    r = _run({**APPENDIX_A, "/apollo/prediction": 4.0})  # exactly t*(planning) - delta
    assert r.deviating_module == "prediction"


@pytest.mark.parametrize("order", [list(APPENDIX_A), list(reversed(APPENDIX_A))])
def test_result_does_not_depend_on_input_order(order):
    assert _run({k: APPENDIX_A[k] for k in order}).deviating_module == "prediction"


def test_same_bin_ties_go_to_the_module_farthest_upstream():
    # a whole pipeline reacting within one simulator tick: all change points in one bin
    tied = {"/apollo/prediction": 7.0, "/apollo/planning": 7.0, "/apollo/control": 7.0,
            "/apollo/canbus/chassis": None, "/apollo/perception/obstacles": None}
    r = _run(tied)
    assert r.deviating_module == "prediction"
    assert r.path[-1] == "prediction"
    assert r.exclusions["planning"] == (
        "reachable, with the same change point as prediction (7 s), but prediction is farther "
        "upstream from /apollo/control and deviations travel downstream"
    )
    assert "later than" not in r.exclusions["control"]


def test_exclusions_say_later_only_when_later_and_name_a_tie_by_name():
    r = _run(APPENDIX_A)
    assert r.exclusions["planning"] == (
        "reachable, but its change point (7 s) is later than prediction's (4.5 s)"
    )
    twins = parse_cmg({"modules": {
        "a": {"writes": ["/x"]}, "b": {"writes": ["/y"]},
        "ctl": {"reads": ["/x", "/y"], "writes": ["/cmd"]},
    }})
    r = find_initial_module(build_cmg([], twins), {"/x": 1.0, "/y": 1.0, "/cmd": 1.0}, "/cmd")
    assert r.deviating_module == "a"
    assert r.exclusions["b"] == (
        "reachable, with the same change point as a (1 s) at the same distance from /cmd; "
        "the tie goes to a by name"
    )


def _networkx_walk(cmg, t_star, control, delta):
    """Algorithm 1's reachable set, depths and walk computed with networkx on ``cmg.graph``
    (the walk rocas takes must be the one networkx's shortest_path takes). Without a change
    point on the control channel, the whole graph less the control channel's readers (with
    them when no other module departed)."""
    import networkx as nx

    start = (CHANNEL, control)
    fallback = start in cmg.graph and t_star[start] is None
    pruned = cmg.graph.copy()
    for u, v in cmg.graph.edges:
        tu, tv = t_star[u], t_star[v]
        if not fallback and (tu is None or tv is None or not tv - delta <= tu <= tv):
            pruned.remove_edge(u, v)
    rev = pruned.reverse(copy=False)
    if start not in rev:
        return frozenset(), {}, rev
    readers = set(cmg.graph.successors(start)) if fallback else set()
    reachable = frozenset(n for k, n in nx.descendants(rev, start)
                          if k == MODULE and (k, n) not in readers)
    if readers and not any(t_star[(MODULE, m)] is not None for m in reachable):
        # the commands are the same in both runs and nothing else departed: their readers
        # (the plant's own output) are named too
        reachable = frozenset(n for k, n in nx.descendants(rev, start) if k == MODULE)
    depth = nx.single_source_shortest_path_length(rev, start)
    return reachable, depth, rev


def test_walk_reachability_and_ties_match_networkx_on_random_graphs():
    """Many shortest walks tie in a CMG (a module writing two channels its reader reads); the
    walk must be networkx's, as before rocas stopped importing it for a diff."""
    import random

    import networkx as nx

    rng = random.Random(7)
    ties = 0
    for _ in range(400):
        n_mod, n_ch = rng.randint(2, 6), rng.randint(2, 7)
        chans = [f"/c{i}" for i in range(n_ch)]
        modules = {}
        for m in range(n_mod):
            modules[f"m{m}"] = {"reads": rng.sample(chans, rng.randint(0, min(3, n_ch))),
                                "writes": rng.sample(chans, rng.randint(1, 2))}
        cmg = build_cmg([], parse_cmg({"modules": modules}))
        t = {c: rng.choice([None, 1.0, 2.0, 2.5, 4.0]) for c in chans}
        control = rng.choice(chans)
        delta = rng.choice([1.0, 3.0])
        r = find_initial_module(cmg, t, control, delta, past_window=False)
        reachable, depth, rev = _networkx_walk(cmg, r.t_star, control, delta)
        assert r.reachable == reachable
        if r.deviating_module is None:
            continue
        target = (MODULE, r.deviating_module)
        expected = tuple(n for _, n in nx.shortest_path(rev, (CHANNEL, control), target))
        assert r.path == expected
        ties += len(list(nx.all_shortest_paths(rev, (CHANNEL, control), target))) > 1
        assert depth[target] == len(r.path) - 1
    assert ties >= 10  # the ties the test is about did occur


def test_a_walk_that_names_the_commands_writer_goes_on_from_an_earlier_input():
    # a generated A6 variant (other speeds): planning departs at 1.7 s, the commands only at
    # 5.0 s, the chassis after them; the paper's window [2, 5] s cut the walk at control,
    # which cannot be the first module to deviate when its input departed 3.3 s before it
    t = {"/apollo/perception/obstacles": None, "/apollo/prediction": None,
         "/apollo/planning": 1.7, "/apollo/control": 5.0, "/apollo/canbus/chassis": 5.1}
    r = _run(t)
    assert r.deviating_module == "planning"
    assert r.path == ("/apollo/control", "control", "/apollo/planning", "planning")
    assert "/apollo/planning departed earlier (1.7 s)" in r.fallback
    assert "more than 3 s before" in r.exclusions["control"]
    # from there the window holds again: prediction's departure 4 s before planning's stays out
    r = _run({**t, "/apollo/prediction": -2.3 + 0.0})
    assert r.deviating_module == "planning"
    # an input within the window is the paper's walk, unchanged
    r = _run({**t, "/apollo/planning": 2.5})
    assert r.deviating_module == "planning" and r.fallback is None


def test_the_commands_writer_stays_when_no_input_departed():
    t = {"/apollo/perception/obstacles": None, "/apollo/prediction": None,
         "/apollo/planning": None, "/apollo/control": 5.0, "/apollo/canbus/chassis": 5.1}
    r = _run(t)
    assert r.deviating_module == "control" and r.fallback is None


def test_a_walk_goes_on_past_a_named_modules_window_only_when_asked_and_from_whose_inputs():
    from rocas.analysis.pinpoint import past_the_window

    cmg = build_cmg([], APOLLO)
    # perception's obstacles depart 3.5 s before planning, the prediction 3.2 s before: both
    # outside the window, so the walk ends at planning
    t = {**APPENDIX_A, "/apollo/perception/obstacles": 3.5, "/apollo/prediction": 3.8}
    r = find_initial_module(cmg, t, "/apollo/control", 3.0)
    assert r.deviating_module == "planning" and r.fallback is None  # not the commands' writer
    # from perception's input only: the walk from the obstacles names perception
    p = past_the_window(cmg, t, r, 3.0, written_by=["perception"])
    assert p.deviating_module == "perception"
    assert p.path[-2:] == ("/apollo/perception/obstacles", "perception")
    assert "no input of planning departed within 3 s before planning departed (7 s)" in p.fallback
    # from any input: the latest, the prediction, whose own window reaches the obstacles
    assert past_the_window(cmg, t, r, 3.0).deviating_module == "perception"
    # only inputs that departed at most reach_s before planning (7 s): the obstacles (3.5 s)
    # are 3.5 s before, within 4 s; the prediction (3.8 s) too, the chassis (1.5 s) not
    assert past_the_window(cmg, t, r, 3.0, written_by=["perception"], reach_s=4.0) \
        .deviating_module == "perception"
    assert past_the_window(cmg, t, r, 3.0, written_by=["perception"], reach_s=3.4) is r
    assert past_the_window(cmg, t, r, 3.0, written_by=["canbus"], reach_s=4.0) is r
    # the chassis departed earlier too (1.5 s): from canbus's input the walk names canbus
    assert past_the_window(cmg, t, r, 3.0, written_by=["canbus"]).deviating_module == "canbus"
    # no input written by the module asked for, or none before the window: unchanged
    assert past_the_window(cmg, t, r, 3.0, written_by=["control"]) is r
    assert past_the_window(cmg, APPENDIX_A, _run(APPENDIX_A), 3.0, written_by=["perception"]) \
        .deviating_module == "prediction"


def test_a_reader_of_identical_commands_is_named_when_nothing_else_departed():
    # the commands are the same in both runs (no onset) and only canbus, which reads them,
    # departed: nothing else in the graph explains its change, so it is the answer
    t = dict.fromkeys(APPENDIX_A)
    t["/apollo/canbus/chassis"] = 1.5
    r = _run(t)
    assert r.deviating_module == "canbus"
    # when the commands differ, a reader's change may be the response to them: not named
    r = find_initial_module(build_cmg([], APOLLO), t, "/apollo/control", 3.0,
                            control_onset_s=1.4)
    assert r.deviating_module is None
