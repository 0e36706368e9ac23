"""How close a replayed face's weights must be to the stored ones: floating-point rounding only.

Everything discrete in a replay (face ids, parents, operators, genes, label orders) is compared
exactly. The weights a face was shown with are computed from its genes — the rig's expansion and,
in a corrected study, the correctives' solve — with BLAS sums whose order depends on the CPU and
the BLAS kernel (the same study recorded on an Intel machine and replayed on an AMD EPYC with
OpenBLAS' Haswell kernels differs by up to 3.3e-16). So a weight counts as equal when

    |stored − replayed| ≤ WEIGHT_TOLERANCE × max(1, |stored|)

WEIGHT_TOLERANCE = 1e-12 for weights of order 1 (shape weights in [0, 1], correctives their
products): about 4500 ULPs of 1.0 and ten times the worst-case rounding of a 1000-term sum
taken in another order (~1000 × 1.1e-16), yet a million times smaller than a change of 1e-6, and far
below what a face shows (the browser morphs in 32-bit floats, ~6e-8 apart at 1.0). A wrong gene,
another correction or an edited weight moves weights by orders of magnitude more.
"""

from __future__ import annotations

import numpy as np

#: Largest deviation of a replayed weight from the stored one, relative to max(1, |stored|),
#: that is rounding (see the module's notes).
WEIGHT_TOLERANCE = 1e-12


def weight_deviation(stored: np.ndarray, replayed: np.ndarray) -> float:
    """Largest |stored − replayed| / max(1, |stored|) over all entries (inf where one is NaN or
    infinite and the other is not the same value)."""
    stored = np.asarray(stored, dtype=np.float64)
    replayed = np.asarray(replayed, dtype=np.float64)
    if stored.shape != replayed.shape:
        raise ValueError(f"weights of shape {stored.shape} and {replayed.shape} cannot be compared")
    with np.errstate(invalid="ignore", over="ignore"):
        scaled = np.abs(stored - replayed) / np.maximum(1.0, np.abs(stored))
    scaled = np.where(stored == replayed, 0.0, scaled)  # the same infinity
    scaled = np.where(np.isfinite(scaled), scaled, np.inf)  # NaN or inf on one side only
    return float(np.max(scaled, initial=0.0))


def within_rounding(deviation: float) -> bool:
    """Whether a :func:`weight_deviation` is floating-point rounding."""
    return deviation <= WEIGHT_TOLERANCE
