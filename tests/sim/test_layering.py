"""The simulator knows worlds, not stacks: no module under rocas/sim imports rocas.stacks.ads."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import rocas.sim

SIM_DIR = Path(rocas.sim.__file__).parent
FORBIDDEN = "rocas.stacks.ads"


def _imported_modules(tree: ast.AST) -> list[tuple[int, str]]:
    """(line, module) of every import in ``tree``, also those inside functions; ``from rocas
    import ads`` counts as ``rocas.stacks.ads``."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.append((node.lineno, node.module))
            found += [(node.lineno, f"{node.module}.{alias.name}") for alias in node.names]
    return found


def _stack_imports(source: str) -> list[tuple[int, str]]:
    return [(line, m) for line, m in _imported_modules(ast.parse(source))
            if m == FORBIDDEN or m.startswith(FORBIDDEN + ".")]


def test_no_module_of_the_simulator_imports_the_ads():
    files = sorted(SIM_DIR.rglob("*.py"))
    assert len(files) >= 8  # the walk sees the package (engine, oracles, recorder, world, ...)
    offending = [f"{path.relative_to(SIM_DIR.parent.parent)}:{line}: {module}"
                 for path in files for line, module in _stack_imports(path.read_text())]
    assert offending == []


def test_importing_the_simulator_loads_no_stack():
    # also through what it imports (scenarios, recording): a fresh interpreter imports every
    # module of rocas.sim and lists the rocas.stacks.ads modules that came with them
    child = (
        "import importlib, pkgutil, sys, rocas.sim\n"
        "names = [m.name for m in pkgutil.iter_modules(rocas.sim.__path__)]\n"
        "for n in names: importlib.import_module('rocas.sim.' + n)\n"
        "print(len(names), sorted(m for m in sys.modules if m.split('.')[:3] == ['rocas', 'stacks', 'ads']))"
    )
    out = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True,
                         check=True).stdout.split(maxsplit=1)
    assert int(out[0]) >= 8
    assert out[1].strip() == "[]"


def test_the_check_sees_every_form_of_import():
    source = """
import rocas.stacks.ads.params
from rocas.stacks.ads.stack import AdsStack
from rocas.stacks import ads
def lazy():
    from rocas.stacks.ads import planning
import rocas.adsx, rocas.sim.world
from rocas.sim import world
"""
    assert sorted({line for line, _ in _stack_imports(source)}) == [2, 3, 4, 6]
