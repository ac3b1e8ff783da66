"""rocas: root cause analysis of autonomous-driving accidents from MCAP recordings."""

__version__ = "0.1.0"
