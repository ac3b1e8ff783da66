from google.protobuf.internal import containers as _containers
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Iterable as _Iterable, Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class Stamp(_message.Message):
    __slots__ = ("time_s", "seq", "module")
    TIME_S_FIELD_NUMBER: _ClassVar[int]
    SEQ_FIELD_NUMBER: _ClassVar[int]
    MODULE_FIELD_NUMBER: _ClassVar[int]
    time_s: float
    seq: int
    module: str
    def __init__(self, time_s: _Optional[float] = ..., seq: _Optional[int] = ..., module: _Optional[str] = ...) -> None: ...

class Point2(_message.Message):
    __slots__ = ("x", "y")
    X_FIELD_NUMBER: _ClassVar[int]
    Y_FIELD_NUMBER: _ClassVar[int]
    x: float
    y: float
    def __init__(self, x: _Optional[float] = ..., y: _Optional[float] = ...) -> None: ...

class EgoState(_message.Message):
    __slots__ = ("stamp", "position", "heading_rad", "speed_mps", "accel_mps2", "route_s_m")
    STAMP_FIELD_NUMBER: _ClassVar[int]
    POSITION_FIELD_NUMBER: _ClassVar[int]
    HEADING_RAD_FIELD_NUMBER: _ClassVar[int]
    SPEED_MPS_FIELD_NUMBER: _ClassVar[int]
    ACCEL_MPS2_FIELD_NUMBER: _ClassVar[int]
    ROUTE_S_M_FIELD_NUMBER: _ClassVar[int]
    stamp: Stamp
    position: Point2
    heading_rad: float
    speed_mps: float
    accel_mps2: float
    route_s_m: float
    def __init__(self, stamp: _Optional[_Union[Stamp, _Mapping]] = ..., position: _Optional[_Union[Point2, _Mapping]] = ..., heading_rad: _Optional[float] = ..., speed_mps: _Optional[float] = ..., accel_mps2: _Optional[float] = ..., route_s_m: _Optional[float] = ...) -> None: ...

class Waypoint(_message.Message):
    __slots__ = ("t_s", "position")
    T_S_FIELD_NUMBER: _ClassVar[int]
    POSITION_FIELD_NUMBER: _ClassVar[int]
    t_s: float
    position: Point2
    def __init__(self, t_s: _Optional[float] = ..., position: _Optional[_Union[Point2, _Mapping]] = ...) -> None: ...

class Agent(_message.Message):
    __slots__ = ("id", "kind", "position", "heading_rad", "speed_mps", "length_m", "width_m", "height_m", "is_static", "forecast", "color")
    ID_FIELD_NUMBER: _ClassVar[int]
    KIND_FIELD_NUMBER: _ClassVar[int]
    POSITION_FIELD_NUMBER: _ClassVar[int]
    HEADING_RAD_FIELD_NUMBER: _ClassVar[int]
    SPEED_MPS_FIELD_NUMBER: _ClassVar[int]
    LENGTH_M_FIELD_NUMBER: _ClassVar[int]
    WIDTH_M_FIELD_NUMBER: _ClassVar[int]
    HEIGHT_M_FIELD_NUMBER: _ClassVar[int]
    IS_STATIC_FIELD_NUMBER: _ClassVar[int]
    FORECAST_FIELD_NUMBER: _ClassVar[int]
    COLOR_FIELD_NUMBER: _ClassVar[int]
    id: int
    kind: str
    position: Point2
    heading_rad: float
    speed_mps: float
    length_m: float
    width_m: float
    height_m: float
    is_static: bool
    forecast: _containers.RepeatedCompositeFieldContainer[Waypoint]
    color: str
    def __init__(self, id: _Optional[int] = ..., kind: _Optional[str] = ..., position: _Optional[_Union[Point2, _Mapping]] = ..., heading_rad: _Optional[float] = ..., speed_mps: _Optional[float] = ..., length_m: _Optional[float] = ..., width_m: _Optional[float] = ..., height_m: _Optional[float] = ..., is_static: _Optional[bool] = ..., forecast: _Optional[_Iterable[_Union[Waypoint, _Mapping]]] = ..., color: _Optional[str] = ...) -> None: ...

class AgentForecasts(_message.Message):
    __slots__ = ("stamp", "agents")
    STAMP_FIELD_NUMBER: _ClassVar[int]
    AGENTS_FIELD_NUMBER: _ClassVar[int]
    stamp: Stamp
    agents: _containers.RepeatedCompositeFieldContainer[Agent]
    def __init__(self, stamp: _Optional[_Union[Stamp, _Mapping]] = ..., agents: _Optional[_Iterable[_Union[Agent, _Mapping]]] = ...) -> None: ...

class EgoPlan(_message.Message):
    __slots__ = ("stamp", "waypoints", "target_speed_mps", "collide", "collide_in_s", "collide_agent")
    STAMP_FIELD_NUMBER: _ClassVar[int]
    WAYPOINTS_FIELD_NUMBER: _ClassVar[int]
    TARGET_SPEED_MPS_FIELD_NUMBER: _ClassVar[int]
    COLLIDE_FIELD_NUMBER: _ClassVar[int]
    COLLIDE_IN_S_FIELD_NUMBER: _ClassVar[int]
    COLLIDE_AGENT_FIELD_NUMBER: _ClassVar[int]
    stamp: Stamp
    waypoints: _containers.RepeatedCompositeFieldContainer[Waypoint]
    target_speed_mps: float
    collide: bool
    collide_in_s: float
    collide_agent: int
    def __init__(self, stamp: _Optional[_Union[Stamp, _Mapping]] = ..., waypoints: _Optional[_Iterable[_Union[Waypoint, _Mapping]]] = ..., target_speed_mps: _Optional[float] = ..., collide: _Optional[bool] = ..., collide_in_s: _Optional[float] = ..., collide_agent: _Optional[int] = ...) -> None: ...

class BrakePrediction(_message.Message):
    __slots__ = ("stamp", "probability", "brake", "features")
    STAMP_FIELD_NUMBER: _ClassVar[int]
    PROBABILITY_FIELD_NUMBER: _ClassVar[int]
    BRAKE_FIELD_NUMBER: _ClassVar[int]
    FEATURES_FIELD_NUMBER: _ClassVar[int]
    stamp: Stamp
    probability: float
    brake: bool
    features: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, stamp: _Optional[_Union[Stamp, _Mapping]] = ..., probability: _Optional[float] = ..., brake: _Optional[bool] = ..., features: _Optional[_Iterable[float]] = ...) -> None: ...

class VehicleCommand(_message.Message):
    __slots__ = ("stamp", "steer", "throttle", "brake", "override")
    STAMP_FIELD_NUMBER: _ClassVar[int]
    STEER_FIELD_NUMBER: _ClassVar[int]
    THROTTLE_FIELD_NUMBER: _ClassVar[int]
    BRAKE_FIELD_NUMBER: _ClassVar[int]
    OVERRIDE_FIELD_NUMBER: _ClassVar[int]
    stamp: Stamp
    steer: float
    throttle: float
    brake: float
    override: str
    def __init__(self, stamp: _Optional[_Union[Stamp, _Mapping]] = ..., steer: _Optional[float] = ..., throttle: _Optional[float] = ..., brake: _Optional[float] = ..., override: _Optional[str] = ...) -> None: ...
