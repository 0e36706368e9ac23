"""Same seed, same numbers on every backend: in-process, a process pool, Dask."""

from __future__ import annotations

import pandas as pd
import pytest

from emogen.config import SimulationConfig
from emogen.errors import ConfigError
from emogen.simulate.backends import DaskBackend, LocalBackend, make_backend
from emogen.simulate.runner import run_simulation

CFG = SimulationConfig(
    target={"jawOpen": 1.0, "mouthSmile": 0.3}, runs=24, seed=11, noise_temperature=0.02
)


@pytest.fixture(scope="module")
def local(ict_model):
    return run_simulation(CFG, ict_model.rig, all_weights=True)


def assert_same(a, b) -> None:
    pd.testing.assert_frame_equal(a.table, b.table)
    pd.testing.assert_frame_equal(a.faces, b.faces)
    assert a.record["run_seeds"] == b.record["run_seeds"]


def test_dask_local_cluster_gives_the_local_numbers(ict_model, local) -> None:
    with DaskBackend(n_workers=2, processes=False, chunk_runs=5) as backend:
        result = run_simulation(CFG, ict_model.rig, backend=backend, all_weights=True)
    assert_same(local, result)
    assert result.record["backend"] == "dask LocalCluster"


def test_process_pool_gives_the_local_numbers(ict_model, local) -> None:
    backend = LocalBackend(workers=2)
    assert backend.chunk_size(24) == 6
    assert_same(local, run_simulation(CFG, ict_model.rig, backend=backend, all_weights=True))


def test_make_backend() -> None:
    assert isinstance(make_backend(None, 1), LocalBackend)
    with pytest.raises(ConfigError, match="--dask must be 'local' or a scheduler address"):
        make_backend("somewhere")
    with pytest.raises(ConfigError, match="workers must be >= 1"):
        LocalBackend(0)


CORRECTED = SimulationConfig(
    target={"jawOpen": 1.0, "mouthShrugLower": 0.8},
    runs=110,
    seed=5,
    correct=True,
    ga={"generations": 3},
)


def test_corrected_simulation_is_the_same_in_a_process_pool_and_on_dask(ict_model) -> None:
    """Every shown face corrected (collisions included): one process, two worker processes and
    a Dask LocalCluster give the same tables, corrective weights and all."""
    local = run_simulation(CORRECTED, ict_model, all_weights=True)
    shown = local.faces
    assert local.record["corrected"]
    collision = [c for c in shown.columns if c.startswith("w_collision_")]
    assert len(collision) == 8 and (shown[collision].to_numpy() > 0).any(axis=1).mean() > 0.05
    pooled = run_simulation(CORRECTED, ict_model, backend=LocalBackend(2), all_weights=True)
    assert_same(local, pooled)
    with DaskBackend(n_workers=2, processes=False, chunk_runs=40) as backend:
        assert_same(local, run_simulation(CORRECTED, ict_model, backend=backend, all_weights=True))
