"""The required n of a power curve: the fit checked against the simulated points (χ² from
scipy against a plain sum), interpolation where it misfits, a bootstrap interval that covers."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from emogen.analysis.power_required import fit_p, interpolated_n, required_n
from emogen.errors import ConfigError

N = np.array([4, 6, 9, 13, 19, 28, 40, 60, 90])
R = 400


def _logistic(a: float, b: float) -> np.ndarray:
    return 0.05 + 0.95 / (1 + np.exp(-(a + b * np.log(N))))


def test_interpolation_against_a_hand_computed_crossing() -> None:
    power = np.array([0.1, 0.3, 0.5, 0.7, 0.9])
    n = np.array([5, 10, 20, 40, 80])
    # halfway from 0.7 (n 40) to 0.9 (n 80) in log n: 40·√2 = 56.6 → 57
    assert interpolated_n(n, power, 0.8) == int(np.ceil(40 * np.sqrt(2))) == 57
    assert interpolated_n(n, power, 0.05) == 5
    assert interpolated_n(n, power, 0.95) is None


def test_fit_p_is_pearson_chi_square() -> None:
    power = np.array([0.2, 0.45, 0.8, 0.9])
    fitted = np.array([0.25, 0.4, 0.78, 0.93])
    chi2 = sum((p - f) ** 2 * R / (f * (1 - f)) for p, f in zip(power, fitted, strict=True))
    assert fit_p(N[:4], power, fitted, R) == pytest.approx(stats.chi2.sf(chi2, 2))
    assert np.isnan(fit_p(N[:2], power[:2], fitted[:2], R))


def test_a_logistic_curve_is_fitted_and_its_interval_covers() -> None:
    rng = np.random.default_rng(0)
    true = _logistic(-6.0, 2.0)
    power = rng.binomial(R, true) / R
    got = required_n(N, power, R, target=0.8, alpha=0.05, max_n=100, rng=rng)
    exact = np.exp((np.log(0.75 / 0.2) + 6.0) / 2.0)  # where the true curve reaches 0.8
    assert got.method == "fit" and got.fit_p > 0.01
    assert got.lo is not None and got.hi is not None
    assert got.lo <= exact <= got.hi and got.lo <= got.n <= got.hi


def test_a_misfitting_curve_is_interpolated() -> None:
    """A plateau then a jump: no logistic in log n fits it; the points are read instead."""
    rng = np.random.default_rng(1)
    power = np.array([0.05, 0.06, 0.05, 0.07, 0.06, 0.95, 0.96, 0.97, 0.98])
    got = required_n(N, power, R, target=0.8, alpha=0.05, max_n=100, rng=rng)
    assert got.method == "interpolation" and got.fit_p < 0.01
    assert got.n == interpolated_n(N, power, 0.8)


def test_unreached_power_has_no_n_and_bad_input_is_named() -> None:
    rng = np.random.default_rng(2)
    got = required_n(N, np.full(len(N), 0.3), R, target=0.8, alpha=0.05, max_n=100, rng=rng)
    assert got.n is None and "not reached" in got.text()
    with pytest.raises(ConfigError, match="equal 1-d arrays"):
        required_n(N, np.ones(3), R, target=0.8, alpha=0.05, max_n=100, rng=rng)
