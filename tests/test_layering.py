"""The package's shape, measured from its source (issue 38): subpackages import one another
one way only (imports inside functions count), no code compares a stack's name outside the
registry, and every file and function stays within what one reader holds in mind."""

from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx

import rocas
from rocas.stacks import registry

ROOT = Path(rocas.__file__).parent
SOURCES = sorted(p for p in ROOT.rglob("*.py") if not p.name.endswith("_pb2.py"))
#: the stack packages count as subpackages of their own (the registry loads them by name)
STACK_PACKAGES = ("ads", "lav", "highway")
MAX_FILE_LINES = 800
MAX_FUNCTION_LINES = 80
MAX_LONG_FUNCTIONS = 5


def _unit(module: str) -> str | None:
    """The subpackage (or top-level module) a dotted rocas module belongs to."""
    parts = module.split(".")
    if parts[0] != "rocas" or len(parts) == 1:
        return None
    if parts[1] == "stacks" and len(parts) > 2 and parts[2] in STACK_PACKAGES:
        return f"stacks.{parts[2]}"
    return parts[1]


def _module_of(path: Path) -> str:
    rel = path.relative_to(ROOT.parent).with_suffix("")
    parts = list(rel.parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> list[tuple[int, str]]:
    """(line, dotted module) of every import in the file, inside functions too."""
    module = _module_of(path)
    package = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package[:len(package) - node.level + 1] + ([base] if base else []))
            if base != "rocas":
                found.append((node.lineno, base))
            found += [(node.lineno, f"{base}.{a.name}") for a in node.names]
    return found


def _graph() -> tuple[nx.DiGraph, dict[tuple[str, str], list[str]]]:
    graph, where = nx.DiGraph(), {}
    for path in SOURCES:
        src = _unit(_module_of(path))
        for line, target in _imports(path):
            dst = _unit(target)
            if src and dst and dst != src:
                graph.add_edge(src, dst)
                where.setdefault((src, dst), []).append(f"{path.relative_to(ROOT.parent)}:{line}")
    return graph, where


def test_no_circle_between_subpackages():
    graph, where = _graph()
    assert graph.number_of_nodes() >= 15
    circles = list(nx.simple_cycles(graph))
    shown = [" -> ".join([*c, c[0]]) + ": " + "; ".join(
        f"{a}->{b} at {where[(a, b)][0]}" for a, b in zip(c, [*c[1:], c[0]], strict=True))
        for c in circles]
    assert shown == []


def test_the_layers_run_one_way():
    graph, _ = _graph()
    below = {"sim": "rollout", "stacks": "rollout", "scenarios": "sim", "recording": "analysis"}
    for low, high in below.items():
        assert not graph.has_edge(low, high), f"{low} imports {high}"


def test_no_code_compares_a_stack_name_outside_the_registry():
    names = set(registry.names())
    found = []
    for path in SOURCES:
        if path == ROOT / "stacks" / "registry.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Compare):
                for side in (node.left, *node.comparators):
                    if isinstance(side, ast.Constant) and side.value in names:
                        found.append(f"{path.relative_to(ROOT.parent)}:{node.lineno}")
    assert found == []


def test_no_file_is_longer_than_one_reader_holds_in_mind():
    long = {str(p.relative_to(ROOT.parent)): n for p in SOURCES
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_FILE_LINES}
    assert long == {}


def test_at_most_five_long_functions():
    long = []
    for path in SOURCES:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                n = node.end_lineno - node.lineno + 1
                if n > MAX_FUNCTION_LINES:
                    long.append(f"{path.relative_to(ROOT.parent)}:{node.name} ({n})")
    assert len(long) <= MAX_LONG_FUNCTIONS, long
