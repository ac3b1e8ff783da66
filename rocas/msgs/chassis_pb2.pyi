from rocas.msgs import header_pb2 as _header_pb2
from google.protobuf.internal import enum_type_wrapper as _enum_type_wrapper
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class Chassis(_message.Message):
    __slots__ = ("header", "engine_started", "speed_mps", "odometer_m", "throttle_percentage", "brake_percentage", "steering_percentage", "gear_location", "driving_mode")
    class GearPosition(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
        __slots__ = ()
        GEAR_NEUTRAL: _ClassVar[Chassis.GearPosition]
        GEAR_DRIVE: _ClassVar[Chassis.GearPosition]
        GEAR_REVERSE: _ClassVar[Chassis.GearPosition]
        GEAR_PARKING: _ClassVar[Chassis.GearPosition]
    GEAR_NEUTRAL: Chassis.GearPosition
    GEAR_DRIVE: Chassis.GearPosition
    GEAR_REVERSE: Chassis.GearPosition
    GEAR_PARKING: Chassis.GearPosition
    class DrivingMode(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
        __slots__ = ()
        COMPLETE_MANUAL: _ClassVar[Chassis.DrivingMode]
        COMPLETE_AUTO_DRIVE: _ClassVar[Chassis.DrivingMode]
        EMERGENCY_MODE: _ClassVar[Chassis.DrivingMode]
    COMPLETE_MANUAL: Chassis.DrivingMode
    COMPLETE_AUTO_DRIVE: Chassis.DrivingMode
    EMERGENCY_MODE: Chassis.DrivingMode
    HEADER_FIELD_NUMBER: _ClassVar[int]
    ENGINE_STARTED_FIELD_NUMBER: _ClassVar[int]
    SPEED_MPS_FIELD_NUMBER: _ClassVar[int]
    ODOMETER_M_FIELD_NUMBER: _ClassVar[int]
    THROTTLE_PERCENTAGE_FIELD_NUMBER: _ClassVar[int]
    BRAKE_PERCENTAGE_FIELD_NUMBER: _ClassVar[int]
    STEERING_PERCENTAGE_FIELD_NUMBER: _ClassVar[int]
    GEAR_LOCATION_FIELD_NUMBER: _ClassVar[int]
    DRIVING_MODE_FIELD_NUMBER: _ClassVar[int]
    header: _header_pb2.Header
    engine_started: bool
    speed_mps: float
    odometer_m: float
    throttle_percentage: float
    brake_percentage: float
    steering_percentage: float
    gear_location: Chassis.GearPosition
    driving_mode: Chassis.DrivingMode
    def __init__(self, header: _Optional[_Union[_header_pb2.Header, _Mapping]] = ..., engine_started: _Optional[bool] = ..., speed_mps: _Optional[float] = ..., odometer_m: _Optional[float] = ..., throttle_percentage: _Optional[float] = ..., brake_percentage: _Optional[float] = ..., steering_percentage: _Optional[float] = ..., gear_location: _Optional[_Union[Chassis.GearPosition, str]] = ..., driving_mode: _Optional[_Union[Chassis.DrivingMode, str]] = ...) -> None: ...
