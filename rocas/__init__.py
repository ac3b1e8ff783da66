"""rocas: root cause analysis of autonomous-driving accidents from MCAP recordings."""

__version__ = "0.1.0"

from rocas import replay as replay  # noqa: E402  (callable: rocas.replay(path) -> Scenario)
