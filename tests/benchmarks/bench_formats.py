"""Speed of ``rocas diff`` on every input format against a plain read+decode (issue 36 item 6;
prints figures; not a test).

For each format, two whole processes on the same file:

- ``rocas diff F F --cmg CMG --json`` (the file against itself: every channel paired, every
  message read);
- a plain read+decode of every message with the fastest well-kept decoder for the format:
  rosbags' ROS 1 deserializer on ``rosbags.rosbag1``'s reader (ROS 1 bag), rosbags' CDR
  deserializer on ``rosbags.rosbag2``'s reader (rosbag2 .db3), protobuf (upb) on the record's
  sections for Cyber RT (there is no maintained Cyber reader to compare with: the framing is a
  16-byte head per section; the decoding is protobuf's), and the ``mcap`` reader with rosbags
  for an MCAP copy (ros1 profile).

Inputs: the real recordings in recordings/real, and "scaled" ones (``--scale-mb``, default
20 MB) built from their messages repeated over a longer span with shifted log times (the
same channels, schemas and payloads): the real files are under 1 MB, where process start-up
is all that is measured. Min and median of ``--repeats`` runs; the ratio is rocas / plain on
the medians.

Usage: python tests/benchmarks/bench_formats.py [--repeats 5] [--scale-mb 20] [--only NAME]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
REAL = ROOT / "recordings" / "real"

PLAIN_ROS1 = """
import sys
from rosbags.rosbag1 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
store = get_typestore(Stores.EMPTY)
n = 0
with Reader(sys.argv[1]) as r:
    for c in r.connections:
        store.register(get_types_from_msg(c.msgdef.data, c.msgtype))
    des = store.deserialize_ros1
    for c, t, raw in r.messages():
        des(raw, c.msgtype)
        n += 1
print(n)
"""

PLAIN_ROSBAG2 = """
import sys
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
store = get_typestore(Stores.EMPTY)
n = 0
with Reader(sys.argv[1]) as r:
    ok = []
    for c in r.connections:  # a definition rosbags cannot parse (a .srv text): left out
        try:
            store.register(get_types_from_msg(c.msgdef.data, c.msgtype))
            ok.append(c)
        except Exception:
            pass
    des = store.deserialize_cdr
    for c, t, raw in r.messages(ok):
        des(raw, c.msgtype)
        n += 1
print(n)
"""

PLAIN_CYBER = """
import struct, sys
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from rocas.recording.cyber import _record_classes, descriptor_set
cls = _record_classes()
classes = {}
n = 0
with open(sys.argv[1], 'rb') as f:
    data = f.read()
pos = 16 + 2048
while pos < len(data):
    kind, _, size = struct.unpack_from('<iiq', data, pos)
    body = data[pos + 16: pos + 16 + size]
    pos += 16 + size
    if kind == 4:
        ch = cls['Channel'].FromString(body)
        pool = descriptor_pool.DescriptorPool()
        for fd in descriptor_pb2.FileDescriptorSet.FromString(descriptor_set(ch.proto_desc)).file:
            pool.Add(fd)
        classes[ch.name] = message_factory.GetMessageClass(
            pool.FindMessageTypeByName(ch.message_type))
    elif kind == 2:
        for m in cls['ChunkBody'].FromString(body).messages:
            classes[m.channel_name].FromString(m.content)
            n += 1
print(n)
"""

PLAIN_MCAP_ROS1 = """
import sys
from mcap.reader import make_reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.msg import normalize_msgtype
store = get_typestore(Stores.EMPTY)
names = {}
n = 0
with open(sys.argv[1], 'rb') as f:
    for schema, channel, message in make_reader(f).iter_messages():
        name = names.get(schema.id)
        if name is None:
            name = names[schema.id] = normalize_msgtype(schema.name)
            store.register(get_types_from_msg(schema.data.decode(), name))
        store.deserialize_ros1(message.data, name)
        n += 1
