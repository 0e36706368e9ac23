"""The registry is the one place a task is found (issue #38): no task's or command's name as a
string in the study layer, the web layer's Python or the page's shared modules; registering a
task checks its names; the step route's body and the state's view follow the registry."""

from __future__ import annotations

import ast
import re
from pathlib import Path
from typing import Any, ClassVar, Literal

import pytest

from emogen.errors import ConfigError
from emogen.tasks.blocks import TaskBlock
from emogen.tasks.protocol import TaskDefaults, TrialCommand
from emogen.tasks.registry import TASKS, command_names, parse_command, register

SRC = Path(__file__).resolve().parents[2] / "src" / "emogen"
NAMES = {*TASKS, *command_names()} - {"begin"}


def python_strings(path: Path) -> list[tuple[int, str]]:
    """(line, text) of every string constant of a module (docstrings aside)."""
    tree = ast.parse(path.read_text())
    docs = {
        id(n.body[0].value)
        for n in ast.walk(tree)
        if isinstance(n, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef)
        and n.body
        and isinstance(n.body[0], ast.Expr)
        and isinstance(n.body[0].value, ast.Constant)
    }
    return [
        (n.lineno, n.value)
        for n in ast.walk(tree)
        if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docs
    ]


def test_the_study_and_web_layers_name_no_task() -> None:
    files = [p for p in (SRC / "study").rglob("*.py") if "migrations" not in p.parts]
    files += list((SRC / "web").glob("*.py"))
    found = [
        f"{p.relative_to(SRC)}:{line}: {text!r}"
        for p in files
        for line, text in python_strings(p)
        if text in NAMES
    ]
    assert found == [], "task or command names outside the tasks:\n" + "\n".join(found)


def test_the_study_and_web_layers_import_no_task_package() -> None:
    """They reach a task through the registry and the protocol only, never its package."""
    packages = {type(t).__module__.rsplit(".", 1)[0] for t in TASKS.values()}
    assert "emogen.tasks.evolve" in packages  # the check sees the real tasks
    files = [p for p in (SRC / "study").rglob("*.py") if "migrations" not in p.parts]
    files += list((SRC / "web").glob("*.py"))
    found = []
    for p in files:
        for node in ast.walk(ast.parse(p.read_text())):
            names = [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            names += [a.name for a in node.names] if isinstance(node, ast.Import) else []
            found += [
                f"{p.relative_to(SRC)}:{node.lineno}: {n}"
                for n in names
                if any(n == pkg or n.startswith(pkg + ".") for pkg in packages)
            ]
    assert found == [], "task packages imported outside the tasks:\n" + "\n".join(found)


def test_the_page_s_shared_modules_name_no_task() -> None:
    names = "|".join(sorted(TASKS))
    quoted = re.compile(rf"""["'`]({names})["'`]""")
    found = [
        f"{p.name}:{k + 1}"
        for p in (SRC / "web" / "static").glob("*.js")
        for k, line in enumerate(p.read_text().splitlines())
        if quoted.search(line)
    ]
    assert found == []


class _Block(TaskBlock):
    task: Literal["twin"]


class _Answer(TrialCommand):
    command: Literal["answer"]  # the categorise task's command name


class _Twin(TaskDefaults):
    name: ClassVar[str] = "twin"
    block: ClassVar[type[TaskBlock]] = _Block
    commands: ClassVar[tuple[type[TrialCommand], ...]] = (_Answer,)
    view_type = result_type = dict
    tables = export_tables = ()
    instructions = ""
    screens: ClassVar[dict[str, tuple[float, float]]] = {}
    start = accept = view = prompt = simulate = TaskDefaults.face


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({}, "command 'answer' must be a Literal name no other task uses"),
        ({"name": "evolve"}, "a task named 'evolve' is registered already"),
        ({"name": "Bad Name"}, "a task's name is 1-16 lowercase letters"),
        ({"name": "other"}, "its block's 'task' must be Literal\\['other'\\]"),
    ],
)
def test_a_task_with_a_taken_or_bad_name_is_refused(change: dict[str, Any], message: str) -> None:
    task = type("Twin", (_Twin,), change)()
    before = dict(TASKS)
    with pytest.raises(ConfigError, match=message):
        register(task)
    assert "twin" not in TASKS and before == TASKS


def test_a_task_without_its_parts_is_refused_naming_them() -> None:
    bare = type("Bare", (TaskDefaults,), {"name": "bare"})()
    with pytest.raises(ConfigError, match="task 'bare' lacks block, commands, view_type"):
        register(bare)
    assert "bare" not in TASKS


def test_a_command_body_is_found_by_its_name() -> None:
    cmd = parse_command({"command": "answer", "key": "k" * 8, "trial": 2, "label": "sad"})
    assert type(cmd).__name__ == "Answer" and cmd.payload() == {
        "trial": 2,
        "response_ms": None,
        "label": "sad",
        "intensity": None,
        "confidence": None,
    }
    with pytest.raises(ConfigError, match=r"unknown command 'selct' \(did you mean 'select'\?\)"):
        parse_command({"command": "selct", "key": "k" * 8})
    with pytest.raises(ConfigError, match=r"command 'rate': .*greater than or equal to 1"):
        parse_command({"command": "rate", "key": "k" * 8, "trial": 0, "value": 0})
