"""Channel topics, module names and the wiring of the built-in ADS (the one place to import)."""

from __future__ import annotations

from rocas.msgs import (
    chassis_pb2,
    control_pb2,
    localization_pb2,
    perception_pb2,
    planning_pb2,
    prediction_pb2,
)

# the recording keys of rocas's own recordings, importable from here too
from rocas.recording.topology import EGO_METADATA as EGO_METADATA
from rocas.recording.topology import RUN_METADATA as RUN_METADATA
from rocas.recording.topology import WORLD_ATTACHMENT as WORLD_ATTACHMENT
from rocas.stacks.base import ChannelSpec

LOCALIZATION = "localization"
CANBUS = "canbus"
PERCEPTION = "perception"
PREDICTION = "prediction"
PLANNING = "planning"
CONTROL = "control"

TOPIC_POSE = "/localization/pose"
TOPIC_CHASSIS = "/canbus/chassis"
TOPIC_OBSTACLES = "/perception/obstacles"
TOPIC_TRAFFIC_LIGHT = "/perception/traffic_light"
TOPIC_BRAKE_SIGNAL = "/perception/brake_signal"
TOPIC_PREDICTION = "/prediction"
TOPIC_PLANNING = "/planning"
TOPIC_CONTROL = "/control"


#: a channel of the built-in ADS: the stacks' channel declaration (topic, type, writer,
#: readers, period, role)
Channel = ChannelSpec


CHANNELS: tuple[Channel, ...] = (
    Channel(TOPIC_POSE, localization_pb2.LocalizationEstimate, LOCALIZATION,
            (PERCEPTION, PREDICTION, PLANNING, CONTROL), 0.05),
    Channel(TOPIC_CHASSIS, chassis_pb2.Chassis, CANBUS, (PLANNING, CONTROL), 0.05),
    Channel(TOPIC_OBSTACLES, perception_pb2.PerceptionObstacles, PERCEPTION, (PREDICTION,), 0.1),
    Channel(TOPIC_TRAFFIC_LIGHT, perception_pb2.TrafficLightDetection, PERCEPTION, (PLANNING,),
            0.1),
    Channel(TOPIC_BRAKE_SIGNAL, perception_pb2.BrakeSignal, PERCEPTION, (PLANNING,), 0.1),
    Channel(TOPIC_PREDICTION, prediction_pb2.PredictionObstacles, PREDICTION, (PLANNING,), 0.1),
    Channel(TOPIC_PLANNING, planning_pb2.ADCTrajectory, PLANNING, (CONTROL,), 0.1),
    Channel(TOPIC_CONTROL, control_pb2.ControlCommand, CONTROL, (CANBUS,), 0.05,
            role="control"),
)
