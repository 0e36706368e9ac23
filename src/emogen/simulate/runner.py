"""Many simulated runs of the GA with a cosine observer; one tidy row per run and generation."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from emogen.config import SimulationConfig
from emogen.ga.engine import Engine
from emogen.model.rig import Rig
from emogen.rng import fresh_seed, spawn_seeds
from emogen.simulate.observer import CosineObserver

RECORD_SCHEMA = "emogen.simulate/1"
COLUMNS = ("run", "generation", "elite_error", "n_selected", "run_seed")


@dataclass(frozen=True)
class SimulationResult:
    """table: one row per run and generation (columns ``COLUMNS``); record: how it was made."""

    table: pd.DataFrame
    record: dict[str, Any]


def simulate_run(
    config: SimulationConfig, rig: Rig, target: np.ndarray, seed: int
) -> tuple[np.ndarray, np.ndarray]:
    """One run: (elite CD error per generation (G+1,), faces selected per generation (G+1,))."""
    ga = config.ga
    engine = Engine(ga, rig, seed)
    observer = CosineObserver(
        target, config.selections_at, final=ga.generations, ranking=ga.variant == "classical"
    )
    errors = np.empty(ga.generations + 1)
    counts = np.empty(ga.generations + 1, dtype=np.int64)
    while not engine.done:
        population = engine.ask()
        elite, others, error = observer.choose(population)
        errors[population.generation] = error
        counts[population.generation] = 1 + len(others)
        engine.tell(elite, others)
    return errors, counts


def run_simulation(
    config: SimulationConfig, rig: Rig, *, model_name: str = "", model_hash: str = ""
) -> SimulationResult:
    """``config.runs`` independent runs; run r uses the r-th spawned child of the seed.

    A config without a seed gets a fresh one, recorded in the result's resolved config.
    """
    from emogen import __version__

    seed = config.seed if config.seed is not None else fresh_seed()
    config = config.model_copy(update={"seed": seed})
    target = rig.weights_from_names(config.target)
    seeds = spawn_seeds(seed, config.runs)
    n_gen = config.ga.generations + 1
    errors = np.empty((config.runs, n_gen))
    counts = np.empty((config.runs, n_gen), dtype=np.int64)
    for run, run_seed in enumerate(seeds):
        errors[run], counts[run] = simulate_run(config, rig, target, run_seed)
    table = pd.DataFrame(
        {
            "run": np.repeat(np.arange(config.runs), n_gen),
            "generation": np.tile(np.arange(n_gen), config.runs),
            "elite_error": errors.reshape(-1),
            "n_selected": counts.reshape(-1),
            "run_seed": np.repeat(np.array(seeds, dtype=np.int64), n_gen),
        }
    )
    record = {
        "schema": RECORD_SCHEMA,
        "emogen_version": __version__,
        "model": {"name": model_name, "hash": model_hash},
        "rig": {"name": rig.name, "genes": list(rig.gene_names(config.ga.eye_motion))},
        "config": config.model_dump(mode="json"),
        "seed": seed,
        "run_seeds": seeds,
        "target_weights": {
            s: float(w) for s, w in zip(rig.shape_names, target, strict=True) if w != 0
        },
        "metric": "cosine distance (eq. 12) on full weight vectors",
    }
    return SimulationResult(table, record)


def summary(table: pd.DataFrame) -> pd.DataFrame:
    """Mean and standard deviation of the elite error per generation."""
    return table.groupby("generation")["elite_error"].agg(["mean", "std"])


def write_simulation(result: SimulationResult, out: Path) -> list[Path]:
    """``simulation.parquet``, ``simulation.csv`` and ``simulation.json`` (the record) in ``out``."""
    import json

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "simulation.parquet", out / "simulation.csv", out / "simulation.json"]
    result.table.to_parquet(paths[0], index=False)
    result.table.to_csv(paths[1], index=False)
    paths[2].write_text(json.dumps(result.record, indent=2) + "\n")
    return paths
