"""Generated protobuf classes for the built-in ADS channels (source: proto/rocas/msgs/).

Do not edit the ``*_pb2`` modules by hand: run ``python proto/generate.py``.
rocas never needs these classes to *read* a recording; they are for writing one.
"""

from rocas.msgs import (
    chassis_pb2,
    control_pb2,
    header_pb2,
    localization_pb2,
    perception_pb2,
    planning_pb2,
    prediction_pb2,
)

__all__ = [
    "chassis_pb2",
    "control_pb2",
    "header_pb2",
    "localization_pb2",
    "perception_pb2",
    "planning_pb2",
    "prediction_pb2",
]
