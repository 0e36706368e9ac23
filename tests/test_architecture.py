"""The package's shape: no import cycles, one-way layers, small modules and functions.

Imports are read from the source with ``ast`` (every ``import``, including those inside
functions and under ``TYPE_CHECKING``: a type-only import is still a dependency of the design).
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = SRC / "emogen"

#: The layers, lowest first: a module may import from its own package and from packages of
#: lower layers only; packages sharing a layer are siblings and import nothing of each other.
#: model → correct → ga → tasks → (simulate | study → web) → analysis → cli, with metrics, appearance
#: and render where they are used (docs/architecture.md).
LAYERS: tuple[tuple[str, ...], ...] = (
    ("errors",),
    ("rng", "config", "data", "columns", "solvers", "leftovers"),
    ("model",),
    ("metrics", "appearance"),
    ("correct",),
    ("render",),
    ("ga",),
    ("tasks",),
    ("simulate", "study"),
    ("web",),
    ("analysis",),
    ("cli",),
    ("__main__",),
)
RANK = {name: i for i, names in enumerate(LAYERS) for name in names}

#: Size limits: modules of at most ~400 lines, functions of at most 80. Exempt: the Alembic
#: migrations (one schema, written out) and numba kernels (one loop nest each, split by hand
#: they get slower and no clearer).
MODULE_LINES = 400
FUNCTION_LINES = 80
EXEMPT_MODULES = ("study/migrations/versions/",)


def modules() -> dict[str, Path]:
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(SRC).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        found[name] = path
    return found


def imports(path: Path, name: str, known: dict[str, Path]) -> Iterator[tuple[str, int]]:
    """(imported emogen module, line) for every import statement of a module."""
    is_package = path.name == "__init__.py"
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        targets: list[str] = []
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = name.split(".")
                anchor = anchor if is_package else anchor[:-1]
                anchor = anchor[: len(anchor) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            targets = [
                f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names
            ]
        for target in targets:
            while target and target not in known:
                target = target.rpartition(".")[0]
            if target.startswith("emogen"):
                yield target, node.lineno


def graph() -> dict[str, set[str]]:
    known = modules()
    return {
        name: {t for t, _ in imports(path, name, known) if t != name}
        for name, path in known.items()
    }


def layer_of(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "emogen"


def test_every_package_has_a_layer() -> None:
    assert {layer_of(m) for m in modules()} - {"emogen"} <= set(RANK), "add it to LAYERS"


def test_no_import_cycles() -> None:
    g = graph()
    state: dict[str, int] = {}  # 1 on the stack, 2 done
    stack: list[str] = []
    cycles: list[list[str]] = []

    def visit(node: str) -> None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(g.get(node, ())):
            if layer_of(nxt) == "emogen":
                continue  # the root package: __version__ and the errors (checked below)
            if state.get(nxt) == 1:
                cycles.append([*stack[stack.index(nxt) :], nxt])
            elif nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = 2

    for node in sorted(g):
        if node not in state:
            visit(node)
    assert cycles == [], "import cycles:\n" + "\n".join(" → ".join(c) for c in cycles)


def test_layers_point_one_way() -> None:
    known = modules()
    wrong = []
    for name, path in known.items():
        own = layer_of(name)
        if own == "emogen":
            continue
        for target, line in imports(path, name, known):
            other = layer_of(target)
            if other in (own, "emogen"):
                continue
            if RANK[other] >= RANK[own]:
                wrong.append(f"{path.relative_to(SRC)}:{line} ({own}) imports {target} ({other})")
    assert wrong == [], "imports against the layering:\n" + "\n".join(wrong)


def test_the_root_package_imports_only_the_errors_eagerly() -> None:
    tree = ast.parse((PACKAGE / "__init__.py").read_text())
    eager = {n.module for n in tree.body if isinstance(n, ast.ImportFrom)}
    assert eager <= {"emogen.errors"}, eager


def test_the_core_never_imports_the_web_framework() -> None:
    web = ("fastapi", "starlette", "uvicorn")
    found = []
    for name, path in modules().items():
        if layer_of(name) in ("web", "cli", "__main__"):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
            if isinstance(node, ast.ImportFrom):
                names = [node.module or ""]
            found += [f"{name}: {n}" for n in names if n.split(".")[0] in web]
    assert found == []


def _is_numba_kernel(node: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    return any("njit" in ast.unparse(d) or "numba" in ast.unparse(d) for d in node.decorator_list)


def test_modules_and_functions_stay_small() -> None:
    big = []
    for path in modules().values():
        rel = path.relative_to(PACKAGE).as_posix()
        if rel.startswith(EXEMPT_MODULES):
            continue
        tree = ast.parse(path.read_text())
        kernels = [
            n
            for n in ast.walk(tree)
            if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef) and _is_numba_kernel(n)
        ]
        kernel_lines = sum((n.end_lineno or n.lineno) - n.lineno + 1 for n in kernels)
        lines = len(path.read_text().splitlines()) - kernel_lines
        if lines > MODULE_LINES:
            big.append(f"{rel}: {lines} lines (limit {MODULE_LINES}, numba kernels not counted)")
        for n in ast.walk(tree):
            if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef) and n not in kernels:
                length = (n.end_lineno or n.lineno) - n.lineno + 1
                if length > FUNCTION_LINES:
                    big.append(
                        f"{rel}:{n.lineno} {n.name}: {length} lines (limit {FUNCTION_LINES})"
                    )
    assert big == [], "too big:\n" + "\n".join(big)


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("from emogen.ga.draws import Draws", {"emogen.ga.draws"}),
        ("from emogen.ga import draws", {"emogen.ga.draws"}),
        ("import emogen.model.face", {"emogen.model.face"}),
        ("from . import operators", {"emogen.ga.operators"}),
        ("from .draws import Draws", {"emogen.ga.draws"}),
        ("def f():\n    from emogen.study.config import StudyConfig", {"emogen.study.config"}),
        ("import numpy", set()),
    ],
)
def test_the_import_reader(tmp_path: Path, source: str, expected: set[str]) -> None:
    """The reader the checks above rely on finds every kind of import statement."""
    path = tmp_path / "probe.py"
    path.write_text(source)
    assert {t for t, _ in imports(path, "emogen.ga.probe", modules())} == expected
