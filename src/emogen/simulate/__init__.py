"""Simulated studies: observers select by a metric, many runs vectorised, tidy tables, sweeps."""

from emogen.simulate.backends import DaskBackend, LocalBackend, make_backend
from emogen.simulate.observer import CosineObserver, Metric, Observer, make_metric, rank_by_cosine
from emogen.simulate.problem import Problem, RunArrays
from emogen.simulate.runner import (
    SimulationResult,
    build_problem,
    run_simulation,
    simulate_run,
    write_simulation,
)
from emogen.simulate.vectorised import engine_run, simulate_runs

__all__ = [
    "CosineObserver",
    "DaskBackend",
    "LocalBackend",
    "Metric",
    "Observer",
    "Problem",
    "RunArrays",
    "SimulationResult",
    "build_problem",
    "engine_run",
    "make_backend",
    "make_metric",
    "rank_by_cosine",
    "run_simulation",
    "simulate_run",
    "simulate_runs",
    "write_simulation",
]
