"""The analysis pipeline: replay, physical mutation, diff, cyber mutation, validation."""

from rocas.pipeline.analyze import analyze
from rocas.pipeline.config import PHASES, VERDICTS, AnalyzeConfig
from rocas.pipeline.report import Report

__all__ = ["PHASES", "VERDICTS", "AnalyzeConfig", "Report", "analyze"]
