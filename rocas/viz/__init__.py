"""Rerun output: every phase of an analysis as entities and timelines in a ``.rrd`` file."""

from rocas.viz.diff import log_diff, write_diff_rrd
from rocas.viz.stream import rrd_recording

__all__ = ["log_diff", "rrd_recording", "write_diff_rrd"]
