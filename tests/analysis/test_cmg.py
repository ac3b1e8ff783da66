"""The CMG: precedence of --cmg / metadata / callerid, union over a topic's channels, JSON."""

from __future__ import annotations

import json

import pytest

from rocas.analysis.cmg import (
    ChannelModuleGraph,
    build_cmg,
    control_channel,
    load_cmg,
    parse_cmg,
    resolve_topology,
)
from rocas.errors import InputError, TopologyError
from rocas.recording.annotation import ChannelAnnotation
from rocas.recording.model import ChannelInfo


def chan(cid: int, topic: str, **meta: str) -> ChannelInfo:
    meta = {k.replace("_", "."): v for k, v in meta.items()}
    return ChannelInfo(cid, topic, "protobuf", "x.Y", "protobuf", b"", meta)


STACK = [
    chan(1, "/obj", rocas_writers="perception", rocas_readers="planning"),
    chan(2, "/plan", rocas_writers="planning", rocas_readers="control"),
    chan(3, "/cmd", rocas_writers="control", rocas_role="control"),
]


def test_metadata_is_the_source_when_there_is_no_cmg_file():
    topo = resolve_topology(STACK)
    assert topo["/plan"].writers == ("planning",)
    assert topo["/plan"].readers == ("control",)
    assert (topo["/plan"].writers_source, topo["/plan"].readers_source) == ("metadata",) * 2
    assert topo["/cmd"].is_control and topo["/cmd"].readers_source == "missing"
    graph = build_cmg(STACK)
    assert graph.modules == ["control", "perception", "planning"]
    assert graph.channels_written_by("planning") == ["/plan"]
    assert control_channel(graph) == "/cmd"


def test_callerid_names_the_writer_only_when_rocas_writers_is_absent():
    channels = [
        chan(1, "/scan", callerid="/lidar_driver"),
        chan(2, "/odom", callerid="/base", rocas_writers="odometry"),
    ]
    topo = resolve_topology(channels)
    assert topo["/scan"].writers == ("/lidar_driver",)
    assert topo["/scan"].writers_source == "callerid"
    assert topo["/odom"].writers == ("odometry",)
    assert topo["/odom"].writers_source == "metadata"


def test_a_topic_with_several_publishers_gets_every_callerid():
    # a ROS 1 bag converted to MCAP: one channel per (topic, publisher)
    channels = [chan(1, "/cmd_vel", callerid="/teleop"), chan(2, "/cmd_vel", callerid="/nav")]
    topo = resolve_topology(channels)
    assert topo["/cmd_vel"].writers == ("/teleop", "/nav")


def test_cmg_file_overrides_the_channels_it_names_and_the_control_channel():
    spec = parse_cmg({
        "modules": {"planner2": {"reads": ["/obj"], "writes": ["/plan"]}},
        "control_channel": "/plan",
    })
    topo = resolve_topology(STACK, spec)
    assert topo["/plan"].writers == ("planner2",) and topo["/plan"].writers_source == "cmg"
    # the file names no reader of /plan: the recorded readers stay
    assert topo["/plan"].readers == ("control",) and topo["/plan"].readers_source == "metadata"
    assert topo["/obj"].readers == ("planner2",)
    assert topo["/cmd"].writers == ("control",) and topo["/cmd"].writers_source == "metadata"
    assert [t for t, c in topo.items() if c.is_control] == ["/plan"]
    assert control_channel(build_cmg(STACK, spec), None, spec) == "/plan"


def test_channels_only_the_cmg_file_names_are_flagged_not_fatal():
    spec = parse_cmg({"modules": {"m": {"writes": ["/ghost", "/obj"]}},
                      "control_channel": "/nowhere"})
    topo = resolve_topology(STACK, spec)
    assert topo["/ghost"].in_recording is False and topo["/obj"].in_recording is True
    assert spec.missing_channels(c.topic for c in STACK) == ["/ghost", "/nowhere"]
    kept = spec.restricted_to(c.topic for c in STACK)  # what rocas diff builds the graph from
    graph = build_cmg(STACK, kept)
    assert "/ghost" not in graph.channels and graph.channels_written_by("m") == ["/obj"]
    with pytest.raises(TopologyError, match="'/nowhere' .from <cmg>. is not in the recording"):
        control_channel(graph, None, kept)


