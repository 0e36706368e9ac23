"""The required n of a simulated power curve, with the fit checked and a 95% interval.

The logistic fit (:func:`fit_power_curve`, used by :mod:`emogen.analysis.power`) smooths the
Monte Carlo noise of single points, but only where its shape fits them. It is checked against the
simulated points by Pearson's χ² (each point Binomial(replicates, fitted power), df = points −
2, over the n whose test can reach α); where it misfits (p < ``MISFIT_P``) the required n is
read off the simulated points themselves instead — linear interpolation in log n between the
last point below the wanted power and the first at or above it.

The interval is a parametric bootstrap: every simulated power redrawn as Binomial(replicates,
power) / replicates, the required n recomputed the same way (fit, or interpolation), the 2.5th
and 97.5th percentiles taken; an upper end beyond the largest simulated n is None.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from emogen.errors import ConfigError

MISFIT_P = 0.01
METHODS = ("fit", "interpolation")


@dataclass(frozen=True)
class Required:
    """The required n per group (None: not reached), its bootstrap 95% interval, how it was
    read (``fit`` or ``interpolation``) and the fit's goodness-of-fit p (NaN: no check)."""

    n: int | None
    lo: int | None
    hi: int | None
    method: str
    fit_p: float

    def text(self) -> str:
        if self.n is None:
            return "not reached within the simulated n"
        hi = "beyond the simulated n" if self.hi is None else str(self.hi)
        return f"{self.n} (95% CI {self.lo}–{hi}; {self.method})"


def fit_p(n: np.ndarray, power: np.ndarray, fitted: np.ndarray, replicates: int) -> float:
    """Pearson χ² goodness-of-fit p of the fitted powers to the simulated ones (NaN with fewer
    than three points)."""
    p = np.clip(fitted, 1e-9, 1 - 1e-9)
    if len(n) < 3:
        return float("nan")
    chi2 = float(np.sum((power - p) ** 2 * replicates / (p * (1 - p))))
    return float(stats.chi2.sf(chi2, len(n) - 2))


def interpolated_n(n: np.ndarray, power: np.ndarray, target: float) -> int | None:
    """Smallest n where the simulated curve reaches ``target``: interpolated linearly in log n
    between the last point below it and the first at or above it (None: never reached)."""
    above = np.flatnonzero(power >= target)
    if len(above) == 0:
        return None
    i = int(above[0])
    if i == 0:
        return int(n[0])
    x0, x1, y0, y1 = np.log(n[i - 1]), np.log(n[i]), power[i - 1], power[i]
    x = x0 + (target - y0) * (x1 - x0) / (y1 - y0)
    return int(np.ceil(np.exp(x) - 1e-9))


def required_n(
    n: np.ndarray,
    power: np.ndarray,
    replicates: int,
    *,
    target: float,
    alpha: float,
    max_n: int,
    rng: np.random.Generator,
    resamples: int = 200,
) -> Required:
    """The required n with its check and interval (module doc)."""
    n, power = np.asarray(n), np.asarray(power, dtype=np.float64)
    if n.shape != power.shape or n.ndim != 1 or len(n) == 0:
        raise ConfigError(f"n and power must be equal 1-d arrays; got {n.shape}, {power.shape}")
    floor = _smallest_testable(alpha)

    def by_fit(pw: np.ndarray) -> int | None:
        fit = fit_power_curve(n, pw, replicates, alpha)
        if fit is None:
            return None
        a, b = fit
        x = (np.log((target - alpha) / (1 - target)) - a) / b
        if not x <= np.log(max_n):  # beyond the simulated range (or no number at all)
            return None
        return max(int(np.ceil(np.exp(x))), floor)

    def by_points(pw: np.ndarray) -> int | None:
        value = interpolated_n(n, pw, target)
        return None if value is None else max(value, floor)

    fit = fit_power_curve(n, power, replicates, alpha)
    keep = n >= floor
    p = float("nan")
    if fit is not None:
        p = fit_p(n[keep], power[keep], fitted_power(n[keep], fit, alpha), replicates)
    method = "interpolation" if fit is None or p < MISFIT_P else "fit"
    find = by_fit if method == "fit" else by_points
    boot = [find(rng.binomial(replicates, power) / replicates) for _ in range(resamples)]
    values = np.array([np.inf if v is None else v for v in boot], dtype=np.float64)
    lo = np.quantile(values, 0.025, method="lower")  # discrete: no arithmetic on inf
    hi = np.quantile(values, 0.975, method="higher")
    return Required(
        find(power),
        None if not np.isfinite(lo) else int(lo),
        None if not np.isfinite(hi) else int(np.ceil(hi)),
        method,
        p,
    )


def _smallest_testable(alpha: float) -> int:
    """Smallest n per group whose permutation test can reach p <= alpha: 2 / C(2n, n) <= alpha."""
    from math import comb

    n = 2
    while 2 / comb(2 * n, n) > alpha:
        n += 1
    return n


def fitted_power(n: np.ndarray, fit: tuple[float, float] | None, alpha: float) -> np.ndarray:
    """α + (1 − α) · sigmoid(a + b log n), the fitted power curve (NaN without a fit)."""
    if fit is None:
        return np.full(len(n), np.nan)
    a, b = fit
    return np.asarray(alpha + (1 - alpha) / (1 + np.exp(-(a + b * np.log(n)))))


def fit_power_curve(
    n: np.ndarray, power: np.ndarray, replicates: int, alpha: float
) -> tuple[float, float] | None:
    """Binomial maximum-likelihood fit of power(n) = α + (1 − α) sigmoid(a + b log n) to the
    simulated powers (each from ``replicates`` experiments), over the n whose permutation test
    can reach α. None when fewer than two such n, or when the fit does not rise with n."""
    from scipy.optimize import minimize

    keep = n >= _smallest_testable(alpha)
    x, k = np.log(n[keep]), np.round(power[keep] * replicates)
    if len(x) < 2:
        return None

    def nll(theta: np.ndarray) -> float:
        p = alpha + (1 - alpha) / (1 + np.exp(-(theta[0] + theta[1] * x)))
        p = np.clip(p, 1e-9, 1 - 1e-9)
        return float(-(k * np.log(p) + (replicates - k) * np.log(1 - p)).sum())

    res = minimize(
        nll,
        np.array([-3.0, 1.0]),
        method="Nelder-Mead",
        options={"xatol": 1e-6, "fatol": 1e-9, "maxiter": 4000},
    )
    a, b = (float(v) for v in res.x)
    return (a, b) if b > 0 else None
