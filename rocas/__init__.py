"""rocas: root cause analysis of autonomous-driving accidents from MCAP recordings.

As a library (docs/api.md)::

    import rocas
    result = rocas.diff("accident.mcap", "reference.mcap")   # -> DiffResult
    report = rocas.analyze("accident.mcap", "runs/a09")        # -> Report
    run = rocas.simulate("roundabout_red_truck")               # -> RunResult
    scenario = rocas.replay("accident.mcap")                   # -> the rebuilt Scenario

Everything loads on first use, so ``import rocas`` stays cheap.
"""

from typing import TYPE_CHECKING

from rocas._lazy import lazy_exports

__version__ = "0.1.0"

from rocas import replay as replay  # noqa: E402  (callable: rocas.replay(path) -> Scenario)

if TYPE_CHECKING:
    from rocas.analysis.diff import DiffResult
    from rocas.api import analyze, diff, simulate
    from rocas.errors import (
        InputError,
        RecordingError,
        RocasError,
        ScenarioError,
        TopologyError,
        UsageError,
    )
    from rocas.pipeline.config import AnalyzeConfig
    from rocas.pipeline.report import Report
    from rocas.scenarios.model import Scenario
    from rocas.sim.engine import BatchResult, RunResult

_LAZY = {
    "analyze": "rocas.api",
    "diff": "rocas.api",
    "simulate": "rocas.api",
    "DiffResult": "rocas.analysis.diff",
    "AnalyzeConfig": "rocas.pipeline.config",
    "Report": "rocas.pipeline.report",
    "Scenario": "rocas.scenarios.model",
    "RunResult": "rocas.sim.engine",
    "BatchResult": "rocas.sim.engine",
    "RocasError": "rocas.errors",
    "UsageError": "rocas.errors",
    "InputError": "rocas.errors",
    "RecordingError": "rocas.errors",
    "TopologyError": "rocas.errors",
    "ScenarioError": "rocas.errors",
}
__getattr__, __dir__ = lazy_exports(__name__, globals(), _LAZY)

__all__ = ["AnalyzeConfig", "BatchResult", "DiffResult", "InputError", "RecordingError",
           "Report", "RocasError", "RunResult", "Scenario", "ScenarioError", "TopologyError",
           "UsageError", "__version__", "analyze", "diff", "replay", "simulate"]
