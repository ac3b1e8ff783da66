"""Hostile names: a recording pair whose topic and module names are rich markup and terminal
escape sequences, made by copying a foreign_stack pair with its names replaced."""

from __future__ import annotations

from pathlib import Path

from mcap.reader import make_reader
from mcap.writer import Writer

#: a module whose name rewrites the terminal line into a false answer
SPOOF = "tracker\r\x1b[2KInitial deviating module: planning"
#: names that end or open rich markup
MARKUP = "fore[/]caster[bold]"
TOPIC = "/fusion/[/tracks\x1b[31m"

MODULES = {"tracker": SPOOF, "forecaster": MARKUP}
TOPICS = {"/fusion/tracks": TOPIC, "/fusion/forecast": "/fusion/[bold]forecast[/bold]"}


def _names(value: str) -> str:
    return ",".join(MODULES.get(m, m) for m in value.split(","))


def rename(src: Path, dst: Path) -> Path:
    """``src`` copied to ``dst`` with TOPICS and MODULES replaced (channel topics and the
    rocas.writers / rocas.readers metadata)."""
    with open(src, "rb") as f_in, open(dst, "wb") as f_out:
        reader = make_reader(f_in)
        writer = Writer(f_out)
        writer.start(profile="", library="tests/hostile.py")
        schemas: dict[int, int] = {}
        channels: dict[int, int] = {}
        for schema, channel, message in reader.iter_messages():
            if schema is not None and schema.id not in schemas:
                schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                meta = {k: _names(v) if k in ("rocas.writers", "rocas.readers") else v
                        for k, v in channel.metadata.items()}
                channels[channel.id] = writer.register_channel(
                    TOPICS.get(channel.topic, channel.topic), channel.message_encoding,
                    schemas.get(schema.id, 0) if schema is not None else 0, meta)
            writer.add_message(channels[channel.id], message.log_time, message.data,
                               message.publish_time, message.sequence)
        writer.finish()
    return dst


def hostile_pair(directory: Path) -> tuple[Path, Path]:
    """An accident/reference pair (``tracker`` deviates first, under its SPOOF name)."""
    from foreign_stack import make_pair

    directory.mkdir(parents=True, exist_ok=True)
    pair = make_pair(directory, deviating="tracker")
    return (rename(pair.accident, directory / "hostile_accident.mcap"),
            rename(pair.reference, directory / "hostile_reference.mcap"))
