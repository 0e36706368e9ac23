"""The exact (Clopper–Pearson) 95% interval of a count of k in n: what a calibration benchmark
prints beside a rate, so that a cell of fewer studies than a claim needs says what it allows
(e.g. 10 of 100 false positives: [0.049, 0.176], which does not exclude 5%)."""

from __future__ import annotations

from scipy.stats import binomtest


def clopper_pearson(k: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """Exact binomial interval of k successes in n trials (scipy's ``method="exact"``)."""
    ci = binomtest(int(k), int(n)).proportion_ci(level, method="exact")
    return float(ci.low), float(ci.high)


def share(k: int, n: int) -> str:
    """``k of n = rate (Clopper–Pearson 95% [lo, hi])``."""
    lo, hi = clopper_pearson(k, n)
    return f"{k} of {n} = {k / n:.3f} (Clopper–Pearson 95% [{lo:.3f}, {hi:.3f}])"
