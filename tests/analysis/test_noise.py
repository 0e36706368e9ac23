"""GA noise and the group-spread test, on synthetic 'GA's with known behaviour."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.analysis.noise import (
    PAPER_NOISE,
    GANoise,
    latent_spread_test,
    null_mean_proxy_errors,
    pooled_noise,
    proxy_errors,
    spread_test,
)
from emogen.errors import ConfigError

S = 12


def fake_ga(
    target: np.ndarray, runs: int, rng: np.random.Generator, noise: float = 0.05
) -> np.ndarray:
    """Final faces of a pretend GA: the target's direction, random intensity, a little fill-in."""
    t = np.asarray(target, dtype=np.float64)
    scale = rng.uniform(0.6, 1.0, (runs, 1))
    return np.clip(t * scale + np.abs(rng.normal(0, noise, (runs, len(t)))), 0, 1)


def test_proxy_errors_of_identical_faces_are_zero() -> None:
    faces = np.tile(np.random.default_rng(0).random(S), (5, 1))
    np.testing.assert_allclose(proxy_errors(faces), 0.0, atol=1e-12)


def test_noise_summaries() -> None:
    n = GANoise.from_errors(np.array([0.1, 0.3]), "x")
    assert (n.mean, n.n) == (0.2, 2) and n.label == "0.200 ± 0.141"
    pooled = pooled_noise([n, GANoise(0.4, 0.1, 3, "y")], "both")
    assert pooled.mean == pytest.approx(0.3) and pooled.n == 5
    with pytest.raises(ConfigError):
        pooled_noise([], "none")


def test_spread_within_noise_does_not_exceed_it() -> None:
    rng = np.random.default_rng(1)
    t = np.r_[np.ones(3), np.zeros(S - 3)]
    pool = fake_ga(t, 2000, rng)
    noise = GANoise.from_errors(proxy_errors(pool), "fake", pool)
    group = fake_ga(t, 40, rng)
    res = spread_test(group, noise, group="same target", rng=rng)
    assert not res.exceeds and res.p_value > 0.05


def test_spread_of_a_mixture_of_targets_exceeds_noise() -> None:
    rng = np.random.default_rng(2)
    t1 = np.r_[np.ones(3), np.zeros(S - 3)]
    t2 = np.r_[np.zeros(3), np.ones(3), np.zeros(S - 6)]
    pool = fake_ga(t1, 2000, rng)
    noise = GANoise.from_errors(proxy_errors(pool), "fake", pool)
    group = np.concatenate([fake_ga(t1, 20, rng), fake_ga(t2, 20, rng)])
    res = spread_test(group, noise, rng=rng)
    assert res.exceeds and res.p_value < 0.01


def test_null_distribution_matches_independent_groups() -> None:
    rng = np.random.default_rng(3)
    t = np.r_[np.ones(4), np.zeros(S - 4)]
    pool = fake_ga(t, 3000, rng)
    null = null_mean_proxy_errors(pool, 30, draws=400, rng=rng)
    direct = np.array([proxy_errors(fake_ga(t, 30, rng)).mean() for _ in range(400)])
    assert null.mean() == pytest.approx(direct.mean(), rel=0.03)
    assert null.std() == pytest.approx(direct.std(), rel=0.25)


def test_t_test_fallback_against_the_paper_threshold() -> None:
    rng = np.random.default_rng(4)
    tight = np.tile(np.r_[np.ones(2), np.zeros(S - 2)], (10, 1)) + rng.random((10, S)) * 0.01
    res = spread_test(tight, PAPER_NOISE, rng=rng)
    assert "t-test" in res.method and not res.exceeds
    wide = rng.random((30, S)) ** 4
    assert spread_test(wide, PAPER_NOISE, rng=rng).exceeds
    with pytest.raises(ConfigError, match="at least 2"):
        spread_test(tight[:1], PAPER_NOISE, rng=rng)


