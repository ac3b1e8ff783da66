"""The highway stack's accident catalog (``catalog/h*.toml``, package data).

Each entry is a scene, the ego parameters that make the accident (``[params]``), and its
ground truth: the module and parameter at fault and the value that avoids it (``fix``), or
an empty ``parameter`` when no configuration avoids the accident.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources

from rocas.errors import ScenarioError
from rocas.stacks.highway.scene import Scene, scene_from_dict


@dataclass(frozen=True)
class CatalogEntry:
    """One catalog accident.

    Attributes:
        key: the file's stem (``h01_...``).
        title, description: what happens.
        scene: the scene; params: the ego overrides that make the accident; seed: its seed.
        module, parameter: the ground truth ("" for an accident with no configuration fix).
        fix: the parameter value that avoids the accident (None without a fix).
    """

    key: str
    title: str
    description: str
    scene: Scene
    params: Mapping[str, float]
    seed: int
    module: str
    parameter: str
    fix: float | None


def _entry(key: str, data: Mapping[str, object]) -> CatalogEntry:
    try:
        gt = dict(data["ground_truth"])  # type: ignore[call-overload]
        fix = gt.get("fix")
        return CatalogEntry(key, str(data["title"]), str(data["description"]),
                            scene_from_dict(data["scene"], key),  # type: ignore[arg-type]
                            {str(k): float(v) for k, v in dict(data.get("params", {})).items()},  # type: ignore[call-overload]
                            int(data.get("seed", 0)), str(gt["module"]), str(gt["parameter"]),  # type: ignore[call-overload]
                            None if fix is None else float(fix))
    except KeyError as exc:
        raise ScenarioError(f"highway catalog {key}: missing key {exc}") from None


def entries() -> list[CatalogEntry]:
    """Every entry, in file order."""
    folder = resources.files(__package__).joinpath("catalog")
    out = []
    for f in sorted(folder.iterdir(), key=lambda p: p.name):
        if f.name.endswith(".toml"):
            out.append(_entry(f.name[:-5], tomllib.loads(f.read_text())))
    return out


def entry(key: str) -> CatalogEntry:
    """The entry whose key is or starts with ``key`` (``"h01"``)."""
    found = [e for e in entries() if e.key == key or e.key.startswith(key + "_")]
    if len(found) != 1:
        raise ScenarioError(f"no highway catalog entry {key!r}",
                            "keys: " + ", ".join(e.key for e in entries()))
    return found[0]
