"""simulate_elites: the one reduction of GA runs to their elites, against the tidy faces table
that ``run_simulation`` writes (an independent path through the simulator's records)."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.analysis.elites import final_faces_simulator, simulate_elites, simulate_participants
from emogen.config import GAConfig, SimulationConfig
from emogen.rng import spawn_seeds
from emogen.simulate import build_problem, run_simulation


@pytest.fixture
def config() -> SimulationConfig:
    return SimulationConfig(
        ga=GAConfig(generations=3), target={"jawOpen": 1.0, "mouthSmile": 0.5}, runs=6, seed=4
    )


def test_elites_match_the_faces_table(ict_model, config: SimulationConfig) -> None:  # type: ignore[no-untyped-def]
    rig = ict_model.rig
    table = run_simulation(config, rig, all_weights=True).faces
    assert table is not None
    problem = build_problem(config, rig, all_weights=True)
    seeds = np.array(spawn_seeds(4, 6), dtype=np.int64)
    e = simulate_elites(problem, np.arange(6), seeds)
    assert e.errors.shape == (6, 4) and e.weights.shape == (6, 4, len(rig.shape_names))
    for run in range(6):
        for g in range(4):
            row = table[(table["run"] == run) & (table["generation"] == g) & (table["rank"] == 0)]
            assert len(row) == 1
            np.testing.assert_array_equal(
                e.weights[run, g], row[[f"w_{s}" for s in rig.shape_names]].iloc[0]
            )
            assert e.errors[run, g] == pytest.approx(float(row["error"].iloc[0]))
        first = table[(table["run"] == run) & (table["generation"] == 0)]
        assert e.best_initial[run] == pytest.approx(float(first["error"].min()))
    np.testing.assert_array_equal(e.final, e.weights[:, -1])


def test_participants_are_batches_of_one(ict_model, config: SimulationConfig) -> None:  # type: ignore[no-untyped-def]
    rig = ict_model.rig
    problem = build_problem(config, rig, all_weights=True)
    targets = np.stack(
        [rig.weights_from_names({"jawOpen": 0.8}), rig.weights_from_names({"mouthSmile": 1.0})]
    )
    seeds = spawn_seeds(9, 2)
    each = simulate_participants(problem, targets, seeds)
    for i in range(2):
        alone = simulate_elites(problem, np.array([i]), np.array([seeds[i]]), target=targets[i])
        np.testing.assert_array_equal(each[i].weights, alone.weights)
    # a different target changes the faces: the target is really replaced
    assert not np.array_equal(each[0].final, each[1].final)


def test_final_faces_simulator_reuses_its_seeds(ict_model, config: SimulationConfig) -> None:  # type: ignore[no-untyped-def]
    rig = ict_model.rig
    simulate = final_faces_simulator(config, rig, seed=5)
    target = rig.weights_from_names({"jawOpen": 1.0})
    three, five = simulate(target, 3), simulate(target, 5)
    np.testing.assert_array_equal(three, five[:3])
