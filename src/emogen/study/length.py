"""How long a session takes: its screens counted from the design, times stated seconds a screen.

The seconds are assumptions, stated here and printed with every estimate (``emogen study
check``), not measurements of this study:

* a **selection** screen (ten faces: choose the best, then any acceptable ones) takes 6–9 s, a
  **rating** screen (one face, one 1–7 answer) 3–5 s, and the **pages** around the trials
  (consent, instructions, the end) 1–2 minutes together. Source: the field trial of issue #32,
  where sessions of a 4 emotions × 2 identities study with ``generations = 10`` (8 trials of
  11 selection screens and a rating) took about 10–16 minutes: (600 s − 60 s − 8 × 3 s) / 88 =
  5.9 s and (960 s − 120 s − 8 × 5 s) / 88 = 9.1 s a selection screen. This estimate gives
  that study "about 10–16 minutes";
* a **labelling** screen (one face, a label, perhaps two ratings) 4–8 s (an assumption: no
  study of this kind was timed yet).

Restarts ("Start again") are not counted: a session with restarts takes longer. Once sessions
are done, the dashboard shows how long they really took; a study whose sessions are much longer
than the estimate should say so in its own consent text.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from emogen.tasks.blocks import Condition
from emogen.tasks.registry import TASKS, task_named


def seconds_per_screen() -> dict[str, tuple[float, float]]:
    """Seconds a screen of each kind takes (low, high), as each task states them (see the
    module docstring for the built-in tasks' sources)."""
    return {kind: secs for task in TASKS.values() for kind, secs in task.screens.items()}


#: Consent, instructions and the end page, together (seconds, low and high).
PAGES_SECONDS = (60.0, 120.0)


@dataclass(frozen=True)
class SessionLength:
    """screens: how many screens of each kind a session shows; seconds: (low, high)."""

    screens: dict[str, int]
    seconds: tuple[float, float]

    @property
    def minutes(self) -> tuple[int, int]:
        """(low, high) rounded to whole minutes (at least 1)."""
        low, high = self.seconds
        return max(1, round(low / 60)), max(1, math.ceil(high / 60))

    def words(self) -> str:
        """``"about 10–16 minutes"`` (one number when both round alike)."""
        low, high = self.minutes
        span = f"{low}" if low == high else f"{low}–{high}"
        return f"about {span} minute{'s' if high > 1 else ''}"

    def basis(self) -> str:
        """What the estimate counts: ``"88 selection screens × 6–9 s + … + 1–2 min of …"``."""
        secs = seconds_per_screen()
        parts = [
            f"{n} {kind} screens × {secs[kind][0]:g}–{secs[kind][1]:g} s"
            for kind, n in self.screens.items()
            if n
        ]
        low, high = (s / 60 for s in PAGES_SECONDS)
        return " + ".join([*parts, f"{low:g}–{high:g} min of consent, instructions and end"])

    def explained(self) -> str:
        """The estimate with the screens and the seconds it assumes, for the researcher."""
        return (
            f"a session takes {self.words()} ({self.basis()}; restarts not counted; the "
            "seconds a screen are assumptions, see emogen.study.length)"
        )


def session_length(conditions: Sequence[Condition], generations: int) -> SessionLength:
    """The screens of a session of these trials (``StudyConfig.conditions()``; ``generations``:
    ``ga.generations``) and the time they take, each trial's screens as its task counts them
    (a block's face table read when the server starts counts no trials here)."""
    screens = {kind: 0 for kind in seconds_per_screen()}
    for condition in conditions:
        for kind, n in task_named(condition.task).screens_of(condition, generations).items():
            screens[kind] += n
    secs = seconds_per_screen()
    low = PAGES_SECONDS[0] + sum(n * secs[k][0] for k, n in screens.items())
    high = PAGES_SECONDS[1] + sum(n * secs[k][1] for k, n in screens.items())
    return SessionLength(screens, (low, high))
