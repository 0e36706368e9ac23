"""Options of ``emogen analyse``."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from emogen.analysis.exclusions import ExclusionRule
from emogen.analysis.plan import DEFAULT_PRIMARY
from emogen.config import GAConfig


@dataclass(frozen=True)
class AnalysisOptions:
    render: bool = True
    noise_runs: int = 500
    noise_draws: int = 2000
    seed: int = 1
    gmm_dims: float = 2
    alpha: float = 0.05
    ga: GAConfig | None = None  # the study's GA settings (default: inferred from the data)
    render_size: int = 256
    # the participants' choice noise T (softmax, CD units) the GA-noise null simulates; None:
    # a simulation's own recorded T, and for a study an explicit, reported assumption of T = 0
    choice_noise: float | None = None
    # a participant table (CSV/Parquet: participant_id + e.g. group) joined to a study's faces
    participants: Path | None = None
    # the participant table's column whose groups are compared
    group_column: str = "group"
    # the exclusion rule applied before every analysis of a study (None: nobody excluded)
    exclusions: ExclusionRule | None = field(default_factory=ExclusionRule)
    # the command line that made the report (the methods block; default: this process's)
    command: str | None = None
    # the primary tests (emogen.analysis.plan.PLANNABLE); every other test is exploratory
    primary: tuple[str, ...] = DEFAULT_PRIMARY
    # a retest study's export (``retest_of``): the between-session reliability section
    retest: Path | None = None
