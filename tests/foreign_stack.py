"""Recording pairs from a made-up stack ("acme") that is nothing like rocas's ADS.

Its protobuf schemas are built at run time (no generated code, other names, nesting, a
map field, enums), one channel is JSON, rates differ per channel, the two recordings
start at different absolute times, and some fields carry noise in both runs. In the
accident run one module starts to deviate at ``deviate_at_s`` and its consumers follow
with a lag, so the initial deviating module is known by construction. A distractor
channel (/vehicle/state) deviates early, as /apollo/canbus/chassis does in the paper's
Appendix A, and Algorithm 1 must exclude it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from mcap.writer import CompressionType, Writer

from rocas.recording.writer import register_protobuf_channel

F = descriptor_pb2.FieldDescriptorProto

# module -> (reads, writes); rates in Hz per channel
TOPOLOGY = {
    "lidar": ((), ("/sensing/cloud",)),
    "tracker": (("/sensing/cloud",), ("/fusion/tracks",)),
    "forecaster": (("/fusion/tracks",), ("/fusion/forecast",)),
    "behaviour": (("/fusion/forecast", "/vehicle/state"), ("/behaviour/plan",)),
    "actuator": (("/behaviour/plan", "/vehicle/state"), ("/vehicle/actuation",)),
    "vehicle": (("/vehicle/actuation",), ("/vehicle/state",)),
    "diag": ((), ("/diag/status",)),
}
CONTROL = "/vehicle/actuation"
RATES = {
    "/sensing/cloud": 20,
    "/fusion/tracks": 10,
    "/fusion/forecast": 5,
    "/behaviour/plan": 10,
    "/vehicle/actuation": 50,
    "/vehicle/state": 50,
    "/diag/status": 1,
}
# how long after the deviating module each downstream module follows [s]
CHAIN = ["tracker", "forecaster", "behaviour", "actuator"]
LAG_S = 0.6


def _field(msg, name, number, ftype, label=F.LABEL_OPTIONAL, type_name=None):
    f = msg.field.add(name=name, number=number, type=ftype, label=label)
    if type_name:
        f.type_name = type_name


def build_classes(extra_plan_field: bool = False) -> dict[str, type]:
    """The acme message classes, in a fresh descriptor pool."""
    fd = descriptor_pb2.FileDescriptorProto(name="acme/av.proto", package="acme.av",
                                            syntax="proto3")
    stamp = fd.message_type.add(name="Stamp")
    _field(stamp, "sec", 1, F.TYPE_INT64)
    _field(stamp, "nsec", 2, F.TYPE_INT32)
    vec = fd.message_type.add(name="Vec")
    _field(vec, "x", 1, F.TYPE_DOUBLE)
    _field(vec, "y", 2, F.TYPE_DOUBLE)
    cloud = fd.message_type.add(name="PointCloud")
    _field(cloud, "stamp", 1, F.TYPE_MESSAGE, type_name=".acme.av.Stamp")
    _field(cloud, "ranges", 2, F.TYPE_FLOAT, F.LABEL_REPEATED)
    _field(cloud, "ring", 3, F.TYPE_INT32)
    track = fd.message_type.add(name="Track")
    _field(track, "uid", 1, F.TYPE_UINT32)
    _field(track, "pos", 2, F.TYPE_MESSAGE, type_name=".acme.av.Vec")
    _field(track, "vel", 3, F.TYPE_MESSAGE, type_name=".acme.av.Vec")
    _field(track, "label", 4, F.TYPE_STRING)
    tracks = fd.message_type.add(name="TrackList")
    _field(tracks, "stamp", 1, F.TYPE_MESSAGE, type_name=".acme.av.Stamp")
    _field(tracks, "tracks", 2, F.TYPE_MESSAGE, F.LABEL_REPEATED, ".acme.av.Track")
    path = fd.message_type.add(name="Path")
    _field(path, "uid", 1, F.TYPE_UINT32)
    _field(path, "points", 2, F.TYPE_MESSAGE, F.LABEL_REPEATED, ".acme.av.Vec")
    _field(path, "prob", 3, F.TYPE_DOUBLE)
    forecast = fd.message_type.add(name="Forecast")
    _field(forecast, "stamp", 1, F.TYPE_MESSAGE, type_name=".acme.av.Stamp")
    _field(forecast, "paths", 2, F.TYPE_MESSAGE, F.LABEL_REPEATED, ".acme.av.Path")
    behaviour = fd.enum_type.add(name="Behaviour")
    for i, n in enumerate(["KEEP", "SLOW", "HALT"]):
        behaviour.value.add(name=n, number=i)
    plan = fd.message_type.add(name="Plan")
    _field(plan, "stamp", 1, F.TYPE_MESSAGE, type_name=".acme.av.Stamp")
    _field(plan, "waypoints", 2, F.TYPE_MESSAGE, F.LABEL_REPEATED, ".acme.av.Vec")
    _field(plan, "behaviour", 3, F.TYPE_ENUM, type_name=".acme.av.Behaviour")
    entry = plan.nested_type.add(name="CostsEntry")
    entry.options.map_entry = True
    _field(entry, "key", 1, F.TYPE_STRING)
    _field(entry, "value", 2, F.TYPE_DOUBLE)
    _field(plan, "costs", 4, F.TYPE_MESSAGE, F.LABEL_REPEATED, ".acme.av.Plan.CostsEntry")
    if extra_plan_field:
        _field(plan, "comment", 5, F.TYPE_STRING)
    act = fd.message_type.add(name="Actuation")
    _field(act, "stamp", 1, F.TYPE_MESSAGE, type_name=".acme.av.Stamp")
    _field(act, "accel", 2, F.TYPE_DOUBLE)
    _field(act, "steer", 3, F.TYPE_DOUBLE)
    _field(act, "emergency", 4, F.TYPE_BOOL)
    state = fd.message_type.add(name="VehicleState")
    _field(state, "stamp", 1, F.TYPE_MESSAGE, type_name=".acme.av.Stamp")
    _field(state, "speed", 2, F.TYPE_DOUBLE)
    _field(state, "yaw", 3, F.TYPE_DOUBLE)
    pool = descriptor_pool.DescriptorPool()
    pool.Add(fd)
    names = ["PointCloud", "TrackList", "Forecast", "Plan", "Actuation", "VehicleState"]
    return {n: message_factory.GetMessageClass(pool.FindMessageTypeByName(f"acme.av.{n}"))
            for n in names}


TYPES = {
    "/sensing/cloud": "PointCloud",
    "/fusion/tracks": "TrackList",
    "/fusion/forecast": "Forecast",
    "/behaviour/plan": "Plan",
    "/vehicle/actuation": "Actuation",
    "/vehicle/state": "VehicleState",
}


@dataclass(frozen=True)
class Pair:
    """A generated accident/reference pair and what is known about it."""

    accident: Path
    reference: Path
    deviating_module: str | None
    control_channel: str = CONTROL


def _onset(deviating: str | None, deviate_at_s: float) -> dict[str, float]:
    """Time each module starts to deviate in the accident run [s]."""
    if deviating is None:
        return {}
    start = CHAIN.index(deviating)
    return {m: deviate_at_s + LAG_S * (i - start) for i, m in enumerate(CHAIN) if i >= start}


def write_run(
    path: Path,
    *,
    accident: bool,
    deviating: str | None = "forecaster",
    deviate_at_s: float = 6.0,
    duration_s: float = 12.0,
    start_sec: int = 1_700_000_000,
    seed: int = 0,
    topology: bool = True,
    distractor_at_s: float | None = 1.5,
    extra_plan_field: bool = False,
    compression: CompressionType = CompressionType.ZSTD,
) -> None:
    """Write one run of the acme stack to ``path``."""
    classes = build_classes(extra_plan_field)
    onset = _onset(deviating, deviate_at_s) if accident else {}
    rng = np.random.default_rng(seed + (1000 if accident else 0))
    readers: dict[str, list[str]] = {}
    for m, (reads, _) in TOPOLOGY.items():
        for t in reads:
            readers.setdefault(t, []).append(m)
    with open(path, "wb") as f:
        w = Writer(f, compression=compression, chunk_size=64 * 1024)
        w.start(profile="", library="acme-logger")
        ids: dict[str, int] = {}
        schema_ids: dict[str, int] = {}
        for module, (_, writes) in TOPOLOGY.items():
            for topic in writes:
                role = "control" if topic == CONTROL else None
                kw = dict(writers=[module], readers=readers.get(topic, []), role=role)
                if not topology:
                    kw = {}
                if topic in TYPES:
                    ids[topic] = register_protobuf_channel(
                        w, topic, classes[TYPES[topic]], schema_ids=schema_ids, **kw
                    )
                else:
                    sid = w.register_schema("acme.Status", "jsonschema", b"{}")
                    meta = {}
                    if topology:
                        meta = {"rocas.writers": module}
                    ids[topic] = w.register_channel(topic, "json", sid, meta)
        events = []
        phase_rng = np.random.default_rng(seed)  # the stack's timing: same in both runs
        for topic, hz in RATES.items():
            n = int(duration_s * hz)
            phase = phase_rng.uniform(0.0, 1.0 / hz)
            # publication jitter of +-2 ms, independent in the two runs
            offs = rng.uniform(-0.002, 0.002, size=n)
            events += [(0.01 + phase + i / hz + offs[i], topic, i) for i in range(n)]
        events.sort()
        seq = dict.fromkeys(RATES, 0)
        for t, topic, i in events:
            abs_t = start_sec + t
            stamp = {"sec": int(abs_t), "nsec": int((abs_t % 1) * 1e9)}
            writer_module = next(m for m, (_, ws) in TOPOLOGY.items() if topic in ws)
            dev = writer_module in onset and t >= onset[writer_module]
            msg = _message(classes, topic, i, t, stamp, dev, rng,
                           distractor=accident and distractor_at_s is not None
                           and topic == "/vehicle/state" and t >= distractor_at_s)
            data = json.dumps(msg).encode() if isinstance(msg, dict) else msg.SerializeToString()
            w.add_message(ids[topic], log_time=int(abs_t * 1e9), publish_time=int(abs_t * 1e9),
                          data=data, sequence=seq[topic])
            seq[topic] += 1
        w.finish()


def _message(classes, topic, i, t, stamp, dev, rng, distractor):
    if topic == "/diag/status":
        return {"ok": True, "uptime_s": int(t), "modules": ["lidar", "tracker"]}
    msg = classes[TYPES[topic]]()
    msg.stamp.sec = stamp["sec"]
    msg.stamp.nsec = stamp["nsec"]
    if topic == "/sensing/cloud":
        ranges = np.round(np.linspace(1, 50, 32), 2)
        noisy = rng.random(32) < 0.1  # sensor noise, independent in both runs
        ranges[noisy] += rng.normal(0, 0.05, noisy.sum())
        msg.ranges.extend(ranges.astype(np.float32).tolist())
        msg.ring = i % 16
    elif topic == "/fusion/tracks":
        for k in range(4):
            tr = msg.tracks.add(uid=k, label="car" if k % 2 else "bike")
            tr.pos.x, tr.pos.y = 10.0 * k + t, 2.0 * k
            tr.vel.x, tr.vel.y = 1.0, 0.0
            if dev:
                tr.pos.x += 0.7 + k
                tr.vel.x = 1.5
                tr.label = "truck"
    elif topic == "/fusion/forecast":
        for k in range(4):
            p = msg.paths.add(uid=k, prob=0.9)
            for s in range(6):
                p.points.add(x=10.0 * k + t + s, y=2.0 * k + (0.5 * s if dev else 0.0))
            if dev:
                p.prob = 0.4
    elif topic == "/behaviour/plan":
        for s in range(10):
            msg.waypoints.add(x=t + s, y=0.0 if not dev else 0.3 * s)
        msg.behaviour = 2 if dev else 0
        msg.costs["comfort"] = 1.0
        msg.costs["safety"] = 5.0 if dev else 1.0
    elif topic == "/vehicle/actuation":
        msg.accel = -6.0 if dev else 0.5
        msg.steer = 0.2 if dev else 0.0
        msg.emergency = dev
    elif topic == "/vehicle/state":
        msg.speed = round(10.0 + 0.1 * (i % 7), 3) + (0.5 if distractor else 0.0)
        msg.yaw = 0.2 if distractor else 0.0
    return msg


def make_pair(
    directory: Path, name: str = "acme", *, deviating: str | None = "forecaster",
    seed: int = 0, **kw,
) -> Pair:
    """Write an accident/reference pair into ``directory``."""
    acc = directory / f"{name}_accident.mcap"
    ref = directory / f"{name}_reference.mcap"
    ref_kw = {k: v for k, v in kw.items() if k != "extra_plan_field"}
    write_run(acc, accident=True, deviating=deviating, seed=seed,
              start_sec=1_700_000_000, **kw)
    write_run(ref, accident=False, deviating=deviating, seed=seed, start_sec=1_700_086_400,
              compression=CompressionType.LZ4, **ref_kw)
    return Pair(acc, ref, deviating)
