"""The import graph of the lower layers and the CLI: one-way, no circles.

Parses every module's imports (function-level ones included) with ``ast`` and checks that
``model`` imports nothing above it, ``correct``/``appearance``/``metrics``/``render`` nothing
from a higher layer, only ``emogen.cli`` imports ``emogen.cli``, and the modules of these
layers import each other without a cycle.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PKG = SRC / "emogen"

#: the layers from the bottom; a package may import only from layers below its own
LAYERS = (
    ("model",),
    ("metrics", "appearance"),
    ("correct",),
    ("render",),
    ("ga",),
    ("simulate", "study"),
    ("web",),
    ("analysis",),
    ("cli",),
)
CHECKED = ("model", "metrics", "appearance", "correct", "render")
FORBIDDEN = {
    package: tuple(p for upper in LAYERS[k:] for p in upper if p != package)
    for k, layer in enumerate(LAYERS)
    for package in layer
    if package in CHECKED
}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
            found |= {f"{node.module}.{a.name}" for a in node.names}
    return {m for m in found if m == "emogen" or m.startswith("emogen.")}


def _graph() -> dict[str, set[str]]:
    """Module → the emogen modules it imports. ``from emogen.pkg import sub`` counts as an
    import of the submodule alone; a module's own parent packages are left out (Python runs
    them before the module in any case)."""
    modules = {_module_name(p): p for p in PKG.rglob("*.py")}
    graph = {}
    for name, p in modules.items():
        found = {m for m in _imports(p) if m in modules and m != name}
        found -= {m for m in found if any(o.startswith(m + ".") for o in found)}
        graph[name] = {m for m in found if not name.startswith(m + ".")}
    return graph


def test_import_parser_sees_function_level_imports(tmp_path: Path) -> None:
    f = tmp_path / "m.py"
    f.write_text(
        "import os\nfrom emogen.model import face\ndef g():\n    from emogen.cli import app\n"
    )
    assert _imports(f) == {"emogen.model", "emogen.model.face", "emogen.cli", "emogen.cli.app"}


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_lower_layers_import_nothing_above_them(package: str) -> None:
    bad = [
        f"{mod} imports {dep}"
        for mod, deps in _graph().items()
        if mod.startswith(f"emogen.{package}")
        for dep in deps
        if any(dep.startswith(f"emogen.{up}") for up in FORBIDDEN[package])
    ]
    assert bad == []


def test_only_the_cli_imports_the_cli() -> None:
    bad = [
        f"{mod} imports {dep}"
        for mod, deps in _graph().items()
        if not mod.startswith("emogen.cli") and mod != "emogen.__main__"
        for dep in deps
        if dep.startswith("emogen.cli")
    ]
    assert bad == []


def test_no_import_cycles_in_the_lower_layers_and_the_cli() -> None:
    scope = (
        "emogen.model",
        "emogen.metrics",
        "emogen.appearance",
        "emogen.correct",
        "emogen.render",
        "emogen.cli",
    )
    graph = {
        m: {d for d in deps if d.startswith(scope)}
        for m, deps in _graph().items()
        if m.startswith(scope)
    }
    state: dict[str, int] = {}
    cycles: list[list[str]] = []

    def visit(node: str, path: list[str]) -> None:
        state[node] = 1
        for dep in sorted(graph.get(node, ())):
            if state.get(dep) == 1:
                cycles.append([*path[path.index(dep) :], dep] if dep in path else [node, dep])
            elif dep not in state:
                visit(dep, [*path, dep])
        state[node] = 2

    for start in sorted(graph):
        if start not in state:
            visit(start, [start])
    assert cycles == []
