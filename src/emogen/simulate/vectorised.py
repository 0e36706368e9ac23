"""Many simulated runs advanced together as arrays, and the one-run reference they equal.

:func:`simulate_runs` keeps R runs as one genes array ``(R, N, K)``: each generation it expands
them to weights, applies the corrections (if on), measures every face against the target,
lets the observer choose (vectorised; per-run Gumbel draws for choice noise) and breeds the
next generation with :func:`~emogen.ga.algorithm.next_generation` — the same function, over
the same run axis, that the engine calls with one run. Run r draws from the generators the
engine would use for its seed — :func:`~emogen.ga.draws.generation_draws` (seed, 0, g) for
the GA, :func:`~emogen.rng.observer_rng` for the choice noise — so its numbers equal those
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
from typing import Any

import numpy as np

from emogen.ga.algorithm import classical_next_generation, next_generation
from emogen.ga.draws import CURRENT_STREAM, block_size, generation_draws
from emogen.ga.engine import Engine
from emogen.ga.init import first_generations
from emogen.metrics import cosine_distance
from emogen.rng import generation_rngs, observer_rng, observer_rngs
from emogen.simulate.observer import Observer, choice_order, selection_count
from emogen.simulate.problem import Problem, RunArrays


def _measure(problem: Problem, shown: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(metric distances, CD errors) of faces (R, N, S) to the target: (S,), or (R, S) one
    per run (simulated participants, each their own)."""
    flat = shown.reshape(-1, shown.shape[-1])
    target = problem.target
    if target.ndim == 2:  # one target per run (R, S): repeat it for the run's faces
        target = np.repeat(target, shown.shape[-2], axis=0)
    error = cosine_distance(flat, target)
    distance = error if problem.metric.name == "cd" else problem.metric(flat, target)
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
    rngs = generation_rngs(seeds, 0, 0)
    genes, operators, options = first_generations(  # generation 0 of each run, as the engine's
        ga, rig, problem.fixed_sets, rngs=rngs
    )
    genome = problem.genome
    if problem.dynamic is not None:  # the timing after the static draws, as the engine's
        genes = np.stack([genome.initial(genes[r], rng) for r, rng in enumerate(rngs)])
    n = genes.shape[1]
    expansion = rig.expansion_matrix(ga.eye_motion)
    obs = observer_rngs(seeds, 0) if cfg.noise_temperature > 0 else []
    distance = np.empty((r_count, n_gen, n))
    error = np.empty((r_count, n_gen, n))
    rank = np.full((r_count, n_gen, n), -1, dtype=np.int16)
    parts = None if problem.dynamic is None else (np.empty_like(error), np.empty_like(error))
    ops = [operators]  # (R, N) for generation 0, then each generation's (N,), the same for all runs
    width = len(problem.columns)
    shown_all = np.empty((r_count, n_gen, n, width)) if problem.all_weights else None
    rows = np.arange(r_count)[:, None]
    params: dict[str, Any] = {
        "random_faces_count": ga.random_faces,
        "mutation_genes": ga.mutation_genes,
        "random_genes": ga.random_genes,
        "genome": genome,
    }
    k = genes.shape[2]
    block = block_size(n, k, ga.mutation_genes, ga.random_genes)
    block += n * genome.extra_draws(k, ga.mutation_genes)
    for g in range(n_gen):
        shown = genome.amplitude(genes) @ expansion  # a dynamic face's: its peak profile
        if problem.correction is not None:
            r_count, n, n_shapes = shown.shape
            shown = problem.correction(shown.reshape(-1, n_shapes)).reshape(r_count, n, -1)
        if problem.dynamic is not None and parts is not None:
            distance[:, g], parts[0][:, g], parts[1][:, g] = problem.dynamic.measure(genes)
            error[:, g] = distance[:, g]
        else:
            distance[:, g], error[:, g] = _measure(problem, shown)
        if shown_all is not None:
            shown_all[:, g] = shown
        gumbel = np.stack([o.gumbel(size=n) for o in obs]) if obs else None
        order = choice_order(distance[:, g], cfg.noise_temperature, gumbel)
        count = selection_count(cfg, g, n)
        rank[rows, g, order[:, :count]] = np.arange(count, dtype=np.int16)
        if g < n_gen - 1:
            draws = generation_draws(seeds, 0, g + 1, stream=CURRENT_STREAM, block=block)
            if ga.variant == "classical":
                off = classical_next_generation(genes, order[:, :count], draws=draws, **params)
            else:
                off = next_generation(
                    genes, order[:, 0], order[:, 1:count], g, draws=draws, **params
                )
            genes = off.genes
            ops.append(off.operators)
        if on_generation is not None:
            on_generation(r_count)
    return RunArrays(
        np.asarray(runs, dtype=np.int64),
        seeds,
        distance,
        error,
        rank,
        _operators(ops, r_count),
        shown_all,
        options,
        *(parts or (None, None)),
    )


def _operators(ops: list[np.ndarray], r_count: int) -> np.ndarray:
    """(R, G+1, N) operator names from generation 0's (R, N) and later generations' (N,),
    written once at the end in the names' own width (a fixed wide string type per generation
    cost 3 ms of a 500-run simulation's ~100)."""
    out = np.empty((r_count, len(ops), ops[0].shape[-1]), dtype=np.result_type(*ops))
    out[:, 0] = ops[0]
    if len(ops) > 1:
        out[:, 1:] = np.stack(ops[1:])
    return out


def engine_run(problem: Problem, run: int, seed: int) -> RunArrays:
    """One run through the engine's ``ask()``/``tell()``, as a participant drives it: the
    reference :func:`simulate_runs` reproduces (same seed, same numbers)."""
    cfg = problem.config
    engine = Engine(cfg.ga, problem.rig, seed, genome=problem.genome)
    temperature = cfg.noise_temperature
    view = problem.dynamic
    observer = Observer(
        problem.metric if view is None else view.distance,
        problem.target if view is None else view.target,
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
    parts = None if view is None else (np.empty_like(error), np.empty_like(error))
    while not engine.done:
        pop = engine.ask()
        g = pop.generation
        shown = np.asarray(pop.weights)
        if problem.correction is not None:
            shown = problem.correction(shown)
        elite, others, _ = observer.choose(pop, shown if view is None else pop.genes)
        if view is not None and parts is not None:
            distance[0, g], parts[0][0, g], parts[1][0, g] = view.measure(pop.genes)
            error[0, g] = distance[0, g]
        else:
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
        *(parts or (None, None)),
    )
