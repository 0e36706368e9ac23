"""Repeatability of evolved faces (Table III): inter-sample cosine-distance bins, target bias.

* :func:`repeatability_bins` — the share of face pairs whose CD (eq. 12) falls in each of the
  paper's bins [0, .25), [.25, .5), [.5, .75), [.75, 1]: every unordered pair of distinct
  samples (n (n − 1) / 2 pairs), counted in blocks so that 10,000 faces need no 10⁴ × 10⁴
  matrix. CD of blendshape weights (all ≥ 0) lies in [0, 1]; anything above 1 (negative
  weights) is counted in the last bin.
* :func:`initial_bias` — the paper's target bias: the CD of the *best* option at
  initialisation to the target (the lowest CD among the generation-0 faces), per sample.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from emogen.errors import ShapeError
from emogen.metrics import cosine_distance

BIN_EDGES: tuple[float, ...] = (0.0, 0.25, 0.5, 0.75, 1.0)
BIN_LABELS: tuple[str, ...] = ("[0, 0.25)", "[0.25, 0.5)", "[0.5, 0.75)", "[0.75, 1]")


def _unit_rows(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    f = np.asarray(faces, dtype=np.float64)
    if f.ndim != 2:
        raise ShapeError(f"faces must have shape (n_faces, n_weights); got {f.shape}")
    norms = np.linalg.norm(f, axis=1)
    zero = norms == 0
    unit = np.divide(f, norms[:, None], out=np.zeros_like(f), where=~zero[:, None])
    return unit, zero


def pairwise_cd_counts(
    faces: np.ndarray, edges: tuple[float, ...] = BIN_EDGES, *, block: int = 2048
) -> np.ndarray:
    """Counts of unordered pairs (i < j) per CD bin; the last bin is closed and open-ended."""
    unit, zero = _unit_rows(faces)
    n = len(unit)
    inner = np.asarray(edges[1:-1], dtype=np.float64)
    counts = np.zeros(len(edges) - 1, dtype=np.int64)
    for lo in range(0, n, block):
        a = unit[lo : lo + block]
        cd = 1.0 - a @ unit[lo:].T  # rows lo.., columns lo..: keep the upper triangle only
        za, zb = zero[lo : lo + block, None], zero[None, lo:]
        cd = np.where(za | zb, np.where(za & zb, 0.0, 1.0), np.clip(cd, 0.0, 2.0))
        iu = np.triu_indices(len(a), k=1, m=cd.shape[1])
        counts += np.bincount(np.searchsorted(inner, cd[iu], side="right"), minlength=len(counts))
    return counts


def repeatability_bins(faces: np.ndarray, edges: tuple[float, ...] = BIN_EDGES) -> np.ndarray:
    """Fractions (summing to 1) of face pairs per CD bin; NaNs when there are < 2 faces."""
    counts = pairwise_cd_counts(faces, edges)
    total = counts.sum()
    if total == 0:
        return np.full(len(counts), np.nan)
    return counts / total


def bins_frame(rows: dict[str, np.ndarray], percent: bool = True) -> pd.DataFrame:
    """A table of bin shares, one row per label (in % by default)."""
    scale = 100.0 if percent else 1.0
    return pd.DataFrame(
        {label: [float(v[i]) * scale for v in rows.values()] for i, label in enumerate(BIN_LABELS)},
        index=pd.Index(list(rows), name="set"),
    )


def best_initial_error(initial: np.ndarray, target: np.ndarray) -> np.ndarray:
    """CD of the closest generation-0 face to the target, per sample.

    initial : (n_samples, n_faces, n_weights) the initial populations; target : (n_weights,)
    or (n_samples, n_weights) (a proxy target per sample). Returns (n_samples,).
    """
    init = np.asarray(initial, dtype=np.float64)
    if init.ndim != 3:
        raise ShapeError(
            f"initial populations must have shape (n_samples, n_faces, n_weights); got {init.shape}"
        )
    t = np.asarray(target, dtype=np.float64)
    t = np.broadcast_to(t if t.ndim == 2 else t[None], (len(init), init.shape[2]))
    cd = cosine_distance(init, t[:, None, :])
    return np.asarray(cd.min(axis=1))


def initial_bias(best_errors: np.ndarray) -> tuple[float, float]:
    """(mean, sd) of the best initial option's CD to the target: the paper's target bias."""
    b = np.asarray(best_errors, dtype=np.float64)
    return float(b.mean()), float(b.std(ddof=1)) if len(b) > 1 else 0.0
