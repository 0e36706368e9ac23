"""Similarity of dynamic faces: the paper's CD over time, and a timing distance.

A dynamic face (``emogen.ga.genome.DynamicGenome``) has per gene a peak amplitude and five
temporal parameters after Jack, Garrod, Yu, Caldara & Schyns (2012, PNAS 109:7241). Its
**trajectory** is its full weight vectors at T times evenly over the clip, (…, T, S); its
**latencies** are each gene's onset, peak and offset times in seconds, (…, K, 3). Three
distances describe how far two dynamic faces are apart (docs/ga.md, "Similarity of dynamic
faces"), each symmetric and 0 between a face and itself:

* :func:`trajectory_cd` — total: CD (the paper's eq. 12) of the two trajectories taken as one
  vector each (every shape at every time). For faces whose genes all share one time course it
  is exactly the static CD of their peak weights (the common curve factors out of eq. 12).
* peak shape — the static CD (:func:`emogen.metrics.cosine_distance`) of the peak profiles,
  the amplitudes expanded to shapes: what a static observer compares.
* :func:`timing_distance` — timing in seconds: the root mean square difference of the
  latencies of the genes both faces show, each gene weighted by the product of its two
  amplitudes. A face moved later by Δ seconds is Δ away. NaN when the faces share no shown
  gene (their timing cannot be compared).

The trajectories and latencies are made from genes by :mod:`emogen.simulate.dynamic`.
"""

from __future__ import annotations

import numpy as np

from emogen.errors import ShapeError
from emogen.metrics.basic import cosine_distance


def trajectory_cd(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Total distance: CD of trajectories (…, T, S) as vectors of T·S numbers, broadcast.
    Returns (…)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.ndim < 2 or a.shape[-2:] != b.shape[-2:]:
        raise ShapeError(
            f"trajectories must have the same times and shapes (…, T, S); got {a.shape} and "
            f"{b.shape}"
        )
    return cosine_distance(a.reshape(*a.shape[:-2], -1), b.reshape(*b.shape[:-2], -1))


def timing_distance(
    latencies_a: np.ndarray,
    amplitudes_a: np.ndarray,
    latencies_b: np.ndarray,
    amplitudes_b: np.ndarray,
) -> np.ndarray:
    """Timing (s) of faces given by latencies (…, K, 3) and amplitudes (…, K), broadcast:
    sqrt(Σₖ wₖ Σⱼ Δₖⱼ² / (3 Σₖ wₖ)) over the latencies j (onset, peak, offset), with
    wₖ = amplitude_a,k · amplitude_b,k. Returns (…); NaN where no gene is shown by both."""
    lat_a = np.asarray(latencies_a, dtype=np.float64)
    lat_b = np.asarray(latencies_b, dtype=np.float64)
    if lat_a.shape[-1] != 3 or lat_b.shape[-1] != 3:
        raise ShapeError(
            "latencies must be (…, n_genes, 3): onset, peak and offset in seconds; got "
            f"{lat_a.shape} and {lat_b.shape}"
        )
    amp_a = np.asarray(amplitudes_a, dtype=np.float64)
    amp_b = np.asarray(amplitudes_b, dtype=np.float64)
    if amp_a.shape != lat_a.shape[:-1] or amp_b.shape != lat_b.shape[:-1]:
        raise ShapeError(
            f"amplitudes (…, n_genes) must match latencies (…, n_genes, 3); got {amp_a.shape} "
            f"with {lat_a.shape} and {amp_b.shape} with {lat_b.shape}"
        )
    w = amp_a * amp_b
    total = w.sum(axis=-1)
    squared = (w * ((lat_a - lat_b) ** 2).sum(axis=-1)).sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        out: np.ndarray = np.where(total > 0, np.sqrt(squared / (3 * total)), np.nan)
    return out
