"""Simulating the elites: GA runs reduced to each generation's elite, the one way every
analysis (``emogen analyse``'s GA noise, ``emogen power``'s pools, ``emogen replicate``'s
conditions and simulated participants) turns a simulation into faces.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from emogen.errors import EmoGenError

if TYPE_CHECKING:
    from emogen.config import SimulationConfig
    from emogen.model.rig import Rig
    from emogen.simulate import Problem


@dataclass(frozen=True, eq=False)
class Elites:
    """The elites of R runs: errors (R, G+1) their CD to the target, weights (R, G+1, S) their
    full weights, best_initial (R,) the smallest generation-0 error (the initial bias),
    fixed_options (R,) the fixed set used (−1: protocol initialisation)."""

    errors: np.ndarray
    weights: np.ndarray
    best_initial: np.ndarray
    fixed_options: np.ndarray

    @property
    def final(self) -> np.ndarray:
        """(R, S) the last generation's elites."""
        return np.asarray(self.weights[:, -1])


def simulate_elites(
    problem: Problem,
    runs: np.ndarray,
    seeds: np.ndarray,
    *,
    target: np.ndarray | None = None,
) -> Elites:
    """Simulate runs (their numbers and seeds, (R,) each) of ``problem`` — toward ``target``
    (full weights) instead of the problem's own when given — keeping every generation's elite.
    ``problem`` must record all weights (``build_problem(..., all_weights=True)``)."""
    from emogen.simulate import simulate_runs

    if target is not None:
        problem = dataclasses.replace(problem, target=target)
    a = simulate_runs(problem, np.asarray(runs), np.asarray(seeds))
    if a.weights is None:
        raise EmoGenError("the simulation returned no weights (build it with all_weights=True)")
    elite = np.argmax(a.rank == 0, axis=2)  # (R, G+1)
    r = np.arange(a.error.shape[0])[:, None]
    g = np.arange(a.error.shape[1])[None, :]
    return Elites(
        errors=a.error[r, g, elite],
        weights=a.weights[r, g, elite],
        best_initial=a.error[:, 0, :].min(axis=1),
        fixed_options=a.fixed_options,
    )


def simulate_participants(
    problem: Problem, targets: np.ndarray, seeds: list[int] | np.ndarray
) -> list[Elites]:
    """One run per simulated participant i toward their own target ``targets[i]`` (full
    weights), run number i with seed ``seeds[i]``: a batch of one each, as a participant is."""
    return [
        simulate_elites(problem, np.array([i]), np.array([s]), target=t)
        for i, (t, s) in enumerate(zip(targets, seeds, strict=True))
    ]


def final_faces_simulator(
    config: SimulationConfig, rig: Rig, seed: int
) -> Callable[[np.ndarray, int], np.ndarray]:
    """``simulate(target (S,), runs) -> (runs, S)``: final elites of runs toward a target (full
    weights in the rig's shape order), with ``config``'s GA settings and a CD observer. Run r
    always uses the r-th seed spawned from ``seed``."""
    from emogen.rng import spawn_seeds
    from emogen.simulate import build_problem

    problem = build_problem(
        config.model_copy(update={"runs": 1, "seed": seed}), rig, all_weights=True
    )
    seeds: list[int] = []

    def simulate(target: np.ndarray, runs: int) -> np.ndarray:
        if len(seeds) < runs:
            seeds[:] = spawn_seeds(seed, runs)
        t = np.asarray(target, dtype=np.float64)
        return simulate_elites(problem, np.arange(runs), np.array(seeds[:runs]), target=t).final

    return simulate
