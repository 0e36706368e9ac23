"""Many simulated runs advanced together as arrays, and the one-run reference they equal.

:func:`simulate_runs` keeps R runs as one genes array ``(R, N, K)``: each generation it expands
them to weights, applies the corrections (if on), measures every face against the target,
lets the observer choose (vectorised; per-run Gumbel draws for choice noise) and breeds the
next generation with :func:`~emogen.ga.batch.next_generation_batch`. Run r draws from the
generators the engine would use for its seed — :func:`~emogen.rng.generation_rng` (seed, 0, g)
for the GA, :func:`~emogen.rng.observer_rng` for the choice noise — so its numbers equal those
of :func:`engine_run`, which drives the :class:`~emogen.ga.engine.Engine` one run at a time
through ``ask()``/``tell()`` like a participant. Results depend on each run's seed only, never
on how runs are grouped into chunks or spread over workers.

That holds with corrections on too: a face's correction depends on that face alone (the
collision detector and the blending it reads work face by face in a fixed order,
:mod:`emogen.correct.blend`), so correcting a run's faces with the runner's whole batch or the
engine's 10 at a time gives the same weights, bit for bit.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from emogen.config import SimulationConfig
from emogen.correct.faces import correct_faces, model_correctives
from emogen.errors import ConfigError
from emogen.ga.batch import classical_next_generation_batch, next_generation_batch
from emogen.ga.engine import Engine
from emogen.ga.init import first_generation
from emogen.metrics import cosine_distance
from emogen.model.rig import Rig
from emogen.rng import generation_rng, observer_rng
from emogen.simulate.observer import Metric, Observer, choice_order, selection_count

if TYPE_CHECKING:
    from emogen.model.face import FaceModel


@dataclass(frozen=True, eq=False)
class Correction:
    """The model's corrections applied to every shown face (:func:`emogen.correct.correct_faces`).

    ``correction(weights (B, S))`` → the corrected full weight vectors (B, S + C): the
    effective shape weights (companions capped), then every corrective weight (combinational
    products, collision weights of eq. 5) in ``names[S:]`` order. The corrected face is the
    blend of those weights (gaze on the shapes), so the metrics see exactly what a participant
    sees. Identical faces of a batch are corrected once. The GA keeps evolving the uncorrected
    genes, as with a participant, who only ever sees corrected faces.
    """

    model: FaceModel

    @property
    def names(self) -> tuple[str, ...]:
        """Column names of the corrected vectors: the shapes, then the correctives."""
        return tuple(self.model.shape_names) + tuple(model_correctives(self.model).names)

    @property
    def deltas(self) -> np.ndarray:
        """(C, V, 3) the correctives' vertex offsets, in ``names[S:]`` order."""
        c = model_correctives(self.model)
        return np.concatenate([c.combinational_deltas, c.collision_deltas])

    def __call__(self, weights: np.ndarray) -> np.ndarray:
        w = np.asarray(weights, dtype=np.float64)
        unique, inverse = np.unique(w, axis=0, return_inverse=True)
        result = correct_faces(self.model, unique)
        corrected = np.concatenate([result.weights, result.correctives], axis=1)
        return np.asarray(corrected[inverse.reshape(-1)], dtype=np.float64)


def make_correction(model: FaceModel | None) -> Correction:
    """The corrections for ``correct = true`` (they need the face model, not only its rig)."""
    if model is None:
        raise ConfigError("correct = true needs the face model, not only its rig")
    from emogen.model.face import FaceModel

    if not isinstance(model, FaceModel):
        raise ConfigError(
            "correct = true needs a FaceModel (its geometry gives the correctives, "
            f"emogen.correct); got {type(model).__name__}"
        )
    return Correction(model)


@dataclass(frozen=True, eq=False)
class Problem:
    """Everything needed to simulate runs of one configuration (picklable, for workers).

    target : the target's shown full weights, (n_shapes,) or, corrected, (n_shapes + C,) —
    see :attr:`columns`; fixed_sets : (n_sets, N, K) for fixed initialisation.
    """

    config: SimulationConfig
    rig: Rig
    target: np.ndarray
    metric: Metric
    fixed_sets: np.ndarray | None = None
    correction: Correction | None = None
    all_weights: bool = False
    target_source: dict[str, Any] = field(default_factory=dict)

    @property
    def n_generations(self) -> int:
        """Generations shown: G + 1."""
        return self.config.ga.generations + 1

    @property
    def columns(self) -> tuple[str, ...]:
        """Names of the shown full weight vectors' columns (shapes, then any correctives)."""
        return self.rig.shape_names if self.correction is None else self.correction.names


@dataclass(frozen=True)
class RunArrays:
    """What R runs showed and chose, generation by generation.

    runs, seeds : (R,) int; distance : (R, G+1, N) the selection metric to the target; error :
    (R, G+1, N) CD to the target (the paper's convergence measure); rank : (R, G+1, N) int,
    0 for the elite, 1… for the other selections in choice order, −1 unselected; operators :
    (R, G+1, N) str; weights : (R, G+1, N, S) shown full weights, or None; fixed_options : (R,)
    the fixed set used (−1 for protocol initialisation).
    """

    runs: np.ndarray
    seeds: np.ndarray
    distance: np.ndarray
    error: np.ndarray
    rank: np.ndarray
    operators: np.ndarray
    weights: np.ndarray | None
    fixed_options: np.ndarray

    @staticmethod
    def concatenate(parts: list[RunArrays]) -> RunArrays:
        """Parts of one simulation, in run order."""
        parts = sorted(parts, key=lambda p: int(p.runs[0]) if len(p.runs) else 0)

        def cat(name: str) -> np.ndarray:
            return np.concatenate([getattr(p, name) for p in parts])

        weights = [p.weights for p in parts]
        return RunArrays(
            runs=cat("runs"),
            seeds=cat("seeds"),
            distance=cat("distance"),
            error=cat("error"),
            rank=cat("rank"),
            operators=cat("operators"),
            weights=None if any(w is None for w in weights) else cat("weights"),
            fixed_options=cat("fixed_options"),
        )


