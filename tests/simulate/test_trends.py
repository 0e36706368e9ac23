"""The paper's convergence trends (Section IV-C, Tables IV and V), reproduced on our model.

500 runs per condition, as in the paper (about 3 s each). Targets: target 1 is one shape
(jawOpen, like the paper's jaw-open target 1); the twelve-shape target mixes brows, eyes and
mouth like the paper's complex target 2.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy import stats

from emogen.analysis.paper_targets import TARGET_1, table_v_by_shapes
from emogen.analysis.paper_targets import TARGET_2 as TARGET_12
from emogen.config import GAConfig, InitConfig, SimulationConfig
from emogen.simulate.runner import run_simulation

RUNS = 500
SEED = 1


def errors(rig, target: dict[str, float], lo_hi: tuple[int, int]) -> np.ndarray:
    """(runs, 11) elite CD error per run and generation."""
    cfg = SimulationConfig(
        target=target,
        runs=RUNS,
        seed=SEED,
        ga=GAConfig(init=InitConfig(activation_range=lo_hi)),
    )
    t = run_simulation(cfg, rig).table
    return t.pivot(index="run", columns="generation", values="elite_error").to_numpy()


@pytest.mark.slow
def test_paper_trends(ict_model) -> None:
    rig = ict_model.rig
    one = errors(rig, TARGET_1, (3, 8))
    twelve = errors(rig, TARGET_12, (3, 8))
    # mean elite error falls from generation 0 to 10, for both targets
    for e in (one, twelve):
        assert e[:, 10].mean() < e[:, 0].mean() - 0.1
        assert stats.wilcoxon(e[:, 0], e[:, 10], alternative="greater").pvalue < 1e-6
    # a one-shape target ends with a higher error than a twelve-shape one (Table V)
    assert one[:, 10].mean() > twelve[:, 10].mean()
    assert stats.mannwhitneyu(one[:, 10], twelve[:, 10], alternative="greater").pvalue < 1e-6
    # fewer initial activations converge better for the one-shape target (Table IV)
    few = errors(rig, TARGET_1, (1, 3))
    many = errors(rig, TARGET_1, (8, 16))
    assert few[:, 10].mean() < many[:, 10].mean()
    assert stats.mannwhitneyu(few[:, 10], many[:, 10], alternative="less").pvalue < 1e-3
    # and start with the larger, more variable bias (σ0 falls with more activations)
    assert few[:, 0].mean() > many[:, 0].mean() and few[:, 0].std() > many[:, 0].std()


# Table V: targets of increasing complexity converge better (lower μ and σ of the final CD error).


@pytest.mark.slow
def test_table_v_ordering(ict_model) -> None:
    rig = ict_model.rig
    targets = table_v_by_shapes(rig)
    shapes = {k: int((rig.weights_from_names(t) > 0).sum()) for k, t in targets.items()}
    assert shapes == {"1-shape": 1, "3-shape": 3, "12-shape": 12, "dense": 52}
    final = {}
    for name, target in targets.items():
        cfg = SimulationConfig(target=target, runs=RUNS, seed=SEED)
        t = run_simulation(cfg, rig).table
        final[name] = t.loc[t["generation"] == 10, "elite_error"].to_numpy()
    names = list(targets)
    for a, b in itertools.pairwise(names):
        assert final[a].mean() > final[b].mean(), (a, b)
        assert final[a].std() > final[b].std(), (a, b)
        assert stats.mannwhitneyu(final[a], final[b], alternative="greater").pvalue < 1e-6
