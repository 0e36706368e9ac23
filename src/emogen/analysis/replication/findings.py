"""A finding of the paper beside ours, with a verdict, and the small statistics the verdicts
and the tables use."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

VERDICTS = ("holds", "partly", "differs")


@dataclass(frozen=True)
class Finding:
    """What the paper found (``claim``, its numbers ``paper``), ours, and the verdict:
    **holds**, **partly** (some of it, or only qualitatively) or **differs**."""

    section: str
    claim: str
    paper: str
    ours: str
    verdict: str  # holds | partly | differs
    note: str = ""

    def __post_init__(self) -> None:
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict must be holds, partly or differs; got {self.verdict!r}")

    def line(self) -> str:
        return f"[{self.verdict:^7}] {self.section}: {self.claim} — paper {self.paper}; ours {self.ours}"


def graded(all_ok: bool, any_ok: bool) -> str:
    """'holds' when every check passed, 'partly' when some did, else 'differs'."""
    return "holds" if all_ok else "partly" if any_ok else "differs"


def cohen_d(a: np.ndarray, b: np.ndarray) -> float:
    """(mean a − mean b) / pooled sd."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    pooled = np.sqrt(
        ((len(a) - 1) * a.var(ddof=1) + (len(b) - 1) * b.var(ddof=1)) / (len(a) + len(b) - 2)
    )
    return float((a.mean() - b.mean()) / pooled) if pooled > 0 else 0.0


def pm(mu: float | None, sd: float | None, digits: int = 3) -> str:
    """'μ ± σ' for tables; '–' when neither is known."""
    if mu is None and sd is None:
        return "–"
    if mu is None:
        return f"σ {sd:.{digits}f}"
    return f"{mu:.{digits}f} ± {sd:.{digits}f}" if sd is not None else f"{mu:.{digits}f}"
