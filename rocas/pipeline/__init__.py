"""The analysis pipeline: replay, physical mutation, diff, cyber mutation, validation."""

from rocas.pipeline.analyze import PHASES, VERDICTS, AnalyzeConfig, analyze

__all__ = ["PHASES", "VERDICTS", "AnalyzeConfig", "analyze"]
