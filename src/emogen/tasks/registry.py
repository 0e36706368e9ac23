"""The registry of tasks: the one place a task is found by its name.

The study config's ``[[blocks]]`` tables, the study service's steps, the web layer's step route
and the participant's view, the replay and the simulated participants all look tasks up here.
The built-in tasks (``evolve``: the GA; ``categorise``: one face, one label) are registered when
this module is imported; another task is one :func:`register` call away (a lab's own module, or
a test's toy task), with no edit anywhere else.
"""

from __future__ import annotations

import difflib
import re
from typing import Any

from pydantic import ValidationError
from pydantic_core import PydanticCustomError

from emogen.errors import ConfigError
from emogen.tasks.blocks import TaskBlock
from emogen.tasks.categorise.task import CategoriseTask
from emogen.tasks.evolve.task import EvolveTask
from emogen.tasks.gsp.task import GspTask
from emogen.tasks.protocol import Begin, Command, Task

#: Every registered task, by name, in registration order.
TASKS: dict[str, Task] = {}
#: The task of a ``[[blocks]]`` table without ``task``, and of a study without blocks.
DEFAULT_TASK = EvolveTask.name
_NAME = re.compile(r"^[a-z][a-z0-9_]{0,15}$")
#: What a task must have besides its methods (:class:`emogen.tasks.protocol.Task`).
REQUIRED = (
    "block",
    "commands",
    "view_type",
    "result_type",
    "tables",
    "export_tables",
    "instructions",
    "screens",
    "start",
    "accept",
    "view",
    "prompt",
    "simulate",
)


def _literal(model: type[Any], field: str) -> str | None:
    """The one value a model's ``Literal`` field allows (None if it is not such a field)."""
    info = model.model_fields.get(field)
    args: tuple[Any, ...] = tuple(getattr(info.annotation, "__args__", ()) if info else ())
    return str(args[0]) if len(args) == 1 and isinstance(args[0], str) else None


def register(task: Task) -> None:
    """Add ``task`` (its name, its block's ``task`` Literal and its commands' names must be new,
    and the names match)."""
    name = task.name
    missing = [a for a in REQUIRED if not hasattr(task, a)]
    if missing:
        raise ConfigError(f"task {name!r} lacks {', '.join(missing)} (emogen.tasks.protocol.Task)")
    if not _NAME.fullmatch(name):
        raise ConfigError(f"a task's name is 1-16 lowercase letters, digits or '_'; got {name!r}")
    if name in TASKS:
        raise ConfigError(f"a task named {name!r} is registered already")
    if _literal(task.block, "task") != name:
        raise ConfigError(f"task {name!r}: its block's 'task' must be Literal[{name!r}]")
    taken = command_names()
    for cmd in task.commands:
        word = _literal(cmd, "command")
        if word is None or word in taken:
            raise ConfigError(
                f"task {name!r}: command {word!r} must be a Literal name no other task uses "
                f"(taken: {', '.join(sorted(taken))})"
            )
        taken[word] = cmd
    TASKS[name] = task


def unregister(name: str) -> None:
    """Remove a task (a test's toy task, after the test)."""
    TASKS.pop(name, None)


def task_named(name: str) -> Task:
    """The registered task called ``name``; a ConfigError naming the known ones otherwise."""
    if name in TASKS:
        return TASKS[name]
    close = difflib.get_close_matches(name, list(TASKS), n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    raise ConfigError(f"unknown task {name!r}{hint}; tasks: {', '.join(TASKS)}")


def command_names() -> dict[str, type[Command]]:
    """Every command a session takes, by name: ``begin`` and every task's."""
    out: dict[str, type[Command]] = {"begin": Begin}
    for task in TASKS.values():
        for cmd in task.commands:
            out[str(_literal(cmd, "command"))] = cmd
    return out


def command_name(cmd: type[Command]) -> str:
    """The name a command class answers to (its ``command`` Literal)."""
    return str(_literal(cmd, "command"))


def task_of_command(name: str) -> Task | None:
    """The task whose command ``name`` is (None for the study's own ``begin``)."""
    for task in TASKS.values():
        if any(_literal(c, "command") == name for c in task.commands):
            return task
    return None


def parse_command(body: dict[str, Any]) -> Command:
    """A command from its JSON body (``command`` names it): a ConfigError naming what is wrong
    (an unknown command with the known ones; a bad value with pydantic's message)."""
    known = command_names()
    word = body.get("command")
    if not isinstance(word, str) or word not in known:
        close = difflib.get_close_matches(str(word), list(known), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise ConfigError(f"unknown command {word!r}{hint}; commands: {', '.join(known)}")
    try:
        return known[word].model_validate(body)
    except ValidationError as exc:
        e = exc.errors()[0]
        field = ".".join(str(part) for part in e["loc"])
        where = f"{field}: " if field else ""
        got = f"; got {e['input']!r}" if field else ""
        raise ConfigError(f"command {word!r}: {where}{e['msg']}{got}") from None


def blocks_from(tables: Any) -> tuple[TaskBlock, ...]:
    """``[[blocks]]`` tables as their tasks' block configs (``task`` names the task; none: the
    default task). A bad value raises pydantic's ValidationError located at
    ``(k, task, key)``; an unknown task a ValueError naming the known ones."""
    if not isinstance(tables, list | tuple):
        raise ValueError(f"blocks must be a list of tables; got {tables!r}")
    out: list[TaskBlock] = []
    errors: list[Any] = []
    for k, data in enumerate(tables):
        if isinstance(data, TaskBlock):
            out.append(data)
            continue
        if not isinstance(data, dict):
            raise ValueError(f"blocks[{k + 1}] must be a table; got {data!r}")
        try:
            task = task_named(str(data.get("task", DEFAULT_TASK)))
        except ConfigError as exc:
            raise ValueError(f"blocks[{k + 1}].task: {exc}") from None
        try:
            out.append(task.block.model_validate({"task": task.name, **data}))
        except ValidationError as exc:
            for e in exc.errors():
                kind: str | PydanticCustomError = e["type"]
                if kind == "quoted":  # our own error type (emogen.config): carried as it was
                    kind = PydanticCustomError("quoted", e["msg"].replace("{", "{{"))
                errors.append({**e, "type": kind, "loc": (k, *e["loc"])})
    if errors:
        raise ValidationError.from_exception_data("blocks", errors)
    return tuple(out)


register(EvolveTask())
register(CategoriseTask())
register(GspTask())
