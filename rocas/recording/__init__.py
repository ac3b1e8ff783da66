"""The MCAP boundary: a streaming reader, a writer and the topology contract."""

from typing import TYPE_CHECKING

from rocas._lazy import lazy_exports

if TYPE_CHECKING:
    from rocas.recording.annotate import (
        AnnotateReport,
        ChannelAnnotation,
        annotate_recording,
        read_channels,
    )
    from rocas.recording.attach import attach_channel
    from rocas.recording.reader import (
        ChannelInfo,
        ChannelStats,
        DecodedMessage,
        RawMessage,
        ReadReport,
        Recording,
        open_recording,
    )
    from rocas.recording.writer import RecordingWriter, register_protobuf_channel

from rocas.recording.topology import (
    CONTROL_ROLE,
    READERS_KEY,
    ROLE_KEY,
    ROS1_CALLERID_KEY,
    WRITERS_KEY,
    split_modules,
    topology_metadata,
)

# loaded on first use, so that a reader (``rocas diff``) does not import the writer's modules
_LAZY = {
    **dict.fromkeys(("AnnotateReport", "ChannelAnnotation", "annotate_recording",
                     "read_channels"), "rocas.recording.annotate"),
    "attach_channel": "rocas.recording.attach",
    **dict.fromkeys(("ChannelInfo", "ChannelStats", "DecodedMessage", "RawMessage", "ReadReport",
                     "Recording", "open_recording"), "rocas.recording.reader"),
    **dict.fromkeys(("RecordingWriter", "register_protobuf_channel"), "rocas.recording.writer"),
}


__getattr__, __dir__ = lazy_exports(__name__, globals(), _LAZY)


__all__ = [
    "CONTROL_ROLE",
    "READERS_KEY",
    "ROLE_KEY",
    "ROS1_CALLERID_KEY",
    "WRITERS_KEY",
    "ChannelInfo",
    "ChannelStats",
    "DecodedMessage",
    "RawMessage",
    "ReadReport",
    "Recording",
    "RecordingWriter",
    "open_recording",
    "register_protobuf_channel",
    "split_modules",
    "topology_metadata",
    "attach_channel",
    "AnnotateReport",
    "ChannelAnnotation",
    "annotate_recording",
    "read_channels",
]
