from rocas.msgs import header_pb2 as _header_pb2
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class ControlCommand(_message.Message):
    __slots__ = ("header", "throttle", "brake", "steering_target", "steering_rate", "acceleration", "estop", "lateral_error", "heading_error", "station_error", "speed_error")
    HEADER_FIELD_NUMBER: _ClassVar[int]
    THROTTLE_FIELD_NUMBER: _ClassVar[int]
    BRAKE_FIELD_NUMBER: _ClassVar[int]
    STEERING_TARGET_FIELD_NUMBER: _ClassVar[int]
    STEERING_RATE_FIELD_NUMBER: _ClassVar[int]
    ACCELERATION_FIELD_NUMBER: _ClassVar[int]
    ESTOP_FIELD_NUMBER: _ClassVar[int]
    LATERAL_ERROR_FIELD_NUMBER: _ClassVar[int]
    HEADING_ERROR_FIELD_NUMBER: _ClassVar[int]
    STATION_ERROR_FIELD_NUMBER: _ClassVar[int]
    SPEED_ERROR_FIELD_NUMBER: _ClassVar[int]
    header: _header_pb2.Header
    throttle: float
    brake: float
    steering_target: float
    steering_rate: float
    acceleration: float
    estop: bool
    lateral_error: float
    heading_error: float
    station_error: float
    speed_error: float
    def __init__(self, header: _Optional[_Union[_header_pb2.Header, _Mapping]] = ..., throttle: _Optional[float] = ..., brake: _Optional[float] = ..., steering_target: _Optional[float] = ..., steering_rate: _Optional[float] = ..., acceleration: _Optional[float] = ..., estop: _Optional[bool] = ..., lateral_error: _Optional[float] = ..., heading_error: _Optional[float] = ..., station_error: _Optional[float] = ..., speed_error: _Optional[float] = ...) -> None: ...
