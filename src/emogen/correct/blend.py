"""Blending positions face by face in a fixed order, so that a face's correction depends on
that face alone.

A matrix product over a batch (BLAS) may sum a face's terms in an order that depends on the
batch's size and on the number of BLAS threads, which moves the last bit of a vertex; the
collision solve then returns weights a few 10⁻¹⁶ apart. A study's corrected weights are recorded
and compared exactly on replay — by another process, maybe another machine's BLAS — so the
positions the collision detector reads are blended here, one face at a time, shape k = 0, 1, …
in order (zero weights skipped), compiled with numba.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def _blend(
    start: np.ndarray, weights: np.ndarray, rows: np.ndarray
) -> np.ndarray:  # pragma: no cover - compiled
    n, k_n = weights.shape
    d_n = rows.shape[1]
    out = np.empty((n, d_n))
    shared = start.shape[0] == 1
    for i in range(n):
        s = 0 if shared else i
        for d in range(d_n):
            out[i, d] = start[s, d]
        for k in range(k_n):
            w = weights[i, k]
            if w != 0.0:
                for d in range(d_n):
                    out[i, d] += w * rows[k, d]
    return out


def blend(start: np.ndarray, weights: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """start + weights @ rows, float64, each face summed in the same order whatever the batch.

    start : (D,) or (B, D) — shared by every face, or one per face; weights (B, K); rows (K, D).
    Returns (B, D).
    """
    w = np.ascontiguousarray(weights, dtype=np.float64)
    r = np.ascontiguousarray(rows, dtype=np.float64)
    s = np.ascontiguousarray(np.atleast_2d(start), dtype=np.float64)
    if w.ndim != 2 or r.ndim != 2 or w.shape[1] != r.shape[0] or s.shape[1] != r.shape[1]:
        raise ValueError(
            f"blend needs start (D,) or (B, D), weights (B, K), rows (K, D); got {s.shape}, "
            f"{w.shape}, {r.shape}"
        )
    if s.shape[0] not in (1, w.shape[0]):
        raise ValueError(f"start has {s.shape[0]} rows for {w.shape[0]} faces")
    return _blend(s, w, r)
