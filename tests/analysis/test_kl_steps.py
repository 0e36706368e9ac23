"""Figs. 15/17's pooled KL rule: each verdict reached on constructed error curves."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.analysis.replication.kl_steps import KLRises, rises_above


def _errors(jump: bool, n: int = 400, seed: int = 0) -> np.ndarray:
    """Errors (n × 11) whose mean falls geometrically (shrinking steps: the KL between
    generations falls); ``jump``: the distribution moves back up at generation 8."""
    rng = np.random.default_rng(seed)
    mu = 0.3 + 0.5 * 0.6 ** np.arange(11)
    if jump:
        mu[8:] += 0.25
    return mu + rng.normal(0, 0.05, (n, 11))


def test_rises_above_counts_steps_past_the_floor() -> None:
    kl = np.array([0.9, 0.5, 0.6, 0.3, 0.2, 0.25, 0.1, 0.4, 0.3, 0.35])
    steps = np.diff(kl)
    assert rises_above(kl, 0.0, "all") == int(np.sum(steps > 0)) == 4
    assert rises_above(kl, 0.1, "all") == 1
    assert rises_above(kl, 0.0, "late") == int(np.sum(np.diff(kl[4:]) > 0)) == 3
    with pytest.raises(ValueError, match="window must be one of"):
        rises_above(kl, 0.0, "early")


@pytest.mark.parametrize(
    ("expect", "window", "jump", "verdict"),
    [
        (True, "late", True, "holds"),
        (True, "late", False, "differs"),
        (False, "all", False, "holds"),
        (False, "all", True, "differs"),
    ],
)
def test_kl_rises_reach_each_verdict(expect: bool, window: str, jump: bool, verdict: str) -> None:
    decision = KLRises(expect, window, resamples=40)(_errors(jump))
    assert decision.verdict == verdict
    assert decision.lo <= decision.estimate <= decision.hi or decision.estimate == 0


def test_kl_rises_refuse_bad_input() -> None:
    with pytest.raises(ValueError, match="window must be one of"):
        KLRises(True, "middle")
    with pytest.raises(ValueError, match="runs × ≥ 4 generations"):
        KLRises(True)(np.zeros((5, 2)))
