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
