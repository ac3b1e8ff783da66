"""rocas as a library: the functions ``import rocas`` offers (see docs/api.md).

Each is what a command does, without the terminal: the same settings, the same results, the
same errors (:mod:`rocas.errors`: a :class:`~rocas.errors.RocasError` with ``message`` and
``hint``, the exit code's class). Nothing here prints.

- :func:`diff` (``rocas diff``): two recordings -> :class:`rocas.analysis.diff.DiffResult`;
- :func:`analyze` (``rocas analyze``): an accident recording or scenario -> the frozen
  :class:`rocas.pipeline.report.Report`, its run directory kept;
- :func:`simulate` (``rocas simulate``): a scenario -> :class:`rocas.sim.engine.RunResult`;
- ``rocas.replay(recording)``: the scenario a recording is rebuilt into
  (:mod:`rocas.replay`).
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rocas.scenarios.model import Scenario

if TYPE_CHECKING:
    from rocas.analysis.diff import DiffResult
    from rocas.pipeline.report import Report
    from rocas.sim.engine import RunResult


def diff(accident: str | os.PathLike[str], reference: str | os.PathLike[str],
         **options: Any) -> DiffResult:
    """Diff two recordings of one run and find the initial deviating module.

    ``options`` are :func:`rocas.analysis.diff.diff`'s (``bin_s``, ``delta_s``, ``atol``,
    ``rtol``, ``align``, ``ignore_fields``, ``learn_noise``, ``cmg``, ...). Returns the frozen
    :class:`rocas.analysis.diff.DiffResult` (``.deviating_module``, ``.channels``,
    ``.to_json()``); a pair that cannot be compared raises
    :class:`~rocas.errors.RecordingError` or :class:`~rocas.errors.InputError`.
    """
    from rocas.analysis.diff import diff as run_diff

    return run_diff(accident, reference, **options)


def _scenario(source: str | os.PathLike[str] | Scenario) -> Scenario:
    if isinstance(source, Scenario):
        from rocas.rollout import check_params

        return check_params(source)
    from rocas.rollout import load_scenario

    return load_scenario(os.fspath(source))


def simulate(scenario: str | os.PathLike[str] | Scenario,
             params: Mapping[str, float] | None = None, seed: int | None = None, *,
             output: str | os.PathLike[str] | None = None) -> RunResult:
    """One run of a scenario (a :class:`~rocas.scenarios.Scenario`, a scenario file or an
    example's name) with the stack it names, ``params`` (full names) on top of its own
    overrides; with ``output``, the run recorded to that MCAP file. Returns the frozen
    :class:`rocas.sim.engine.RunResult` (``.outcome``, ``.ego`` (T + 1, 5), ...)."""
    from rocas.rollout import simulate as run

    return run(_scenario(scenario), params, seed, output=output)


def analyze(source: str | os.PathLike[str] | Scenario, out: str | os.PathLike[str] | None = None,
            *, resume: bool = False, progress: Callable[[str, dict[str, Any]], None] | None = None,
            **settings: Any) -> Report:
    """The whole analysis of an accident (``rocas analyze``): replay, physical mutation, diff,
    confidence, cyber mutation, validation.

    Args:
        source: an accident recording (a path), or a scenario simulated as the accident (a
            :class:`~rocas.scenarios.Scenario`, or a path ending in ``.toml``).
        out: the run directory (made); None: a new folder under the system's temporary
            folder.
        resume: continue the analysis already in ``out``.
        progress: called as ``progress(phase, info)`` while the phases advance.
        settings: :class:`rocas.pipeline.config.AnalyzeConfig`'s fields (``seed``,
            ``budget``, ``validation_variants``, ``workers``, ...).

    Returns:
        the frozen :class:`rocas.pipeline.report.Report` (``.verdict``,
        ``.triggering_entity``, ``.deviating_module``, ``.misconfiguration``, ``.confidence``,
        ...; ``.to_json()`` is what ``report.json`` holds, before its floats are rounded to 12
        significant digits).

    Raises:
        UsageError: an unknown setting or a value out of its range.
    """
    import dataclasses

    from rocas.errors import UsageError
    from rocas.pipeline.analyze import analyze as run
    from rocas.pipeline.config import AnalyzeConfig
    from rocas.pipeline.rundir import noop

    known = {f.name for f in dataclasses.fields(AnalyzeConfig)}
    unknown = sorted(set(settings) - known)
    if unknown:
        raise UsageError(f"unknown analysis setting {unknown[0]!r}",
                         f"settings: {', '.join(sorted(known))}")
    if isinstance(source, Scenario) or Path(source).suffix == ".toml":
        source = _scenario(source)
    else:
        source = Path(source)
    if out is None:
        out = Path(tempfile.mkdtemp(prefix="rocas-analysis-")) / "run"
    return run(source, out, AnalyzeConfig(**settings), resume=resume, progress=progress or noop)


__all__ = ["analyze", "diff", "simulate"]
