from rocas.msgs import header_pb2 as _header_pb2
from google.protobuf.internal import containers as _containers
from google.protobuf.internal import enum_type_wrapper as _enum_type_wrapper
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Iterable as _Iterable, Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class PerceptionObstacle(_message.Message):
    __slots__ = ("id", "type", "sub_type", "color", "position", "theta", "velocity", "acceleration", "length", "width", "height", "polygon_point", "confidence", "tracking_time")
    class Type(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
        __slots__ = ()
        UNKNOWN: _ClassVar[PerceptionObstacle.Type]
        UNKNOWN_MOVABLE: _ClassVar[PerceptionObstacle.Type]
        UNKNOWN_UNMOVABLE: _ClassVar[PerceptionObstacle.Type]
        PEDESTRIAN: _ClassVar[PerceptionObstacle.Type]
        BICYCLE: _ClassVar[PerceptionObstacle.Type]
        VEHICLE: _ClassVar[PerceptionObstacle.Type]
    UNKNOWN: PerceptionObstacle.Type
    UNKNOWN_MOVABLE: PerceptionObstacle.Type
    UNKNOWN_UNMOVABLE: PerceptionObstacle.Type
    PEDESTRIAN: PerceptionObstacle.Type
    BICYCLE: PerceptionObstacle.Type
    VEHICLE: PerceptionObstacle.Type
    class SubType(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
        __slots__ = ()
        ST_UNKNOWN: _ClassVar[PerceptionObstacle.SubType]
        ST_CAR: _ClassVar[PerceptionObstacle.SubType]
        ST_SUV: _ClassVar[PerceptionObstacle.SubType]
        ST_TRUCK: _ClassVar[PerceptionObstacle.SubType]
        ST_BUS: _ClassVar[PerceptionObstacle.SubType]
        ST_CYCLIST: _ClassVar[PerceptionObstacle.SubType]
        ST_PEDESTRIAN: _ClassVar[PerceptionObstacle.SubType]
        ST_TRAFFICCONE: _ClassVar[PerceptionObstacle.SubType]
        ST_BOX: _ClassVar[PerceptionObstacle.SubType]
    ST_UNKNOWN: PerceptionObstacle.SubType
    ST_CAR: PerceptionObstacle.SubType
    ST_SUV: PerceptionObstacle.SubType
    ST_TRUCK: PerceptionObstacle.SubType
    ST_BUS: PerceptionObstacle.SubType
    ST_CYCLIST: PerceptionObstacle.SubType
    ST_PEDESTRIAN: PerceptionObstacle.SubType
    ST_TRAFFICCONE: PerceptionObstacle.SubType
    ST_BOX: PerceptionObstacle.SubType
    ID_FIELD_NUMBER: _ClassVar[int]
    TYPE_FIELD_NUMBER: _ClassVar[int]
    SUB_TYPE_FIELD_NUMBER: _ClassVar[int]
    COLOR_FIELD_NUMBER: _ClassVar[int]
    POSITION_FIELD_NUMBER: _ClassVar[int]
    THETA_FIELD_NUMBER: _ClassVar[int]
    VELOCITY_FIELD_NUMBER: _ClassVar[int]
    ACCELERATION_FIELD_NUMBER: _ClassVar[int]
    LENGTH_FIELD_NUMBER: _ClassVar[int]
    WIDTH_FIELD_NUMBER: _ClassVar[int]
    HEIGHT_FIELD_NUMBER: _ClassVar[int]
    POLYGON_POINT_FIELD_NUMBER: _ClassVar[int]
    CONFIDENCE_FIELD_NUMBER: _ClassVar[int]
    TRACKING_TIME_FIELD_NUMBER: _ClassVar[int]
    id: int
    type: PerceptionObstacle.Type
    sub_type: PerceptionObstacle.SubType
    color: str
    position: _header_pb2.Point3D
    theta: float
    velocity: _header_pb2.Point3D
    acceleration: _header_pb2.Point3D
    length: float
    width: float
    height: float
    polygon_point: _containers.RepeatedCompositeFieldContainer[_header_pb2.Point3D]
    confidence: float
    tracking_time: float
    def __init__(self, id: _Optional[int] = ..., type: _Optional[_Union[PerceptionObstacle.Type, str]] = ..., sub_type: _Optional[_Union[PerceptionObstacle.SubType, str]] = ..., color: _Optional[str] = ..., position: _Optional[_Union[_header_pb2.Point3D, _Mapping]] = ..., theta: _Optional[float] = ..., velocity: _Optional[_Union[_header_pb2.Point3D, _Mapping]] = ..., acceleration: _Optional[_Union[_header_pb2.Point3D, _Mapping]] = ..., length: _Optional[float] = ..., width: _Optional[float] = ..., height: _Optional[float] = ..., polygon_point: _Optional[_Iterable[_Union[_header_pb2.Point3D, _Mapping]]] = ..., confidence: _Optional[float] = ..., tracking_time: _Optional[float] = ...) -> None: ...

class PerceptionObstacles(_message.Message):
    __slots__ = ("header", "perception_obstacle", "ego_position", "ego_heading")
    HEADER_FIELD_NUMBER: _ClassVar[int]
    PERCEPTION_OBSTACLE_FIELD_NUMBER: _ClassVar[int]
    EGO_POSITION_FIELD_NUMBER: _ClassVar[int]
    EGO_HEADING_FIELD_NUMBER: _ClassVar[int]
    header: _header_pb2.Header
    perception_obstacle: _containers.RepeatedCompositeFieldContainer[PerceptionObstacle]
    ego_position: _header_pb2.Point3D
    ego_heading: float
    def __init__(self, header: _Optional[_Union[_header_pb2.Header, _Mapping]] = ..., perception_obstacle: _Optional[_Iterable[_Union[PerceptionObstacle, _Mapping]]] = ..., ego_position: _Optional[_Union[_header_pb2.Point3D, _Mapping]] = ..., ego_heading: _Optional[float] = ...) -> None: ...

class TrafficLight(_message.Message):
    __slots__ = ("id", "color", "confidence", "tracking_time", "distance_m")
    class Color(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
        __slots__ = ()
        UNKNOWN: _ClassVar[TrafficLight.Color]
        RED: _ClassVar[TrafficLight.Color]
        YELLOW: _ClassVar[TrafficLight.Color]
        GREEN: _ClassVar[TrafficLight.Color]
        BLACK: _ClassVar[TrafficLight.Color]
    UNKNOWN: TrafficLight.Color
    RED: TrafficLight.Color
    YELLOW: TrafficLight.Color
    GREEN: TrafficLight.Color
    BLACK: TrafficLight.Color
    ID_FIELD_NUMBER: _ClassVar[int]
    COLOR_FIELD_NUMBER: _ClassVar[int]
    CONFIDENCE_FIELD_NUMBER: _ClassVar[int]
    TRACKING_TIME_FIELD_NUMBER: _ClassVar[int]
    DISTANCE_M_FIELD_NUMBER: _ClassVar[int]
    id: str
    color: TrafficLight.Color
    confidence: float
    tracking_time: float
    distance_m: float
    def __init__(self, id: _Optional[str] = ..., color: _Optional[_Union[TrafficLight.Color, str]] = ..., confidence: _Optional[float] = ..., tracking_time: _Optional[float] = ..., distance_m: _Optional[float] = ...) -> None: ...

class TrafficLightDetection(_message.Message):
    __slots__ = ("header", "traffic_light", "selected_light_id", "contain_lights")
    HEADER_FIELD_NUMBER: _ClassVar[int]
    TRAFFIC_LIGHT_FIELD_NUMBER: _ClassVar[int]
    SELECTED_LIGHT_ID_FIELD_NUMBER: _ClassVar[int]
    CONTAIN_LIGHTS_FIELD_NUMBER: _ClassVar[int]
    header: _header_pb2.Header
    traffic_light: _containers.RepeatedCompositeFieldContainer[TrafficLight]
    selected_light_id: str
    contain_lights: bool
    def __init__(self, header: _Optional[_Union[_header_pb2.Header, _Mapping]] = ..., traffic_light: _Optional[_Iterable[_Union[TrafficLight, _Mapping]]] = ..., selected_light_id: _Optional[str] = ..., contain_lights: _Optional[bool] = ...) -> None: ...

class BrakeSignal(_message.Message):
    __slots__ = ("header", "brake_probability", "brake_threshold", "brake")
    HEADER_FIELD_NUMBER: _ClassVar[int]
    BRAKE_PROBABILITY_FIELD_NUMBER: _ClassVar[int]
    BRAKE_THRESHOLD_FIELD_NUMBER: _ClassVar[int]
    BRAKE_FIELD_NUMBER: _ClassVar[int]
    header: _header_pb2.Header
    brake_probability: float
    brake_threshold: float
    brake: bool
    def __init__(self, header: _Optional[_Union[_header_pb2.Header, _Mapping]] = ..., brake_probability: _Optional[float] = ..., brake_threshold: _Optional[float] = ..., brake: _Optional[bool] = ...) -> None: ...
