"""The accidents of a campaign: recordings, directories, globs and scenario files, each with
the documented answer when one is known.

An input is a recording (``.mcap``, replayed) or a scenario file (``.toml``/``.json``,
simulated as the accident). A directory stands for the recordings and scenario files in it
(not below it); a pattern with ``*``, ``?`` or ``[`` for the files it matches. A scenario file
beside a recording of the same name (``x.mcap`` and ``x.toml``, as ``rocas catalog generate
--family F -o DIR --record`` writes them) is the recording's ground truth, not a second
accident.

The documented answer (the catalog type, e.g. ``A3``) comes from a catalog-format file's
``[ground_truth]`` table: the scenario file itself, or the one beside a recording; a recording
named like a catalog entry (``recordings/a03_...mcap``) has that entry's. Without one the
accident is triaged all the same, and the campaign's completeness and purity leave it out.
"""

from __future__ import annotations

import glob
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path

from rocas._fs import safe_component
from rocas.errors import InputError

RECORDING_SUFFIXES = (".mcap",)
SCENARIO_SUFFIXES = (".toml", ".json")
_GLOB_CHARS = set("*?[")


@dataclass(frozen=True)
class CampaignInput:
    """One accident of a campaign.

    Attributes:
        name: unique within the campaign; its run directory's name.
        path: the recording or scenario file.
        kind: "recording" or "scenario".
        truth_type: the documented type (catalog id, e.g. "A3"), or None when unknown.
        truth_title: that type's title ("" when unknown).
    """

    name: str
    path: Path
    kind: str
    truth_type: str | None = None
    truth_title: str = ""


def collect_inputs(specs: list[str]) -> list[CampaignInput]:
    """The campaign's accidents from the command line's INPUTS, in the order given (a
    directory's and a pattern's files sorted by name); a file named twice counts once.

    Raises:
        InputError: an input that does not exist, a pattern that matches nothing, a file that
            is neither a recording nor a scenario, or no accident at all.
    """
    files: list[Path] = []
    for spec in specs:
        p = Path(spec)
        if p.is_dir():
            found = sorted(f for f in p.iterdir() if f.is_file() and _accepted(f))
            files.extend(_without_truth_sidecars(found))
        elif p.is_file():
            if not _accepted(p):
                raise InputError(f"{p}: not a recording (.mcap) or a scenario file (.toml, .json)",
                                 "name recordings, scenario files or directories holding them")
            files.append(p)
        elif _GLOB_CHARS & set(spec):
            found = sorted(Path(f) for f in glob.glob(spec) if Path(f).is_file() and _accepted(Path(f)))
            if not found:
                raise InputError(f"{spec}: no recording or scenario file matches",
                                 "check the pattern; quote it so the shell leaves it to rocas")
            files.extend(_without_truth_sidecars(found))
        else:
            raise InputError(f"no such file or directory: {spec}", "check the path")
    seen: set[str] = set()
    unique: list[Path] = []
    for f in files:
        key = os.path.realpath(f)
        if key not in seen:
            seen.add(key)
            unique.append(f)
    if not unique:
        raise InputError("no accident to triage: the inputs hold no recording or scenario file",
                         "name .mcap recordings, scenario files or directories holding them")
    names: set[str] = set()
    out = []
    for f in unique:
        stem = safe_component(f.stem)  # the run directory's name: one harmless component
        name, n = stem, 2
        while name in names:  # the same stem from two folders
            name, n = f"{stem}-{n}", n + 1
        names.add(name)
        kind = "recording" if f.suffix in RECORDING_SUFFIXES else "scenario"
        truth_type, title = documented_type(f)
        out.append(CampaignInput(name, f, kind, truth_type, title))
    return out


def _accepted(f: Path) -> bool:
    return f.suffix in RECORDING_SUFFIXES + SCENARIO_SUFFIXES


def _without_truth_sidecars(files: list[Path]) -> list[Path]:
    """Leave out the scenario files that are a recording's ground truth (same stem, same
    folder, recording present)."""
    recordings = {(f.parent, f.stem) for f in files if f.suffix in RECORDING_SUFFIXES}
    return [f for f in files if f.suffix in RECORDING_SUFFIXES or (f.parent, f.stem) not in recordings]


def documented_type(path: Path) -> tuple[str | None, str]:
    """(type id, title) of the documented answer for ``path`` (see the module docstring), or
    (None, "") when none is known."""
    doc = path if path.suffix == ".toml" else path.with_suffix(".toml")
    truth = _ground_truth_table(doc) if doc.is_file() else None
    if truth is not None and isinstance(truth.get("id"), str):
        return truth["id"], str(truth.get("title", ""))
    if path.suffix in RECORDING_SUFFIXES:
        from rocas.catalog import entries

        for e in entries():
            if path.stem == e.key:
                return e.truth.id, e.truth.title
    return None, ""


def _ground_truth_table(path: Path) -> dict[str, object] | None:
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return None  # analysing it says what is wrong with it; here only the answer is looked for
    truth = data.get("ground_truth")
    return truth if isinstance(truth, dict) else None