def test_annotations_give_each_named_channel_its_writers_and_readers():
    spec = parse_cmg({"modules": {"a": {"writes": ["/x"]}, "b": {"reads": ["/x", "/y"]}}})
    assert spec.annotations() == {
        "/x": ChannelAnnotation(writers=("a",), readers=("b",)),
        "/y": ChannelAnnotation(writers=(), readers=("b",)),
    }


def test_a_recording_without_topology_is_refused_by_build_cmg():
    with pytest.raises(TopologyError, match="no channel topology") as info:
        build_cmg([chan(1, "/a"), chan(2, "/b")])
    assert "rocas annotate" in info.value.hint


def test_json_output_reads_back_as_a_cmg_file(tmp_path):
    graph = build_cmg(STACK)
    doc = graph.to_json()
    assert doc["control_channel"] == "/cmd"
    assert {c["topic"]: c["writers_source"] for c in doc["channels"]}["/obj"] == "metadata"
    path = tmp_path / "cmg.json"
    path.write_text(json.dumps(doc))
    spec = load_cmg(path)
    again = ChannelModuleGraph.from_topology(resolve_topology(STACK, spec))
    assert set(again.graph.edges) == set(graph.graph.edges)
    assert control_channel(again, None, spec) == "/cmd"


def test_the_keys_rocas_cmg_adds_are_ignored_when_read_back():
    spec = parse_cmg({
        "modules": {"m": {"writes": ["/cmd"]}}, "control_channel": "/cmd",
        "channels": [], "recording": "r.mcap", "control_source": "metadata",
        "notes": ["a note"], "hints": [],
    })
    assert spec.writes == {"m": ("/cmd",)} and spec.control_channel == "/cmd"


def test_dot_marks_the_control_channel():
    dot = build_cmg(STACK).to_dot()
    assert '"channel:/cmd" [label="/cmd", shape=box, style=bold];' in dot
    assert '"module:planning" -> "channel:/plan";' in dot


def test_dot_escapes_quotes_backslashes_and_line_breaks_in_names():
    import re

    odd_topic, odd_module = '/cam "front"\\raw', 'drv"x\\'
    graph = build_cmg([chan(1, odd_topic, rocas_writers=odd_module, rocas_readers="a\nb",
                            rocas_role="control")])
    dot = graph.to_dot()
    quoted = re.compile(r'"((?:[^"\\\n]|\\.)*)"')  # a DOT quoted string, escapes allowed
    names = set()
    for line in dot.splitlines()[2:-1]:
        # with the quoted strings taken out, only DOT syntax is left: no stray quote
        rest = quoted.sub("S", line)
        assert re.fullmatch(r"  S( \[label=S, shape=(box|ellipse)(, style=bold)?\]| -> S);",
                            rest), line
        names |= {re.sub(r"\\(.)", lambda m: {"n": "\n"}.get(m[1], m[1]), q)
                  for q in quoted.findall(line)}
    assert {f"channel:{odd_topic}", f"module:{odd_module}", "module:a\nb", odd_topic} <= names


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("{not json", "not valid JSON"),
        ('{"modules": []}', "'modules' must be an object"),
        ('{"modules": {"a": {"writes": "/x"}}}', "modules.a.writes must be a list"),
        ('{"modules": {}, "extra": 1}', "unknown key 'extra'"),
        ('{"modules": {}, "control_chanel": "/cmd", "notes": []}', "unknown key 'control_chanel'"),
    ],
)
def test_bad_cmg_files_say_what_is_wrong(tmp_path, text, needle):
    path = tmp_path / "bad.json"
    path.write_text(text)
    with pytest.raises(InputError, match=needle):
        load_cmg(path)


def test_missing_cmg_file(tmp_path):
    with pytest.raises(InputError, match="no such CMG file"):
        load_cmg(tmp_path / "nope.json")
