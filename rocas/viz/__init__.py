"""Rerun output: every phase of an analysis as entities and timelines in a ``.rrd`` file.

Importing this package imports the Rerun SDK with its Rust log output off (``RUST_LOG=off``,
unless the user set ``RUST_LOG``), for rocas's own process only: the variable is removed again
once the SDK has read it, so a viewer rocas starts logs as usual. rocas reports Rerun's
failures itself, in one line (:mod:`rocas.viz.stream`).
"""

import os


def _import_rerun_quietly() -> None:
    if "RUST_LOG" in os.environ:
        import rerun  # noqa: F401 - the user chose the level
        return
    os.environ["RUST_LOG"] = "off"  # read once, when the Rust bindings load
    try:
        import rerun  # noqa: F401
    finally:
        del os.environ["RUST_LOG"]


_import_rerun_quietly()

from rocas.viz.diff import log_diff, write_diff_rrd  # noqa: E402
from rocas.viz.stream import rrd_recording  # noqa: E402

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
from rocas.viz.execution import load_execution  # noqa: E402
from rocas.viz.scene import log_scene  # noqa: E402
from rocas.viz.search import log_search  # noqa: E402
from rocas.viz.signals import log_signals  # noqa: E402

__all__ += [
    "analysis_blueprint", "load_execution", "log_execution", "log_run_dir", "log_scene", "log_search",
    "log_signals", "log_verdict", "write_analysis_rrd", "write_recording_rrd", "write_run_dir_rrd",
]
