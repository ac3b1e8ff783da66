"""Differential analysis of two recordings; works on ANY protobuf/JSON MCAP recording.

Never imports the simulator or the built-in ADS: everything is learned from the files.
"""

from rocas.analysis.changepoints import ChangePointConfig, ChangePoints, detect
from rocas.analysis.cmg import (
    ChannelModuleGraph,
    ChannelTopology,
    CmgSpec,
    build_cmg,
    load_cmg,
    parse_cmg,
    resolve_topology,
)
from rocas.analysis.diff import ChannelDiff, DiffResult, diff
from rocas.analysis.mdr import Tolerance, mdr
from rocas.analysis.pinpoint import PinpointResult, find_initial_module
from rocas.analysis.series import ChannelSeries, compute_series

__all__ = [
    "ChangePointConfig",
    "ChangePoints",
    "ChannelDiff",
    "ChannelModuleGraph",
    "ChannelSeries",
    "ChannelTopology",
    "CmgSpec",
    "DiffResult",
    "PinpointResult",
    "Tolerance",
    "build_cmg",
    "compute_series",
    "detect",
    "diff",
    "find_initial_module",
    "load_cmg",
    "mdr",
    "parse_cmg",
    "resolve_topology",
]
