from rocas.msgs import header_pb2 as _header_pb2
from google.protobuf.internal import containers as _containers
from google.protobuf.internal import enum_type_wrapper as _enum_type_wrapper
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Iterable as _Iterable, Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class TrajectoryPoint(_message.Message):
    __slots__ = ("x", "y", "theta", "kappa", "s", "v", "a", "relative_time")
    X_FIELD_NUMBER: _ClassVar[int]
    Y_FIELD_NUMBER: _ClassVar[int]
    THETA_FIELD_NUMBER: _ClassVar[int]
    KAPPA_FIELD_NUMBER: _ClassVar[int]
    S_FIELD_NUMBER: _ClassVar[int]
    V_FIELD_NUMBER: _ClassVar[int]
    A_FIELD_NUMBER: _ClassVar[int]
    RELATIVE_TIME_FIELD_NUMBER: _ClassVar[int]
    x: float
    y: float
    theta: float
    kappa: float
    s: float
    v: float
    a: float
    relative_time: float
    def __init__(self, x: _Optional[float] = ..., y: _Optional[float] = ..., theta: _Optional[float] = ..., kappa: _Optional[float] = ..., s: _Optional[float] = ..., v: _Optional[float] = ..., a: _Optional[float] = ..., relative_time: _Optional[float] = ...) -> None: ...

class ObjectDecision(_message.Message):
    __slots__ = ("id", "type", "distance_s", "lateral_offset", "reason")
    class Type(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
        __slots__ = ()
        IGNORE: _ClassVar[ObjectDecision.Type]
        FOLLOW: _ClassVar[ObjectDecision.Type]
        YIELD: _ClassVar[ObjectDecision.Type]
        OVERTAKE: _ClassVar[ObjectDecision.Type]
        STOP: _ClassVar[ObjectDecision.Type]
        NUDGE: _ClassVar[ObjectDecision.Type]
    IGNORE: ObjectDecision.Type
    FOLLOW: ObjectDecision.Type
    YIELD: ObjectDecision.Type
    OVERTAKE: ObjectDecision.Type
    STOP: ObjectDecision.Type
    NUDGE: ObjectDecision.Type
    ID_FIELD_NUMBER: _ClassVar[int]
    TYPE_FIELD_NUMBER: _ClassVar[int]
    DISTANCE_S_FIELD_NUMBER: _ClassVar[int]
    LATERAL_OFFSET_FIELD_NUMBER: _ClassVar[int]
    REASON_FIELD_NUMBER: _ClassVar[int]
    id: str
    type: ObjectDecision.Type
    distance_s: float
    lateral_offset: float
    reason: str
    def __init__(self, id: _Optional[str] = ..., type: _Optional[_Union[ObjectDecision.Type, str]] = ..., distance_s: _Optional[float] = ..., lateral_offset: _Optional[float] = ..., reason: _Optional[str] = ...) -> None: ...

class MainDecision(_message.Message):
    __slots__ = ("type", "stop_distance", "reason")
    class Type(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
        __slots__ = ()
        CRUISE: _ClassVar[MainDecision.Type]
        STOP: _ClassVar[MainDecision.Type]
        ESTOP: _ClassVar[MainDecision.Type]
    CRUISE: MainDecision.Type
    STOP: MainDecision.Type
    ESTOP: MainDecision.Type
    TYPE_FIELD_NUMBER: _ClassVar[int]
    STOP_DISTANCE_FIELD_NUMBER: _ClassVar[int]
    REASON_FIELD_NUMBER: _ClassVar[int]
    type: MainDecision.Type
    stop_distance: float
    reason: str
    def __init__(self, type: _Optional[_Union[MainDecision.Type, str]] = ..., stop_distance: _Optional[float] = ..., reason: _Optional[str] = ...) -> None: ...

class ADCTrajectory(_message.Message):
    __slots__ = ("header", "total_path_length", "total_path_time", "trajectory_point", "main_decision", "object_decision", "estop", "estop_reason", "lane_id", "cruise_speed")
    class EStopReason(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
        __slots__ = ()
        NONE: _ClassVar[ADCTrajectory.EStopReason]
        COLLISION_IMMINENT: _ClassVar[ADCTrajectory.EStopReason]
        PERCEPTION_BRAKE: _ClassVar[ADCTrajectory.EStopReason]
        NO_FEASIBLE_PATH: _ClassVar[ADCTrajectory.EStopReason]
    NONE: ADCTrajectory.EStopReason
    COLLISION_IMMINENT: ADCTrajectory.EStopReason
    PERCEPTION_BRAKE: ADCTrajectory.EStopReason
    NO_FEASIBLE_PATH: ADCTrajectory.EStopReason
    HEADER_FIELD_NUMBER: _ClassVar[int]
    TOTAL_PATH_LENGTH_FIELD_NUMBER: _ClassVar[int]
    TOTAL_PATH_TIME_FIELD_NUMBER: _ClassVar[int]
    TRAJECTORY_POINT_FIELD_NUMBER: _ClassVar[int]
    MAIN_DECISION_FIELD_NUMBER: _ClassVar[int]
    OBJECT_DECISION_FIELD_NUMBER: _ClassVar[int]
    ESTOP_FIELD_NUMBER: _ClassVar[int]
    ESTOP_REASON_FIELD_NUMBER: _ClassVar[int]
    LANE_ID_FIELD_NUMBER: _ClassVar[int]
    CRUISE_SPEED_FIELD_NUMBER: _ClassVar[int]
    header: _header_pb2.Header
    total_path_length: float
    total_path_time: float
    trajectory_point: _containers.RepeatedCompositeFieldContainer[TrajectoryPoint]
    main_decision: MainDecision
    object_decision: _containers.RepeatedCompositeFieldContainer[ObjectDecision]
    estop: bool
    estop_reason: ADCTrajectory.EStopReason
    lane_id: str
    cruise_speed: float
    def __init__(self, header: _Optional[_Union[_header_pb2.Header, _Mapping]] = ..., total_path_length: _Optional[float] = ..., total_path_time: _Optional[float] = ..., trajectory_point: _Optional[_Iterable[_Union[TrajectoryPoint, _Mapping]]] = ..., main_decision: _Optional[_Union[MainDecision, _Mapping]] = ..., object_decision: _Optional[_Iterable[_Union[ObjectDecision, _Mapping]]] = ..., estop: _Optional[bool] = ..., estop_reason: _Optional[_Union[ADCTrajectory.EStopReason, str]] = ..., lane_id: _Optional[str] = ..., cruise_speed: _Optional[float] = ...) -> None: ...
