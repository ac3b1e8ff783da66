"""The CMG drawing: no two node boxes overlap, for every topology rocas meets in the tests."""

from pathlib import Path

import networkx as nx
import pytest
from foreign_stack import CONTROL, TOPOLOGY
from hypothesis import given, settings
from hypothesis import strategies as st
from ros2_mix import ROS2_CMG

from rocas.analysis.cmg import CHANNEL, MODULE, build_cmg, control_channel, parse_cmg
from rocas.recording import open_recording
from rocas.viz.cmg_layout import label_size, layered_layout, layers, node_boxes, overlapping_boxes
from rocas.viz.diff import node_label

RECORDINGS = sorted((Path(__file__).parents[2] / "recordings").glob("a*.mcap"))


def _walks(g: nx.DiGraph, control: str) -> list[list[tuple[str, str]]]:
    """Every walk Algorithm 1 could report: from the control channel to each module upstream."""
    start = (CHANNEL, control)
    rev = g.reverse(copy=False)
    paths = nx.single_source_shortest_path(rev, start) if start in rev else {}
    if start not in g:
        return [[]]
    return [[start]] + [p for n, p in sorted(paths.items()) if n[0] == MODULE]


def _assert_no_overlap(g: nx.DiGraph, control: str) -> None:
    for walk in _walks(g, control):
        labels = {n: node_label(n[1], 12.34) for n in g}
        pos = layered_layout(g, walk, labels)
        assert set(pos) == set(g)
        assert overlapping_boxes(node_boxes(pos, labels)) == []
        xs = [pos[n][0] for n in walk]
        assert xs == [0.0] * len(walk)  # the walk runs straight up the middle
        ys = [pos[n][1] for n in walk]
        assert ys == sorted(ys, reverse=True)  # from the control channel (bottom) upstream


def _graph_of(cmg_json) -> tuple[nx.DiGraph, str]:
    spec = parse_cmg(cmg_json)
    graph = build_cmg([], spec)
    return graph.graph, control_channel(graph, None, spec)


@pytest.mark.parametrize("path", RECORDINGS, ids=lambda p: p.stem)
def test_catalog_recordings_cmg_nodes_never_overlap(path):
    rec = open_recording(path).scan()
    graph = build_cmg(list(rec.channels.values()))
    _assert_no_overlap(graph.graph, control_channel(graph))


def test_third_party_topologies_nodes_never_overlap():
    acme = {"modules": {m: {"reads": list(r), "writes": list(w)} for m, (r, w) in TOPOLOGY.items()},
            "control_channel": CONTROL}
    for cmg in (acme, ROS2_CMG):
        _assert_no_overlap(*_graph_of(cmg))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 7), st.integers(0, 9), st.booleans()), min_size=1, max_size=30),
       st.integers(0, 9))
def test_random_topologies_nodes_never_overlap(edges, control):
    """Cycles, parts with no link to the control channel, long names: still no overlap."""
    g = nx.DiGraph()
    for m, c, writes in edges:
        mod, ch = (MODULE, f"module_{m}" * (1 + m % 3)), (CHANNEL, f"/topic/{c}/x" * (1 + c % 2))
        g.add_edge(*((mod, ch) if writes else (ch, mod)))
    ctrl = f"/topic/{control}/x" * (1 + control % 2)
    _assert_no_overlap(g, ctrl)


def test_layers_put_the_walk_at_its_index_and_upstream_nodes_above():
    g = nx.DiGraph([(("module", "a"), ("channel", "/a")), (("channel", "/a"), ("module", "b")),
                    (("module", "b"), ("channel", "/ctl")), (("module", "c"), ("channel", "/side"))])
    walk = [("channel", "/ctl"), ("module", "b"), ("channel", "/a"), ("module", "a")]
    lay = layers(g, walk)
    assert [lay[n] for n in walk] == [0, 1, 2, 3]
    assert ("module", "c") in lay and ("channel", "/side") in lay  # unlinked part still drawn


def test_long_names_break_after_a_separator():
    label = node_label("/perception/traffic_light", None)
    assert label.split("\n") == ["/perception/", "traffic_light", "t* = none"]
    assert label_size(label)[0] < label_size("/perception/traffic_light")[0]


def test_the_marks_frame_encloses_the_nodes_with_room_above_for_both_entity_paths():
    from rocas.viz.diff import MARKS_FRAME_TOP, marks_frame

    nodes = (-50.0, 10.0, 70.0, 400.0)
    x0, y0, x1, y1 = marks_frame(nodes)
    assert x0 < nodes[0] and x1 > nodes[2] and y1 > nodes[3]
    # the graph view writes each entity's path above its frame (y points down): a line apart
    assert nodes[1] - y0 == MARKS_FRAME_TOP >= 24.0


def test_the_view_opens_on_the_nodes_and_both_frames_with_their_entity_paths(tmp_path):
    from foreign_stack import make_pair

    from rocas.analysis import diff
    from rocas.viz.diff import ENTITY_PATH_LINE, cmg_drawing, marks_frame

    pair = make_pair(tmp_path, deviating="forecaster")
    d = cmg_drawing(diff(pair.accident, pair.reference))
    fx0, fy0, fx1, fy1 = marks_frame(d.node_extent)
    bx0, by0, bx1, by1 = d.bounds
    assert bx0 <= fx0 and bx1 >= fx1 and by1 >= fy1
    assert by0 <= fy0 - ENTITY_PATH_LINE  # the marks' entity path is inside the view
