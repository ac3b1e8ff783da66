"""The MCAP boundary: a streaming reader, a writer and the topology contract."""

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
from rocas.recording.topology import (
    CONTROL_ROLE,
    READERS_KEY,
    ROLE_KEY,
    ROS1_CALLERID_KEY,
    WRITERS_KEY,
    split_modules,
    topology_metadata,
)
from rocas.recording.writer import RecordingWriter, register_protobuf_channel

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
