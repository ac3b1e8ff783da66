"""constraints.txt pins the tested set: every dependency, inside pyproject's bounds, installed."""

import re
import tomllib
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[1]


def _canon(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _pins() -> dict[str, str]:
    pins = {}
    for line in (ROOT / "constraints.txt").read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            name, _, ver = line.partition("==")
            assert ver, f"not an exact pin: {line}"
            pins[_canon(name)] = ver
    return pins


def _requirements() -> list[Requirement]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    reqs = project["dependencies"] + [r for rs in project["optional-dependencies"].values() for r in rs]
    return [Requirement(r) for r in reqs]


def test_every_dependency_is_pinned_within_its_bounds():
    pins = _pins()
    for req in _requirements():
        pinned = pins.get(_canon(req.name))
        assert pinned is not None, f"{req.name} is not in constraints.txt"
        assert req.specifier.contains(pinned, prereleases=True), f"{req.name}=={pinned} outside {req}"
        assert not req.specifier.contains("999999"), f"{req} has no upper bound"
    assert "numpy" in pins  # the simulator's digests hold for this numpy only


def test_the_installed_versions_are_the_tested_ones():
    wrong = []
    for name, pinned in _pins().items():
        try:
            installed = version(name)
        except PackageNotFoundError:
            continue  # a platform-specific dependency of another platform
        if installed != pinned:
            wrong.append(f"{name} {installed} (tested: {pinned})")
    assert not wrong, 'reinstall with pip install -e ".[dev]" -c constraints.txt: ' + ", ".join(wrong)
