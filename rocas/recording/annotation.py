"""What an annotated copy changes on a channel, and what the copy reports.

Shared by the two ways a copy is made: :mod:`rocas.recording.annotate` (an MCAP file copied
record by record) and :mod:`rocas.recording.convert` (another format written out as MCAP).
Both set a channel's topology with :func:`annotated_metadata` and return an
:class:`AnnotateReport`; neither imports the other for it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from rocas.recording.topology import (
    CONTROL_ROLE,
    READERS_KEY,
    ROLE_KEY,
    WRITERS_KEY,
    join_modules,
)


@dataclass(frozen=True)
class ChannelAnnotation:
    """The modules that write and read one channel.

    An empty side keeps what the recording says (like ``--cmg``, which only replaces the
    writers or readers it names).
    """

    writers: tuple[str, ...] = ()
    readers: tuple[str, ...] = ()


@dataclass(frozen=True)
class AnnotateReport:
    """What a copy (:func:`rocas.recording.annotate.annotate_recording`,
    :func:`rocas.recording.convert.write_mcap`) copied and changed.

    Attributes:
        source: the input path.
        output: the output path.
        profile: the MCAP profile copied from the header (e.g. ``"ros1"``, ``""``).
        compression: chunk compression of the output: ``"zstd"``, ``"lz4"``, ``""`` (chunked,
            uncompressed) or ``None`` (unchunked file).
        schemas: schema records copied.
        channels: channel records copied.
        messages: message records copied.
        attachments: attachment records copied.
        metadata: metadata records copied.
        annotated: topics whose channel metadata was changed.
        control_channel: the channel marked ``rocas.role = control``, if one was asked for.
        missing: topics named in the annotations that the recording does not have.
    """

    source: str
    output: str
    profile: str
    compression: str | None
    schemas: int
    channels: int
    messages: int
    attachments: int
    metadata: int
    annotated: tuple[str, ...]
    control_channel: str | None
    missing: tuple[str, ...] = field(default=())


def annotated_metadata(
    metadata: Mapping[str, str],
    topic: str,
    annotation: ChannelAnnotation | None,
    control_channel: str | None,
) -> dict[str, str]:
    """The metadata a channel gets in the annotated file (other keys are kept as they are).

    Args:
        metadata: the channel's metadata in the input.
        topic: the channel's topic.
        annotation: its writers/readers, or None to keep the recorded ones.
        control_channel: when given, this topic gets ``rocas.role = control`` and every
            other channel loses a ``control`` role.
    """
    out = dict(metadata)
    if annotation is not None:
        for key, modules in ((WRITERS_KEY, annotation.writers), (READERS_KEY, annotation.readers)):
            if value := join_modules(modules):
                out[key] = value
    if control_channel is not None:
        if topic == control_channel:
            out[ROLE_KEY] = CONTROL_ROLE
        elif out.get(ROLE_KEY, "").strip().lower() == CONTROL_ROLE:
            del out[ROLE_KEY]
    return out
