"""The one shape analysis reads (:class:`Dataset`: study exports and simulation output alike;
made by :mod:`emogen.analysis.data`), and reading one output table of a folder."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from emogen.analysis.study_export import StudyExport
from emogen.analysis.study_export import read_output as read_output

#: The columns of :attr:`Dataset.elites` before the weights.
ORDERED = ["group", "participant", "sample", "generation", "n_selected", "error", "complete"]


@dataclass(frozen=True, eq=False)
class Dataset:
    """Elites of every sample and generation, ready for analysis.

    elites : one row per (group, sample, generation): ``group``, ``participant``, ``sample``,
    ``generation``, ``n_selected``, ``error`` (CD to the target or proxy target) and the weight
    ``columns`` (when recorded). bias : one row per sample, ``best_initial_error`` (CD of the
    closest generation-0 face to the (proxy) target). targets : known target weights per group
    (simulations). configs : the resolved simulation config per group (simulations).
    """

    kind: str
    source: Path
    elites: pd.DataFrame
    columns: tuple[str, ...]
    generations: int
    error_kind: str
    bias: pd.DataFrame
    groups: tuple[str, ...]
    targets: dict[str, np.ndarray] = field(default_factory=dict)
    configs: dict[str, dict[str, Any]] = field(default_factory=dict)
    ratings: pd.DataFrame | None = None
    #: a study's categorise answers (the export's ``categorise_responses``), when it has one
    responses: pd.DataFrame | None = None
    #: a study's final faces (from the export's ``final_faces``), in the columns of ``elites``
    finals: pd.DataFrame | None = None
    population_size: int = 10
    selections: tuple[int, ...] = ()
    notes: list[str] = field(default_factory=list)
    #: a study's export, loaded once (every table of it the analysis reads)
    export: StudyExport | None = None

    @property
    def has_weights(self) -> bool:
        return bool(self.columns)

    @property
    def final(self) -> pd.DataFrame:
        """Final faces: a study's ``finals``; a simulation's elites of generation G."""
        if self.finals is not None:
            return self.finals
        e = self.elites
        return e[(e["generation"] == self.generations) & e["complete"]]

    def final_weights(self, group: str, one_per_participant: bool = False) -> np.ndarray:
        """(n, S) the group's final faces; ``one_per_participant``: one of each participant's
        (independent samples where participants repeated the group)."""
        f = self.final
        f = f[f["group"] == group]
        if one_per_participant:
            f = f.drop_duplicates("participant", keep="first")
        return f[list(self.columns)].to_numpy(dtype=np.float64)

    def errors(self, group: str) -> np.ndarray:
        """(n_samples, G + 1) elite errors of a group (NaN where a sample stopped early)."""
        e = self.elites[self.elites["group"] == group]
        wide = e.pivot_table(index="sample", columns="generation", values="error", aggfunc="first")
        wide = wide.reindex(columns=range(self.generations + 1))
        return wide.to_numpy(dtype=np.float64)
