"""Benchmark of ROS 2 (CDR) decoding against the protobuf path (prints figures; not a test).

Writes one scripted run of the built-in channel mix twice: as protobuf
(rocas.recording.synthetic) and as a ROS 2 bag written with mcap-ros2-support's Writer
(tests/ros2_mix.py; the same story, node names and message sizes of the same order).
Then, on each file's message payloads read once into memory:

- protobuf: mcap-protobuf-support's decoder (what rocas uses for protobuf channels);
- ROS 2 candidates, each on the same CDR payloads, when installed:
  mcap-ros2-support (``mcap_ros2``), its fork ``mcap_ros2_support_fast``, and ``rosbags``;
- end to end through rocas's reader (``Recording.decoded``) for both files.

Throughput is payload MB/s and messages/s; min and median of ``--repeats`` runs; ratios are
against the protobuf decoder measured in the same run.

Usage: python tests/benchmarks/bench_ros2_decode.py [--seconds 10] [--repeats 5]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mcap.reader import make_reader

from rocas.recording import open_recording
from rocas.recording.synthetic import MixConfig, write_mix_run

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/: the ROS 2 pair writer
from ros2_mix import Ros2MixConfig, write_ros2_run  # noqa: E402

Payloads = list[tuple[Callable[[bytes], Any], bytes]]


def payloads(path: Path, factory: Any) -> Payloads:
    """(decoder, bytes) of every message; decoders come from ``factory`` (built once)."""
    out: Payloads = []
    decoders: dict[int, Callable[[bytes], Any]] = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages():
            dec = decoders.get(channel.id)
            if dec is None:
                dec = decoders[channel.id] = factory(channel.message_encoding, schema)
            out.append((dec, bytes(message.data)))
    return out


def protobuf_factory() -> Callable[[str, Any], Callable[[bytes], Any]]:
    from mcap_protobuf.decoder import DecoderFactory

    f = DecoderFactory()
    return f.decoder_for


def mcap_ros2_factory() -> Callable[[str, Any], Callable[[bytes], Any]]:
    from mcap_ros2.decoder import DecoderFactory

    return DecoderFactory().decoder_for


def fast_factory() -> Callable[[str, Any], Callable[[bytes], Any]]:
    from mcap_ros2_support_fast.decoder import DecoderFactory

    return DecoderFactory().decoder_for


def rosbags_factory() -> Callable[[str, Any], Callable[[bytes], Any]]:
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)

    def decoder_for(_: str, schema: Any) -> Callable[[bytes], Any]:
        store.register(get_types_from_msg(schema.data.decode(), schema.name))
        name = schema.name
        return lambda data: store.deserialize_cdr(data, name)

    return decoder_for


def timed(fn: Callable[[], Any], repeats: int) -> tuple[float, float]:
    runs = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        runs.append(time.perf_counter() - t)
    return min(runs), statistics.median(runs)


def decode_all(items: Payloads) -> None:
    for dec, data in items:
        dec(data)


def rocas_decoded(path: Path) -> None:
    for _ in open_recording(path).decoded():
        pass


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=10.0, help="length of each run [s]")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        pb = Path(tmp) / "mix.mcap"
        ros2 = Path(tmp) / "ros2.mcap"
        write_mix_run(pb, accident=False, cfg=MixConfig(duration_s=args.seconds))
        write_ros2_run(ros2, accident=False, cfg=Ros2MixConfig(duration_s=args.seconds))
        rows: list[tuple[str, int, int, float, float]] = []
        base = payloads(pb, protobuf_factory())
        pb_bytes = sum(len(d) for _, d in base)
        lo, med = timed(lambda: decode_all(base), args.repeats)
        rows.append(("protobuf (mcap-protobuf-support)", len(base), pb_bytes, lo, med))
        candidates = (("mcap-ros2-support", mcap_ros2_factory),
                      ("mcap-ros2-support-fast", fast_factory),
                      ("rosbags", rosbags_factory))
        ros2_bytes = 0
        for name, make in candidates:
            try:
                items = payloads(ros2, make())
            except ImportError:
                print(f"{name}: not installed, skipped")
                continue
            ros2_bytes = sum(len(d) for _, d in items)
            lo, med = timed(lambda items=items: decode_all(items), args.repeats)
            rows.append((f"ROS 2 CDR ({name})", len(items), ros2_bytes, lo, med))
        for label, path, nbytes in (("rocas reader, protobuf file", pb, pb_bytes),
                                    ("rocas reader, ROS 2 file", ros2, ros2_bytes)):
            n = sum(1 for _ in open_recording(path).decoded())
            lo, med = timed(lambda path=path: rocas_decoded(path), args.repeats)
            rows.append((label, n, nbytes, lo, med))
        base_med = rows[0][4] / rows[0][1]  # seconds per message, protobuf
        print(f"{args.seconds:g} s runs, {args.repeats} repeats (min / median)")
        print(f"{'decoder':<40} {'msgs':>6} {'MB':>6} {'min s':>7} {'med s':>7} "
              f"{'MB/s':>7} {'msg/s':>8} {'x pb/msg':>8}")
        for name, n, nbytes, lo, med in rows:
            print(f"{name:<40} {n:>6} {nbytes / 1e6:>6.2f} {lo:>7.3f} {med:>7.3f} "
                  f"{nbytes / 1e6 / med:>7.1f} {n / med:>8.0f} {med / n / base_med:>8.1f}")


if __name__ == "__main__":
    main()
