"""Rerun output: every phase of an analysis as entities and timelines in a ``.rrd`` file."""

from rocas.viz.diff import log_diff, write_diff_rrd
from rocas.viz.stream import rrd_recording

__all__ = ["log_diff", "rrd_recording", "write_diff_rrd"]

from rocas.viz.analysis import (  # noqa: E402
    analysis_blueprint,
    log_execution,
    log_run_dir,
    log_verdict,
    write_analysis_rrd,
    write_recording_rrd,
    write_run_dir_rrd,
)
from rocas.viz.scene import load_execution, log_scene  # noqa: E402
from rocas.viz.search import log_search  # noqa: E402
from rocas.viz.signals import log_signals  # noqa: E402

__all__ += [
    "analysis_blueprint", "load_execution", "log_execution", "log_run_dir", "log_scene", "log_search",
    "log_signals", "log_verdict", "write_analysis_rrd", "write_recording_rrd", "write_run_dir_rrd",
]
