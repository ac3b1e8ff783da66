from rocas.msgs import header_pb2 as _header_pb2
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class Pose(_message.Message):
    __slots__ = ("position", "heading", "linear_velocity", "linear_acceleration", "angular_velocity")
    POSITION_FIELD_NUMBER: _ClassVar[int]
    HEADING_FIELD_NUMBER: _ClassVar[int]
    LINEAR_VELOCITY_FIELD_NUMBER: _ClassVar[int]
    LINEAR_ACCELERATION_FIELD_NUMBER: _ClassVar[int]
    ANGULAR_VELOCITY_FIELD_NUMBER: _ClassVar[int]
    position: _header_pb2.Point3D
    heading: float
    linear_velocity: _header_pb2.Point3D
    linear_acceleration: _header_pb2.Point3D
    angular_velocity: float
    def __init__(self, position: _Optional[_Union[_header_pb2.Point3D, _Mapping]] = ..., heading: _Optional[float] = ..., linear_velocity: _Optional[_Union[_header_pb2.Point3D, _Mapping]] = ..., linear_acceleration: _Optional[_Union[_header_pb2.Point3D, _Mapping]] = ..., angular_velocity: _Optional[float] = ...) -> None: ...

class LocalizationEstimate(_message.Message):
    __slots__ = ("header", "pose", "lane_id", "lane_s")
    HEADER_FIELD_NUMBER: _ClassVar[int]
    POSE_FIELD_NUMBER: _ClassVar[int]
    LANE_ID_FIELD_NUMBER: _ClassVar[int]
    LANE_S_FIELD_NUMBER: _ClassVar[int]
    header: _header_pb2.Header
    pose: Pose
    lane_id: str
    lane_s: float
    def __init__(self, header: _Optional[_Union[_header_pb2.Header, _Mapping]] = ..., pose: _Optional[_Union[Pose, _Mapping]] = ..., lane_id: _Optional[str] = ..., lane_s: _Optional[float] = ...) -> None: ...