def test_latent_target_search_avoids_the_dense_mean_false_alarm() -> None:
    """A sparse target's GA mean is dense (fill-in); the test must not simulate toward it alone."""
    rng = np.random.default_rng(5)
    sim_rng = np.random.default_rng(6)

    def simulate(target: np.ndarray, runs: int) -> np.ndarray:
        # sparse targets are matched loosely, dense ones tightly: noise shrinks with support
        active = max(int((np.asarray(target) > 0).sum()), 1)
        return fake_ga(target, runs, sim_rng, noise=0.15 / np.sqrt(active))

    t = np.r_[1.0, np.zeros(S - 1)]
    group = simulate(t, 40)
    res, cands = latent_spread_test(group, simulate, group="sparse", rng=rng, pool_runs=400)
    assert not res.exceeds, [c.row() for c in cands]
    assert any(c.active == 1 for c in cands if c.consistent)
    # the dense mean alone would raise the alarm
    dense = next(c for c in cands if c.threshold == 0.0)
    assert dense.active == S
    mixture = np.concatenate([simulate(t, 20), simulate(np.r_[0.0, 1.0, np.zeros(S - 2)], 20)])
    res2, _ = latent_spread_test(mixture, simulate, group="two targets", rng=rng, pool_runs=400)
    assert res2.exceeds and "consistent" in res2.method


def test_excess_spread_interval_brackets_zero_only_within_noise() -> None:
    """p from n-subsets of the group and the pool together; the excess (observed − the mean
    over subsets of the pool) and its interval: the pool null's 2.5–97.5% spread about its
    mean, widened by √((1 + n/N)/(1 − n/N)), inverted around the observed value (the same
    nulls drawn again from the same seed, in the same order)."""
    t1 = np.r_[np.ones(3), np.zeros(S - 3)]
    t2 = np.r_[np.zeros(3), np.ones(3), np.zeros(S - 6)]
    pool = fake_ga(t1, 2000, np.random.default_rng(5))
    noise = GANoise.from_errors(proxy_errors(pool), "fake", pool)
    same = fake_ga(t1, 40, np.random.default_rng(6))
    mixed = np.concatenate([same[:20], fake_ga(t2, 20, np.random.default_rng(7))])
    for group, exceeds in ((same, False), (mixed, True)):
        res = spread_test(group, noise, draws=500, rng=np.random.default_rng(8))
        rng = np.random.default_rng(8)
        n = len(group)
        both = null_mean_proxy_errors(np.vstack([group, pool]), n, draws=500, rng=rng)
        null = null_mean_proxy_errors(pool, n, draws=500, rng=rng)
        observed = proxy_errors(group).mean()
        assert res.p_value == pytest.approx((1 + np.sum(both >= observed)) / 501)
        scale = np.sqrt((1 + n / 2000) / (1 - n / 2000))
        centre = null.mean()
        assert res.excess == pytest.approx(observed - centre)
        hi, lo = (
            observed - centre - scale * (np.quantile(null, q) - centre) for q in (0.025, 0.975)
        )
        assert res.excess_lo == pytest.approx(lo) and res.excess_hi == pytest.approx(hi)
        assert (res.excess_lo > 0) == exceeds and res.exceeds == exceeds
    assert "excess [95% CI]" in res.row() and res.record()["excess_ci_low"] == res.excess_lo


def test_excess_spread_of_the_t_fallback_is_the_t_interval() -> None:
    rng = np.random.default_rng(9)
    group = fake_ga(np.r_[np.ones(3), np.zeros(S - 3)], 30, rng)
    err = proxy_errors(group)
    res = spread_test(group, GANoise(0.02, 0.01, 500, "paper-like"), rng=rng)
    half = 2.045229642132703 * err.std(ddof=1) / np.sqrt(30)  # t(0.975, 29)
    assert res.excess == pytest.approx(err.mean() - 0.02)
    assert res.excess_lo == pytest.approx(err.mean() - half - 0.02)
    assert res.excess_hi == pytest.approx(err.mean() + half - 0.02)


def test_no_consistent_target_takes_the_least_favourable_of_all() -> None:
    """A simulator that always adds a gene the group lacks: no candidate reproduces the
    group's mean, and the test reports the largest p of all candidates (not the best fit)."""
    sim_rng = np.random.default_rng(9)
    extra = np.r_[np.zeros(S - 1), 0.3]

    def simulate(target: np.ndarray, runs: int) -> np.ndarray:
        active = max(int((np.asarray(target) > 0).sum()), 1)
        return fake_ga(np.asarray(target) + extra, runs, sim_rng, noise=0.03 / np.sqrt(active))

    group = fake_ga(np.r_[1.0, 0.5, np.zeros(S - 2)], 60, np.random.default_rng(10), noise=0.04)
    group[:, -1] = 0.0
    res, cands = latent_spread_test(group, simulate, rng=np.random.default_rng(11), pool_runs=300)
    assert not any(c.consistent for c in cands)
    assert "none consistent" in res.method
    assert res.p_value == max(c.test.p_value for c in cands)
    assert res.p_value > min(c.test.p_value for c in cands)  # the choice matters here
