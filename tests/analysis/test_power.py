"""Power analysis by simulation: known answers on synthetic pools, and pools from the GA."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.analysis.power import final_faces_pool, participants_grid, power_analysis, power_at
from emogen.config import GAConfig, SimulationConfig
from emogen.errors import ConfigError


def pool(centre: np.ndarray, n: int, sd: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.clip(centre + rng.normal(0, sd, (n, len(centre))), 0, 1)


def test_identical_groups_reject_at_about_alpha() -> None:
    c = np.r_[np.full(3, 0.6), np.zeros(7)]
    a = pool(c, 400, 0.2, 0)
    p = power_at(a, a, 10, replicates=300, permutations=99, rng=np.random.default_rng(1))
    assert p < 0.1


def test_clearly_different_groups_need_few_participants() -> None:
    a = pool(np.r_[np.full(3, 0.6), np.zeros(7)], 300, 0.05, 0)
    b = pool(np.r_[np.zeros(3), np.full(3, 0.6), np.zeros(4)], 300, 0.05, 1)
    res = power_analysis(a, b, max_n=20, replicates=50, permutations=50, seed=2)
    # a permutation test of 2 × 3 participants has 20 labellings: p >= 2/20 > 0.05, so n = 4
    assert res.n_required == 4
    assert res.curve.set_index("n")["power"].loc[3] == 0.0
    assert res.curve["power"].iloc[-1] >= 0.8 and res.effect_cd > 0.5


def test_a_subtle_difference_needs_more_and_the_curve_rises() -> None:
    c = np.r_[np.full(3, 0.6), np.zeros(7)]
    a = pool(c, 400, 0.15, 0)
    b = pool(c + np.r_[np.zeros(3), 0.12, np.zeros(6)], 400, 0.15, 1)
    res = power_analysis(a, b, max_n=60, replicates=80, permutations=80, seed=3)
    assert res.n_required is not None and res.n_required > 4
    assert res.curve["power"].iloc[-1] > res.curve["power"].iloc[0]
    # the fitted curve rises, crosses the wanted power near the simulated crossing
    fitted = res.curve["fitted"].to_numpy()
    assert np.all(np.diff(fitted) > 0) and res.fit is not None
    assert (
        res.n_observed is not None and abs(res.n_required - res.n_observed) <= 0.5 * res.n_observed
    )


def test_grid_and_checks() -> None:
    g = participants_grid(100)
    assert g[0] == 2 and g[-1] == 100 and g == sorted(set(g))
    with pytest.raises(ConfigError):
        participants_grid(1)
    a = np.ones((5, 3))
    with pytest.raises(ConfigError, match="power and alpha"):
        power_analysis(a, a, target_power=1.5)
    with pytest.raises(ConfigError, match="statistic"):
        power_analysis(a, a, statistic="md")


def test_pools_from_the_ga(ict_model) -> None:  # type: ignore[no-untyped-def]
    rig = ict_model.rig
    cfg = SimulationConfig(ga=GAConfig(generations=2), target={"jawOpen": 1.0})
    w = rig.weights_from_names({"mouthSmile": 0.8, "cheekSquint": 0.5})
    p = final_faces_pool(cfg, rig, w, pool=12, seed=1)
    assert p.shape == (12, len(rig.shape_names)) and np.all(p >= 0)
    q = final_faces_pool(cfg, rig, w, pool=6, seed=1, participant_sd=0.1)
    assert q.shape == (6, len(rig.shape_names))
    with pytest.raises(ConfigError, match="non-zero"):
        final_faces_pool(cfg, rig, np.zeros(len(rig.shape_names)), pool=2, seed=1)
