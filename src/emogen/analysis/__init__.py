"""Analysis of expression distributions (Section IV): the library behind ``emogen analyse``,
``emogen replicate`` and ``emogen power``.

* :mod:`~emogen.analysis.data` — study exports and simulation output as one :class:`Dataset`;
* :mod:`~emogen.analysis.distributions` — per-generation errors, KDE-based KL divergence;
* :mod:`~emogen.analysis.repeatability` — inter-sample CD bins, initial target bias;
* :mod:`~emogen.analysis.separability` — PCA + GMM, cluster correspondence, confusion table;
* :mod:`~emogen.analysis.noise` — GA-noise threshold and the group-spread test;
* :mod:`~emogen.analysis.prototypes` — per-participant prototypes, group means;
* :mod:`~emogen.analysis.power` — power analysis by simulation;
* :mod:`~emogen.analysis.plots`, :mod:`~emogen.analysis.face_sheets`,
  :mod:`~emogen.analysis.report` — figures, rendered heatmaps, the HTML/Markdown report;
* :mod:`~emogen.analysis.analyse` and :mod:`~emogen.analysis.replication` — the two reports.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "AnalysisOptions",
    "Dataset",
    "GANoise",
    "ReplicateSettings",
    "analyse",
    "gmm_separability",
    "kl_divergence",
    "kl_per_generation",
    "load_dataset",
    "participant_prototypes",
    "power_analysis",
    "repeatability_bins",
    "replicate",
    "spread_test",
]

_WHERE = {
    "AnalysisOptions": "emogen.analysis.analyse",
    "analyse": "emogen.analysis.analyse",
    "Dataset": "emogen.analysis.data",
    "load_dataset": "emogen.analysis.data",
    "kl_divergence": "emogen.analysis.distributions",
    "kl_per_generation": "emogen.analysis.distributions",
    "GANoise": "emogen.analysis.noise",
    "spread_test": "emogen.analysis.noise",
    "participant_prototypes": "emogen.analysis.prototypes",
    "power_analysis": "emogen.analysis.power",
    "repeatability_bins": "emogen.analysis.repeatability",
    "ReplicateSettings": "emogen.analysis.replication",
    "replicate": "emogen.analysis.replication",
    "gmm_separability": "emogen.analysis.separability",
}


def __getattr__(name: str) -> Any:  # lazy: importing the package costs nothing
    if name in _WHERE:
        import importlib

        return getattr(importlib.import_module(_WHERE[name]), name)
    raise AttributeError(name)
