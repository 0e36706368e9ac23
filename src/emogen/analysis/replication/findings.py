"""A finding of the paper beside ours, with a verdict, and the small statistics the verdicts
and the tables use."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

VERDICTS = ("holds", "partly", "differs", "inconclusive")


@dataclass(frozen=True)
class Finding:
    """What the paper found (``claim``, its numbers ``paper``), ours, and the verdict:
    **holds**, **partly** (some of it, or only qualitatively), **differs** or
    **inconclusive** (the evidence does not decide), by the named ``rule``
    (:data:`~emogen.analysis.replication.verdicts.RULES`). ``value``: the effect size the
    verdict rests on (``value_label`` says what it is), combined over seeds.
    ``paper_finding=False``: our own proposal, reported apart from the tally.
    ``evidence``: per-run data and their tests (one per part of the claim): the verdict over
    seeds is decided on the runs of all seeds pooled, the parts' verdicts joined by ``parts``
    (default :func:`~emogen.analysis.replication.verdicts.join`); ``interval``: the
    decisions in words. ``fitted``: the fitted object per seed the quantity rests on (a GMM,
    a PCA, an empirical metric's training, a target built from the seed's runs): decided on
    the seeds' estimates, one per fit, not on the pooled runs. ``outside``: why a paper
    finding stays outside the tally (a model-specific absolute level, an oracle, another
    finding's event), empty when it counts."""

    section: str
    claim: str
    paper: str
    ours: str
    verdict: str  # holds | partly | differs | inconclusive
    note: str = ""
    rule: str = "order"
    value: float | None = None
    value_label: str = ""
    paper_finding: bool = True
    evidence: tuple[Any, ...] = field(default=(), compare=False)  # intervals.Evidence
    parts: Callable[[list[str]], str] | None = field(default=None, compare=False)
    interval: str = ""
    fitted: str = ""
    outside: str = ""

    def __post_init__(self) -> None:
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict must be one of {VERDICTS}; got {self.verdict!r}")

    @property
    def counted(self) -> bool:
        """In the tally: a paper finding, not outside it."""
        return self.paper_finding and not self.outside

    @property
    def key(self) -> tuple[str, str]:
        return (self.section, self.claim)

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


def mean_diff_ci(a: np.ndarray, b: np.ndarray) -> tuple[float, float, float]:
    """mean(a) − mean(b) and its 95% (Welch, normal) interval: (difference, lo, hi)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    d = float(a.mean() - b.mean())
    se = float(np.sqrt(a.var(ddof=1) / len(a) + b.var(ddof=1) / len(b)))
    return d, d - 1.96 * se, d + 1.96 * se


def ci_text(d: float, lo: float, hi: float) -> str:
    return f"{d:+.3f} (95% CI {lo:+.3f}…{hi:+.3f})"
