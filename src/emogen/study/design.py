"""Trial order: random (seeded per session), balanced Latin square (by session number), fixed.

Trials are the conditions emotions × identities × repetitions (``StudyConfig.conditions``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from emogen.study.config import StudyConfig


@dataclass(frozen=True)
class TrialOrder:
    """order: condition indices in presentation order; row: the Latin-square row used (or -1)."""

    order: tuple[int, ...]
    kind: str
    row: int


def balanced_latin_square(n: int) -> list[list[int]]:
    """Williams' balanced Latin square: every condition precedes every other equally often.

    n rows for even n; 2n rows (each row and its mirror) for odd n.
    """
    if n < 1:
        return []
    # 0, 1, n-1, 2, n-2, ... then each row shifted by one
    first = [0] + [(j + 1) // 2 if j % 2 == 1 else n - j // 2 for j in range(1, n)]
    rows = [[(c + r) % n for c in first] for r in range(n)]
    if n % 2 == 1:
        rows += [list(reversed(row)) for row in rows]
    return rows


def trial_order(
    config: StudyConfig, *, session_number: int, rng: np.random.Generator
) -> TrialOrder:
    """The order of a session's trials (session_number counts sessions of the study from 0)."""
    n = config.n_trials
    if config.order == "fixed":
        return TrialOrder(tuple(range(n)), "fixed", -1)
    if config.order == "latin_square":
        rows = balanced_latin_square(n)
        row = session_number % len(rows)
        return TrialOrder(tuple(rows[row]), "latin_square", row)
    return TrialOrder(tuple(int(i) for i in rng.permutation(n)), "random", -1)
