from rocas.msgs import header_pb2 as _header_pb2
from rocas.msgs import perception_pb2 as _perception_pb2
from google.protobuf.internal import containers as _containers
from google.protobuf.internal import enum_type_wrapper as _enum_type_wrapper
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Iterable as _Iterable, Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class TrajectoryPoint(_message.Message):
    __slots__ = ("position", "theta", "v", "relative_time")
    POSITION_FIELD_NUMBER: _ClassVar[int]
    THETA_FIELD_NUMBER: _ClassVar[int]
    V_FIELD_NUMBER: _ClassVar[int]
    RELATIVE_TIME_FIELD_NUMBER: _ClassVar[int]
    position: _header_pb2.Point2D
    theta: float
    v: float
    relative_time: float
    def __init__(self, position: _Optional[_Union[_header_pb2.Point2D, _Mapping]] = ..., theta: _Optional[float] = ..., v: _Optional[float] = ..., relative_time: _Optional[float] = ...) -> None: ...

class Trajectory(_message.Message):
    __slots__ = ("probability", "trajectory_point")
    PROBABILITY_FIELD_NUMBER: _ClassVar[int]
    TRAJECTORY_POINT_FIELD_NUMBER: _ClassVar[int]
    probability: float
    trajectory_point: _containers.RepeatedCompositeFieldContainer[TrajectoryPoint]
    def __init__(self, probability: _Optional[float] = ..., trajectory_point: _Optional[_Iterable[_Union[TrajectoryPoint, _Mapping]]] = ...) -> None: ...

class PredictionObstacle(_message.Message):
    __slots__ = ("perception_obstacle", "timestamp", "predicted_period", "trajectory", "is_static", "intent")
    class Intent(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
        __slots__ = ()
        UNKNOWN: _ClassVar[PredictionObstacle.Intent]
        LANE_FOLLOW: _ClassVar[PredictionObstacle.Intent]
        CONSTANT_VELOCITY: _ClassVar[PredictionObstacle.Intent]
        CUT_IN: _ClassVar[PredictionObstacle.Intent]
        STATIONARY: _ClassVar[PredictionObstacle.Intent]
    UNKNOWN: PredictionObstacle.Intent
    LANE_FOLLOW: PredictionObstacle.Intent
    CONSTANT_VELOCITY: PredictionObstacle.Intent
    CUT_IN: PredictionObstacle.Intent
    STATIONARY: PredictionObstacle.Intent
    PERCEPTION_OBSTACLE_FIELD_NUMBER: _ClassVar[int]
    TIMESTAMP_FIELD_NUMBER: _ClassVar[int]
    PREDICTED_PERIOD_FIELD_NUMBER: _ClassVar[int]
    TRAJECTORY_FIELD_NUMBER: _ClassVar[int]
    IS_STATIC_FIELD_NUMBER: _ClassVar[int]
    INTENT_FIELD_NUMBER: _ClassVar[int]
    perception_obstacle: _perception_pb2.PerceptionObstacle
    timestamp: float
    predicted_period: float
    trajectory: _containers.RepeatedCompositeFieldContainer[Trajectory]
    is_static: bool
    intent: PredictionObstacle.Intent
    def __init__(self, perception_obstacle: _Optional[_Union[_perception_pb2.PerceptionObstacle, _Mapping]] = ..., timestamp: _Optional[float] = ..., predicted_period: _Optional[float] = ..., trajectory: _Optional[_Iterable[_Union[Trajectory, _Mapping]]] = ..., is_static: _Optional[bool] = ..., intent: _Optional[_Union[PredictionObstacle.Intent, str]] = ...) -> None: ...

class PredictionObstacles(_message.Message):
    __slots__ = ("header", "prediction_obstacle", "start_timestamp", "end_timestamp")
    HEADER_FIELD_NUMBER: _ClassVar[int]
    PREDICTION_OBSTACLE_FIELD_NUMBER: _ClassVar[int]
    START_TIMESTAMP_FIELD_NUMBER: _ClassVar[int]
    END_TIMESTAMP_FIELD_NUMBER: _ClassVar[int]
    header: _header_pb2.Header
    prediction_obstacle: _containers.RepeatedCompositeFieldContainer[PredictionObstacle]
    start_timestamp: float
    end_timestamp: float
    def __init__(self, header: _Optional[_Union[_header_pb2.Header, _Mapping]] = ..., prediction_obstacle: _Optional[_Iterable[_Union[PredictionObstacle, _Mapping]]] = ..., start_timestamp: _Optional[float] = ..., end_timestamp: _Optional[float] = ...) -> None: ...
