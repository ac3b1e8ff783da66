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

class VehicleState(_message.Message):
    __slots__ = ("id", "x_m", "y_m", "heading_rad", "speed_mps", "lane", "lane_s_m", "lane_lateral_m", "length_m", "width_m", "crashed", "kind")
    ID_FIELD_NUMBER: _ClassVar[int]
    X_M_FIELD_NUMBER: _ClassVar[int]
    Y_M_FIELD_NUMBER: _ClassVar[int]
    HEADING_RAD_FIELD_NUMBER: _ClassVar[int]
    SPEED_MPS_FIELD_NUMBER: _ClassVar[int]
    LANE_FIELD_NUMBER: _ClassVar[int]
    LANE_S_M_FIELD_NUMBER: _ClassVar[int]
    LANE_LATERAL_M_FIELD_NUMBER: _ClassVar[int]
    LENGTH_M_FIELD_NUMBER: _ClassVar[int]
    WIDTH_M_FIELD_NUMBER: _ClassVar[int]
    CRASHED_FIELD_NUMBER: _ClassVar[int]
    KIND_FIELD_NUMBER: _ClassVar[int]
    id: int
    x_m: float
    y_m: float
    heading_rad: float
    speed_mps: float
    lane: str
    lane_s_m: float
    lane_lateral_m: float
    length_m: float
    width_m: float
    crashed: bool
    kind: str
    def __init__(self, id: _Optional[int] = ..., x_m: _Optional[float] = ..., y_m: _Optional[float] = ..., heading_rad: _Optional[float] = ..., speed_mps: _Optional[float] = ..., lane: _Optional[str] = ..., lane_s_m: _Optional[float] = ..., lane_lateral_m: _Optional[float] = ..., length_m: _Optional[float] = ..., width_m: _Optional[float] = ..., crashed: _Optional[bool] = ..., kind: _Optional[str] = ...) -> None: ...

class Traffic(_message.Message):
    __slots__ = ("stamp", "vehicles")
    STAMP_FIELD_NUMBER: _ClassVar[int]
    VEHICLES_FIELD_NUMBER: _ClassVar[int]
    stamp: Stamp
    vehicles: _containers.RepeatedCompositeFieldContainer[VehicleState]
    def __init__(self, stamp: _Optional[_Union[Stamp, _Mapping]] = ..., vehicles: _Optional[_Iterable[_Union[VehicleState, _Mapping]]] = ...) -> None: ...

class EgoState(_message.Message):
    __slots__ = ("stamp", "state", "on_road")
    STAMP_FIELD_NUMBER: _ClassVar[int]
    STATE_FIELD_NUMBER: _ClassVar[int]
    ON_ROAD_FIELD_NUMBER: _ClassVar[int]
    stamp: Stamp
    state: VehicleState
    on_road: bool
    def __init__(self, stamp: _Optional[_Union[Stamp, _Mapping]] = ..., state: _Optional[_Union[VehicleState, _Mapping]] = ..., on_road: _Optional[bool] = ...) -> None: ...

class Neighbour(_message.Message):
    __slots__ = ("present", "id", "gap_m", "speed_mps")
    PRESENT_FIELD_NUMBER: _ClassVar[int]
    ID_FIELD_NUMBER: _ClassVar[int]
    GAP_M_FIELD_NUMBER: _ClassVar[int]
    SPEED_MPS_FIELD_NUMBER: _ClassVar[int]
    present: bool
    id: int
    gap_m: float
    speed_mps: float
    def __init__(self, present: _Optional[bool] = ..., id: _Optional[int] = ..., gap_m: _Optional[float] = ..., speed_mps: _Optional[float] = ...) -> None: ...

class Neighbours(_message.Message):
    __slots__ = ("stamp", "lane", "front", "rear", "left_front", "left_rear", "right_front", "right_rear")
    STAMP_FIELD_NUMBER: _ClassVar[int]
    LANE_FIELD_NUMBER: _ClassVar[int]
    FRONT_FIELD_NUMBER: _ClassVar[int]
    REAR_FIELD_NUMBER: _ClassVar[int]
    LEFT_FRONT_FIELD_NUMBER: _ClassVar[int]
    LEFT_REAR_FIELD_NUMBER: _ClassVar[int]
    RIGHT_FRONT_FIELD_NUMBER: _ClassVar[int]
    RIGHT_REAR_FIELD_NUMBER: _ClassVar[int]
    stamp: Stamp
    lane: str
    front: Neighbour
    rear: Neighbour
    left_front: Neighbour
    left_rear: Neighbour
    right_front: Neighbour
    right_rear: Neighbour
    def __init__(self, stamp: _Optional[_Union[Stamp, _Mapping]] = ..., lane: _Optional[str] = ..., front: _Optional[_Union[Neighbour, _Mapping]] = ..., rear: _Optional[_Union[Neighbour, _Mapping]] = ..., left_front: _Optional[_Union[Neighbour, _Mapping]] = ..., left_rear: _Optional[_Union[Neighbour, _Mapping]] = ..., right_front: _Optional[_Union[Neighbour, _Mapping]] = ..., right_rear: _Optional[_Union[Neighbour, _Mapping]] = ...) -> None: ...

class Decision(_message.Message):
    __slots__ = ("stamp", "target_lane", "lane_change", "idm_accel_mps2", "idm_accel_target_mps2", "desired_gap_m", "target_speed_mps")
    STAMP_FIELD_NUMBER: _ClassVar[int]
    TARGET_LANE_FIELD_NUMBER: _ClassVar[int]
    LANE_CHANGE_FIELD_NUMBER: _ClassVar[int]
    IDM_ACCEL_MPS2_FIELD_NUMBER: _ClassVar[int]
    IDM_ACCEL_TARGET_MPS2_FIELD_NUMBER: _ClassVar[int]
    DESIRED_GAP_M_FIELD_NUMBER: _ClassVar[int]
    TARGET_SPEED_MPS_FIELD_NUMBER: _ClassVar[int]
    stamp: Stamp
    target_lane: str
    lane_change: int
    idm_accel_mps2: float
    idm_accel_target_mps2: float
    desired_gap_m: float
    target_speed_mps: float
    def __init__(self, stamp: _Optional[_Union[Stamp, _Mapping]] = ..., target_lane: _Optional[str] = ..., lane_change: _Optional[int] = ..., idm_accel_mps2: _Optional[float] = ..., idm_accel_target_mps2: _Optional[float] = ..., desired_gap_m: _Optional[float] = ..., target_speed_mps: _Optional[float] = ...) -> None: ...

class Command(_message.Message):
    __slots__ = ("stamp", "steering_rad", "acceleration_mps2")
    STAMP_FIELD_NUMBER: _ClassVar[int]
    STEERING_RAD_FIELD_NUMBER: _ClassVar[int]
    ACCELERATION_MPS2_FIELD_NUMBER: _ClassVar[int]
    stamp: Stamp
    steering_rad: float
    acceleration_mps2: float
    def __init__(self, stamp: _Optional[_Union[Stamp, _Mapping]] = ..., steering_rad: _Optional[float] = ..., acceleration_mps2: _Optional[float] = ...) -> None: ...
