"""The task protocol: what the study layer asks of every task, and the registry of tasks.

A task (``evolve``: the GA; ``categorise``: one face, one label) is one module: its block
config (:mod:`emogen.tasks.blocks`), the view of a trial it sends the page, the step commands
it accepts, and a simulated participant (:mod:`emogen.tasks.simulated`). The study layer keeps
a session's sequence of trials and drives each trial through its task's runner
(:class:`TaskRunner`): starting it (what it shows is stored before it is shown), its view, its
commands. Adding a task adds a module here, a runner in the study layer, a page component and
an export table — not fields threaded through the session.
"""

from __future__ import annotations

from typing import Any, Protocol

from typing_extensions import TypedDict


class FaceView(TypedDict):
    """A face: its id in the trial and its full weights (shapes, then correctives) in GLB
    target order."""

    id: int
    weights: list[float]


#: The step commands each task accepts (the page's POST routes and the steps' ``kind``).
COMMANDS: dict[str, frozenset[str]] = {
    "evolve": frozenset({"select", "restart", "rate"}),
    "categorise": frozenset({"categorise"}),
}
TASKS: tuple[str, ...] = tuple(COMMANDS)


class TaskRunner(Protocol):
    """A task as the study layer runs it over a session's trials (one runner per task,
    registered in ``SessionSteps.runners``; its part of the participant's state is registered in
    ``emogen.study.view.TRIAL_VIEWS``; its step commands in :data:`COMMANDS`)."""

    #: the task's name, as in ``[[blocks]] task = …`` and ``trials.task``
    task: str

    def start(self, db: Any, sess: Any, row: Any) -> Any:
        """Start the session's trial ``row``: store what it shows (before it is shown); return
        the population it has just shown, if any (the view then need not read it back)."""
