"""KL divergence between error distributions (KDE, Scott's bandwidth) on known answers."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from emogen.analysis.distributions import (
    MIN_BANDWIDTH,
    error_matrix,
    generation_summary,
    kde,
    kl_divergence,
    kl_per_generation,
    scott_bandwidth,
)
from emogen.errors import ShapeError


def test_kl_of_identical_samples_is_zero() -> None:
    x = np.random.default_rng(0).beta(2, 5, size=500)
    assert kl_divergence(x, x) == 0.0
    assert kl_divergence(x, x.copy()[::-1]) == pytest.approx(0.0, abs=1e-12)


def test_kl_of_constant_samples_is_zero_and_finite() -> None:
    a = np.full(50, 1.0)  # e.g. generation 0 of a fixed initialisation
    assert kl_divergence(a, a) == 0.0
    d = kl_divergence(np.random.default_rng(1).uniform(0.3, 0.6, 200), a)
    assert np.isfinite(d) and d > 1.0


def test_kl_of_two_gaussians_matches_the_closed_form() -> None:
    rng = np.random.default_rng(2)
    p, q = rng.normal(0, 1, 20000), rng.normal(1, 1, 20000)
    # KL(N(0,1) || N(1,1)) = 0.5; the KDE widens both by h² (h ≈ 0.14), shrinking it by ~2%
    assert kl_divergence(p, q) == pytest.approx(0.5, abs=0.04)
    assert kl_divergence(p, q) > 0 and kl_divergence(q, p) > 0


def test_kl_is_asymmetric_and_non_negative() -> None:
    rng = np.random.default_rng(3)
    narrow, wide = rng.normal(0, 0.5, 4000), rng.normal(0, 2, 4000)
    # closed forms: KL(N(0,.5²)||N(0,2²)) ≈ 0.918, the reverse ≈ 4.886
    assert kl_divergence(narrow, wide) == pytest.approx(0.918, rel=0.1)
    assert kl_divergence(wide, narrow) > 3 * kl_divergence(narrow, wide)


def test_scott_bandwidth_is_scipys_one_dimensional_rule() -> None:
    x = np.random.default_rng(4).normal(size=300)
    ref = stats.gaussian_kde(x, bw_method="scott")
    assert scott_bandwidth(x) == pytest.approx(float(np.sqrt(ref.covariance[0, 0])))
    assert scott_bandwidth(np.ones(10)) == MIN_BANDWIDTH


def test_kde_integrates_to_one_and_matches_scipy() -> None:
    x = np.random.default_rng(5).gamma(2.0, 0.1, size=400)
    h = scott_bandwidth(x)
    grid = np.linspace(-1, 2, 3001)
    dens = kde(x, grid, h)
    assert np.trapezoid(dens, grid) == pytest.approx(1.0, abs=1e-6)
    np.testing.assert_allclose(dens, stats.gaussian_kde(x, bw_method="scott")(grid), atol=1e-9)


def test_kl_per_generation_and_summary() -> None:
    rng = np.random.default_rng(6)
    errors = np.stack([rng.normal(1.0 - 0.1 * g, 0.1, 300) for g in range(5)], axis=1)
    kl = kl_per_generation(errors)
    assert kl.shape == (4,) and np.all(kl > 0)
    same = np.repeat(rng.normal(size=(300, 1)), 4, axis=1)
    np.testing.assert_array_equal(kl_per_generation(same), np.zeros(3))
    s = generation_summary(errors)
    assert list(s["generation"]) == [0, 1, 2, 3, 4]
    assert s["mean"].is_monotonic_decreasing
    with pytest.raises(ShapeError, match="G \\+ 1"):
        kl_per_generation(errors[:, :1])


def test_error_matrix_from_a_long_table() -> None:
    import pandas as pd

    t = pd.DataFrame(
        {"sample": [1, 1, 2, 2], "generation": [0, 1, 0, 1], "error": [0.9, 0.5, 0.8, 0.4]}
    )
    np.testing.assert_array_equal(error_matrix(t), [[0.9, 0.5], [0.8, 0.4]])