def _initial(problem: Problem, seed: int) -> tuple[np.ndarray, np.ndarray, int]:
    """Generation 0 of one run, as the engine makes it."""
    return first_generation(
        problem.config.ga, problem.rig, problem.fixed_sets, rng=generation_rng(seed, 0, 0)
    )


def _measure(problem: Problem, shown: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(metric distances, CD errors) of faces (…, S) to the target."""
    flat = shown.reshape(-1, shown.shape[-1])
    error = cosine_distance(flat, problem.target)
    distance = error if problem.metric.name == "cd" else problem.metric(flat, problem.target)
    return distance.reshape(shown.shape[:-1]), error.reshape(shown.shape[:-1])


def simulate_runs(
    problem: Problem,
    runs: np.ndarray,
    seeds: np.ndarray,
    *,
    on_generation: Callable[[int], None] | None = None,
) -> RunArrays:
    """Simulate runs (their numbers and seeds, (R,) each) together; ``on_generation(R)`` is
    called after every generation (for a progress bar)."""
    cfg, rig = problem.config, problem.rig
    ga = cfg.ga
    seeds = np.asarray(seeds, dtype=np.int64)
    r_count, n_gen = len(seeds), problem.n_generations
    first = [_initial(problem, int(s)) for s in seeds]
    genes = np.stack([f[0] for f in first])
    operators = np.stack([f[1] for f in first])
    n = genes.shape[1]
    expansion = rig.expansion_matrix(ga.eye_motion)
    obs = [observer_rng(int(s), 0) for s in seeds] if cfg.noise_temperature > 0 else []
    distance = np.empty((r_count, n_gen, n))
    error = np.empty((r_count, n_gen, n))
    rank = np.full((r_count, n_gen, n), -1, dtype=np.int16)
    ops = np.empty((r_count, n_gen, n), dtype="<U32")
    width = len(problem.columns)
    shown_all = np.empty((r_count, n_gen, n, width)) if problem.all_weights else None
    rows = np.arange(r_count)[:, None]
    params = {
        "random_faces_count": ga.random_faces,
        "mutation_genes": ga.mutation_genes,
        "random_genes": ga.random_genes,
    }
    for g in range(n_gen):
        shown = genes @ expansion
        if problem.correction is not None:
            r_count, n, n_shapes = shown.shape
            shown = problem.correction(shown.reshape(-1, n_shapes)).reshape(r_count, n, -1)
        distance[:, g], error[:, g] = _measure(problem, shown)
        ops[:, g] = operators
        if shown_all is not None:
            shown_all[:, g] = shown
        gumbel = np.stack([o.gumbel(size=n) for o in obs]) if obs else None
        order = choice_order(distance[:, g], cfg.noise_temperature, gumbel)
        count = selection_count(cfg, g, n)
        rank[rows, g, order[:, :count]] = np.arange(count, dtype=np.int16)
        if g < n_gen - 1:
            rngs = [generation_rng(int(s), 0, g + 1) for s in seeds]
            if ga.variant == "classical":
                off = classical_next_generation_batch(genes, order[:, :count], rngs=rngs, **params)
            else:
                off = next_generation_batch(
                    genes, order[:, 0], order[:, 1:count], g, rngs=rngs, **params
                )
            genes = off.genes
            operators = np.broadcast_to(off.operators, (r_count, n))
        if on_generation is not None:
            on_generation(r_count)
    return RunArrays(
        np.asarray(runs, dtype=np.int64),
        seeds,
        distance,
        error,
        rank,
        ops,
        shown_all,
        np.array([f[2] for f in first], dtype=np.int64),
    )


def engine_run(problem: Problem, run: int, seed: int) -> RunArrays:
    """One run through the engine's ``ask()``/``tell()``, as a participant drives it: the
    reference :func:`simulate_runs` reproduces (same seed, same numbers)."""
    cfg = problem.config
    engine = Engine(cfg.ga, problem.rig, seed)
    temperature = cfg.noise_temperature
    observer = Observer(
        problem.metric,
        problem.target,
        cfg.selections_at,
        final=cfg.ga.generations,
        ranking=cfg.ga.variant == "classical",
        temperature=temperature,
        rng=observer_rng(seed, 0) if temperature > 0 else None,
    )
    n_gen, n = problem.n_generations, cfg.ga.population_size
    distance, error = np.empty((1, n_gen, n)), np.empty((1, n_gen, n))
    rank = np.full((1, n_gen, n), -1, dtype=np.int16)
    ops = np.empty((1, n_gen, n), dtype="<U32")
    shown_all = np.empty((1, n_gen, n, len(problem.columns)))
    while not engine.done:
        pop = engine.ask()
        g = pop.generation
        shown = np.asarray(pop.weights)
        if problem.correction is not None:
            shown = problem.correction(shown)
        elite, others, _ = observer.choose(pop, shown)
        distance[0, g], error[0, g] = _measure(problem, shown)
        where = {int(i): k for k, i in enumerate(pop.ids)}
        for k, face in enumerate([elite, *others]):
            rank[0, g, where[face]] = k
        ops[0, g], shown_all[0, g] = pop.operators, shown
        engine.tell(elite, others)
    options = engine.fixed_options[0] if engine.fixed_options else -1
    return RunArrays(
        np.array([run]),
        np.array([seed], dtype=np.int64),
        distance,
        error,
        rank,
        ops,
        shown_all if problem.all_weights else None,
        np.array([options], dtype=np.int64),
    )