print(n)
"""


def scaled_bag(src: Path, dst: Path, target: int) -> None:
    """A ROS 1 bag with ``src``'s connections and messages repeated to about ``target`` bytes."""
    from rosbags.rosbag1 import Reader, Writer

    with Reader(src) as r:
        msgs = list(r.messages())
        conns = list(r.connections)
        span = r.end_time - r.start_time + 10**8
    per = sum(len(m[2]) + 40 for m in msgs)
    copies = max(1, target // per)
    with Writer(dst) as w:
        out = {c.id: w.add_connection(c.topic, c.msgtype, msgdef=c.msgdef.data, md5sum=c.digest,
                                      callerid=c.ext.callerid, latching=c.ext.latching)
               for c in conns}
        for k in range(copies):
            for c, t, raw in msgs:
                w.write(out[c.id], t + k * span, raw)


def scaled_db3(bag: Path, dst_dir: Path, target: int) -> Path:
    """A rosbag2 (sqlite3) recording of the bag's messages converted to CDR, repeated to about
    ``target`` bytes; returns its .db3 file."""
    from rosbags.rosbag1 import Reader
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    with Reader(bag) as r:
        for c in r.connections:
            store.register(get_types_from_msg(c.msgdef.data, c.msgtype))
        msgs = []
        for c, t, raw in r.messages():
            try:  # rosbags cannot convert every ROS 1 message (/rosout's): those are left out
                msgs.append((c, t, store.ros1_to_cdr(raw, c.msgtype)))
            except Exception:
                continue
        span = r.end_time - r.start_time + 10**8
    per = sum(len(m[2]) + 40 for m in msgs)
    copies = max(1, target // per)
    with Writer(dst_dir, version=9, storage_plugin=StoragePlugin.SQLITE3) as w:
        out = {}
        for c, _, _ in msgs:
            if (c.topic, c.msgtype) not in out:
                out[(c.topic, c.msgtype)] = w.add_connection(c.topic, c.msgtype, typestore=store)
        for k in range(copies):
            for c, t, cdr in msgs:
                w.write(out[(c.topic, c.msgtype)], t + k * span, cdr)
    return next(dst_dir.glob("*.db3"))


def scaled_record(src: Path, dst: Path, target: int) -> None:
    """A Cyber RT record with ``src``'s channels and messages repeated to about ``target``
    bytes (chunks of about 1 MB; no index section: readers here walk the sections)."""
    import struct

    from rocas.recording.cyber import HEADER_BYTES, _record_classes

    cls = _record_classes()
    data = src.read_bytes()
    header = cls["Header"].FromString(data[16 : 16 + struct.unpack_from("<q", data, 8)[0]])
    channels, messages = [], []
    pos = 16 + HEADER_BYTES
    while pos < len(data):
        kind, _, size = struct.unpack_from("<iiq", data, pos)
        body = data[pos + 16 : pos + 16 + size]
        pos += 16 + size
        if kind == 4:
            channels.append(body)
        elif kind == 2:
            messages.extend(cls["ChunkBody"].FromString(body).messages)
    span = header.end_time - header.begin_time + 10**8
    per = sum(len(m.content) + 60 for m in messages)
    copies = max(1, target // per)
    out = bytearray()

    def section(kind: int, body: bytes) -> None:
        out.extend(struct.pack("<iiq", kind, 0, len(body)))
        out.extend(body)

    for body in channels:
        section(4, body)
    chunk = cls["ChunkBody"]()
    total = 0
    for k in range(copies):
        for m in messages:
            chunk.messages.add(channel_name=m.channel_name, time=m.time + k * span,
                               content=m.content)
            total += 1
            if chunk.ByteSize() > 1 << 20:
                head = cls["ChunkHeader"](message_number=len(chunk.messages))
                section(1, head.SerializeToString())
                section(2, chunk.SerializeToString())
                chunk = cls["ChunkBody"]()
    if len(chunk.messages):
        section(1, cls["ChunkHeader"](message_number=len(chunk.messages)).SerializeToString())
        section(2, chunk.SerializeToString())
    header.message_number = total
    header.end_time = header.begin_time + copies * span
    header.size = 16 + HEADER_BYTES + len(out)
    head = header.SerializeToString()
    dst.write_bytes(struct.pack("<iiq", 0, 0, len(head)) + head.ljust(HEADER_BYTES, b"\0")
                    + bytes(out))


def cmg_for(path: Path, dst: Path) -> Path:
    """A CMG file naming every topic of ``path`` as written by one module."""
    sys.path.insert(0, str(ROOT))
    from rocas.recording import open_recording

    rec = open_recording(path).scan()
    topics = sorted({c.topic for c in rec.channels.values()})
    counts = {t: st.messages for t, st in rec.report.channel_stats.items()}
    control = max(topics, key=lambda t: counts.get(t, 0))
    dst.write_text(json.dumps({"modules": {"stack": {"reads": [], "writes": topics}},
                               "control_channel": control}))
    return dst


def timed(argv: list[str], repeats: int) -> list[float]:
    env = {"PYTHONPATH": str(ROOT)}
    import os

    env = {**os.environ, **env}
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        done = subprocess.run(argv, capture_output=True, env=env, check=False)
        out.append(time.perf_counter() - t0)
        if done.returncode not in (0,):
            raise SystemExit(f"{' '.join(argv)} failed ({done.returncode}): "
                             f"{done.stderr.decode()[-500:]}")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--scale-mb", type=float, default=20.0)
    ap.add_argument("--only", help="run only the inputs whose name contains this")
    args = ap.parse_args()
    target = int(args.scale_mb * 1e6)
    py = sys.executable
    with tempfile.TemporaryDirectory(prefix="rocas-bench-formats-") as tmp:
        d = Path(tmp)
        print(f"building {args.scale_mb:g} MB inputs from recordings/real ...", flush=True)
        scaled_bag(REAL / "turtlesim_example.bag", d / "scaled.bag", target)
        db3 = scaled_db3(REAL / "turtlesim_example.bag", d / "scaled_rosbag2", target)
        scaled_record(REAL / "apollo_sim.record.00000", d / "scaled.record", target)
        from rocas.recording.annotate import annotate_recording

        annotate_recording(d / "scaled.bag", d / "scaled_bag.mcap", {})
        inputs = [
            ("ros1 bag (real, 0.9 MB)", REAL / "turtlesim_example.bag", PLAIN_ROS1),
            ("rosbag2 mcap dir (real, 0.02 MB)", REAL / "service_events_mcap", PLAIN_ROSBAG2),
            ("cyber record (real, 0.5 MB)", REAL / "apollo_sim.record.00000", PLAIN_CYBER),
            ("ros1 bag (scaled)", d / "scaled.bag", PLAIN_ROS1),
            ("rosbag2 .db3 (scaled)", db3, PLAIN_ROSBAG2),
            ("cyber record (scaled)", d / "scaled.record", PLAIN_CYBER),
            ("mcap ros1 (scaled)", d / "scaled_bag.mcap", PLAIN_MCAP_ROS1),
        ]
        print(f"{'input':32} {'MB':>6} {'rocas diff min/med [s]':>24} "
              f"{'plain min/med [s]':>20} {'ratio':>6}")
        for name, path, plain in inputs:
            if args.only and args.only not in name:
                continue
            size = (sum(p.stat().st_size for p in path.iterdir()) if path.is_dir()
                    else path.stat().st_size)
            cmg = cmg_for(path, d / f"cmg_{abs(hash(name))}.json")
            rocas_t = timed([py, "-m", "rocas", "diff", str(path), str(path), "--cmg", str(cmg),
                             "--json"], args.repeats)
            plain_t = timed([py, "-c", plain, str(path)], args.repeats)
            rm, pm = statistics.median(rocas_t), statistics.median(plain_t)
            print(f"{name:32} {size / 1e6:6.2f} {min(rocas_t):11.2f} /{rm:6.2f}      "
                  f"{min(plain_t):9.2f} /{pm:6.2f}  {rm / pm:6.2f}x", flush=True)


if __name__ == "__main__":
    main()
