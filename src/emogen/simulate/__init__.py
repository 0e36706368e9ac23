"""Simulated studies: an observer selects by a metric, many runs, tidy tables."""

from emogen.simulate.observer import CosineObserver, rank_by_cosine
from emogen.simulate.runner import SimulationResult, run_simulation, simulate_run, write_simulation

__all__ = [
    "CosineObserver",
    "SimulationResult",
    "rank_by_cosine",
    "run_simulation",
    "simulate_run",
    "write_simulation",
]
