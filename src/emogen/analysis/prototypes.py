"""Prototypes: each participant's mean final face per group (emotion), and group means.

A participant's *prototype* of an emotion is the mean of the final faces they evolved for it
(over repetitions and identities in the group). Group means of prototypes weight every
participant equally, however many trials each completed.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from emogen.errors import ConfigError


def participant_prototypes(final: pd.DataFrame, columns: list[str]) -> pd.DataFrame:
    """One row per (group, participant): ``n_trials`` and the mean of each weight column.

    final : one row per final face with ``group``, ``participant`` and the weight ``columns``.
    """
    missing = [c for c in ("group", "participant", *columns) if c not in final.columns]
    if missing:
        raise ConfigError(f"final faces lack columns {missing[:5]}")
    frame = final[["group", "participant", *columns]].copy()  # consolidated: one block
    grouped = frame.groupby(["group", "participant"], sort=True, observed=True)
    means = pd.concat([grouped.size().rename("n_trials"), grouped[columns].mean()], axis=1)
    return means.reset_index()


def group_means(prototypes: pd.DataFrame, columns: list[str]) -> dict[str, np.ndarray]:
    """Mean prototype per group (every participant weighs the same)."""
    return {
        str(g): part[columns].to_numpy(dtype=np.float64).mean(axis=0)
        for g, part in prototypes.groupby("group", sort=True, observed=True)
    }


def top_weights(weights: np.ndarray, columns: list[str], k: int = 6) -> str:
    """The k largest weights as 'name 0.62, name 0.40, …' (for tables)."""
    w = np.asarray(weights, dtype=np.float64)
    order = np.argsort(-w)[:k]
    return ", ".join(f"{columns[i]} {w[i]:.2f}" for i in order if w[i] > 0.005)
