"""Error distributions per generation and the KL divergence between consecutive generations.

**Density estimate (for the KL divergence).** Each sample of errors is smoothed by a Gaussian
kernel density estimate with Scott's bandwidth, h = σ̂ · n^(−1/5) (σ̂ the sample standard
deviation, ddof = 1; the rule scipy's ``gaussian_kde`` uses in one dimension), floored at
``min_bandwidth`` (0.005 CD units by default) so that a sample of identical values — the
generation-0 error of a fixed initialisation, say — is a narrow bump rather than a spike. Both
densities are evaluated on one common grid of ``grid_points`` (512) points spanning the pooled
samples ± 4 of the larger bandwidth, floored at 1e-12 of their peak (so that q > 0 wherever
p > 0) and renormalised to integrate to 1 on the grid (trapezoid rule). Then

    KL(P ‖ Q) = ∫ p(x) log(p(x) / q(x)) dx      (natural log: nats)

also by the trapezoid rule. Identical samples give identical densities and KL = 0 exactly.
The consecutive-generation divergence of Figs. 15 and 17 is KL(P_g ‖ P_{g−1}), g = 1…G: how
much the error distribution changed in generation g. No boundary correction is made at CD = 0:
both densities leak alike, which matters little for a divergence between them.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from emogen.errors import ShapeError

MIN_BANDWIDTH = 0.005
GRID_POINTS = 512
DENSITY_FLOOR = 1e-12


def scott_bandwidth(x: np.ndarray, min_bandwidth: float = MIN_BANDWIDTH) -> float:
    """Scott's rule h = σ̂ n^(−1/5) for a 1-D sample, at least ``min_bandwidth``."""
    x = np.asarray(x, dtype=np.float64)
    sd = float(np.std(x, ddof=1)) if len(x) > 1 else 0.0
    return max(sd * len(x) ** (-0.2), min_bandwidth)


def kde(x: np.ndarray, grid: np.ndarray, bandwidth: float) -> np.ndarray:
    """Gaussian KDE of the 1-D sample ``x`` evaluated at ``grid`` (unnormalised on the grid)."""
    x = np.asarray(x, dtype=np.float64)
    out = np.zeros(len(grid))
    for lo in range(0, len(x), 2048):  # bounded memory: (2048, grid) at a time
        z = (grid[None, :] - x[lo : lo + 2048, None]) / bandwidth
        out += np.exp(-0.5 * z * z).sum(0)
    return out / (len(x) * bandwidth * np.sqrt(2 * np.pi))


def _clean(x: np.ndarray, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=np.float64).ravel()
    a = a[np.isfinite(a)]
    if len(a) == 0:
        raise ShapeError(f"kl_divergence: sample {name} has no finite values")
    return a


def kl_divergence(
    p_sample: np.ndarray,
    q_sample: np.ndarray,
    *,
    min_bandwidth: float = MIN_BANDWIDTH,
    grid_points: int = GRID_POINTS,
) -> float:
    """KL(P ‖ Q) in nats between the densities of two 1-D samples (see the module docstring)."""
    p_x, q_x = _clean(p_sample, "p"), _clean(q_sample, "q")
    hp = scott_bandwidth(p_x, min_bandwidth)
    hq = scott_bandwidth(q_x, min_bandwidth)
    pad = 4 * max(hp, hq)
    lo = min(p_x.min(), q_x.min()) - pad
    hi = max(p_x.max(), q_x.max()) + pad
    grid = np.linspace(lo, hi, grid_points)
    p = kde(p_x, grid, hp)
    q = kde(q_x, grid, hq)
    p = np.maximum(p, DENSITY_FLOOR * p.max())
    q = np.maximum(q, DENSITY_FLOOR * q.max())
    p /= np.trapezoid(p, grid)
    q /= np.trapezoid(q, grid)
    return max(float(np.trapezoid(p * np.log(p / q), grid)), 0.0)


def kl_per_generation(errors: np.ndarray, *, min_bandwidth: float = MIN_BANDWIDTH) -> np.ndarray:
    """KL(P_g ‖ P_{g−1}) for g = 1…G from errors (n_samples, G + 1) → (G,) nats.

    NaN entries (a sample that stopped early) are left out of their generation.
    """
    e = np.asarray(errors, dtype=np.float64)
    if e.ndim != 2 or e.shape[1] < 2:
        raise ShapeError(f"errors must have shape (n_samples, G + 1) with G >= 1; got {e.shape}")
    return np.array(
        [
            kl_divergence(e[:, g], e[:, g - 1], min_bandwidth=min_bandwidth)
            for g in range(1, e.shape[1])
        ]
    )


def error_matrix(table: pd.DataFrame, value: str = "error") -> np.ndarray:
    """(n_samples, G + 1) errors from a long table with ``sample``, ``generation`` and ``value``."""
    wide = table.pivot_table(index="sample", columns="generation", values=value, aggfunc="first")
    return wide.sort_index(axis=1).to_numpy(dtype=np.float64)


def generation_summary(errors: np.ndarray) -> pd.DataFrame:
    """Per generation: n, mean, sd, median, quartiles of errors (n_samples, G + 1)."""
    e = np.asarray(errors, dtype=np.float64)
    rows = []
    for g in range(e.shape[1]):
        x = e[:, g][np.isfinite(e[:, g])]
        rows.append(
            {
                "generation": g,
                "n": len(x),
                "mean": float(x.mean()) if len(x) else np.nan,
                "sd": float(x.std(ddof=1)) if len(x) > 1 else np.nan,
                "median": float(np.median(x)) if len(x) else np.nan,
                "q25": float(np.quantile(x, 0.25)) if len(x) else np.nan,
                "q75": float(np.quantile(x, 0.75)) if len(x) else np.nan,
            }
        )
    return pd.DataFrame(rows)


def kl_noise_floor(
    sample: np.ndarray,
    n: int,
    *,
    rng: np.random.Generator,
    resamples: int = 200,
    quantile: float = 0.95,
    min_bandwidth: float = MIN_BANDWIDTH,
) -> float:
    """The KL divergence two samples of size ``n`` from ONE distribution reach by chance: the
    ``quantile`` of KL(P̂₁ ‖ P̂₂) over ``resamples`` pairs drawn with replacement from
    ``sample`` (1-D). A KL between generations below it is indistinguishable from no change."""
    x = _clean(np.asarray(sample, dtype=np.float64), "sample")
    kl = [
        kl_divergence(
            x[rng.integers(len(x), size=n)],
            x[rng.integers(len(x), size=n)],
            min_bandwidth=min_bandwidth,
        )
        for _ in range(resamples)
    ]
    return float(np.quantile(kl, quantile))
