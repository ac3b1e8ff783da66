"""No circle between the modules of rocas.recording: the reading layers import downwards only.

Every import statement counts, also those inside functions and under ``TYPE_CHECKING``: a
lazy import that closes a circle hides the layering, it does not remove it. The implicit
import of the package ``rocas.recording`` that every submodule import brings is Python's, not
an edge the code chose, and is left out (``from rocas.recording import reader`` is an edge to
``reader``; ``from rocas.recording import open_recording`` one to the package's
``__init__``); what ``__init__`` itself imports is counted.

Run as a script, it prints every circle it finds (one line each), or ``no circles``.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import rocas.recording

PACKAGE = "rocas.recording"
PACKAGE_DIR = Path(rocas.recording.__file__).parent


def _module_name(path: Path, package_dir: Path) -> str:
    rel = path.relative_to(package_dir).with_suffix("")
    parts = [p for p in rel.parts if p != "__init__"]
    return ".".join([PACKAGE, *parts])


def import_graph(package_dir: Path = PACKAGE_DIR) -> dict[str, set[str]]:
    """Module -> the modules of the package it imports (anywhere in its source)."""
    modules = {_module_name(p, package_dir): p for p in sorted(package_dir.rglob("*.py"))}
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        is_package = path.name == "__init__.py"
        edges: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:  # relative: resolved against this module's package
                    anchor = name.split(".")
                    anchor = anchor if is_package else anchor[:-1]
                    anchor = anchor[: len(anchor) - (node.level - 1)]
                    base = ".".join([*anchor, base] if base else anchor)
                subs = [f"{base}.{alias.name}" for alias in node.names]
                # ``from package import module`` imports the module; any other name is the
                # package's own (its ``__init__``)
                targets = [t for t in subs if t in modules]
                if len(targets) < len(subs):
                    targets.append(base)
            for target in targets:
                if target in modules and target != name:
                    edges.add(target)
        graph[name] = edges
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (each a circle or more)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_the_graph_sees_the_reading_layers():
    graph = import_graph()
    assert "rocas.recording.model" in graph["rocas.recording.foreign"]
    assert "rocas.recording.reader" in graph["rocas.recording.formats"]
    assert "rocas.recording.rosbag" in graph["rocas.recording.formats"]  # a lazy import counts


def test_a_circle_is_found(tmp_path):
    # the checker itself: two modules importing each other, one of them inside a function
    pkg = tmp_path / "recording"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from rocas.recording.b import f\n")
    (pkg / "b.py").write_text("def f():\n    from rocas.recording import a\n")
    assert cycles(import_graph(pkg)) == [["rocas.recording.a", "rocas.recording.b"]]
    # a name the package exports is an import of the package's __init__
    (pkg / "__init__.py").write_text("from rocas.recording.c import g\n")
    (pkg / "b.py").write_text("")
    (pkg / "c.py").write_text("def g():\n    from rocas.recording import f\n")
    assert cycles(import_graph(pkg)) == [["rocas.recording", "rocas.recording.c"]]


def test_no_circle_between_the_modules_of_recording():
    assert cycles(import_graph()) == []


if __name__ == "__main__":
    found = cycles(import_graph())
    for component in found:
        print("circle:", " <-> ".join(component))
    print(f"{len(import_graph())} modules, {sum(map(len, import_graph().values()))} import "
          f"edges, {len(found)} circles" if found else
          f"{len(import_graph())} modules, {sum(map(len, import_graph().values()))} import edges: "
          "no circles")
    sys.exit(1 if found else 0)
