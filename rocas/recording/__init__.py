"""The recording boundary: readers of MCAP and other formats, a writer, the topology contract.

Reading is layered, each layer importing only those below it: ``model`` (the types every
reader yields) <- ``mcap_records`` (MCAP's bytes) <- ``reader`` (the MCAP reader) and
``foreign`` <- ``rosbag``/``cyber`` (other formats) <- ``formats`` (``open_recording``: which
reader opens a path). The names below are re-exported from those modules for callers that
import them from the package.
"""

from typing import TYPE_CHECKING

from rocas._lazy import lazy_exports

if TYPE_CHECKING:
    from rocas.recording.annotate import annotate_recording, read_channels
    from rocas.recording.annotation import AnnotateReport, ChannelAnnotation
    from rocas.recording.attach import attach_channel
    from rocas.recording.formats import open_recording
    from rocas.recording.model import (
        ChannelInfo,
        ChannelStats,
        DecodedMessage,
        RawMessage,
        ReadReport,
    )
    from rocas.recording.reader import Recording
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
    **dict.fromkeys(("annotate_recording", "read_channels"), "rocas.recording.annotate"),
    **dict.fromkeys(("AnnotateReport", "ChannelAnnotation"), "rocas.recording.annotation"),
    "attach_channel": "rocas.recording.attach",
    "open_recording": "rocas.recording.formats",
    **dict.fromkeys(("ChannelInfo", "ChannelStats", "DecodedMessage", "RawMessage", "ReadReport"),
                    "rocas.recording.model"),
    "Recording": "rocas.recording.reader",
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
