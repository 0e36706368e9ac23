"""Algorithm 1 of the paper, and the classical variant, written once over a leading run axis.

This module is the one place the slot rules live. The :class:`~emogen.ga.engine.Engine` (a
participant, R = 1) and the vectorised simulation (:mod:`emogen.simulate.vectorised`, R runs)
both call :func:`next_generation` / :func:`classical_next_generation`; the random numbers come
from a :class:`~emogen.ga.draws.Draws` of per-run, per-generation generators, requested in the
order documented below (the stream, :mod:`emogen.ga.draws`).

The classical variant, for the paper's selection-pressure comparison (Section IV-C):
"Instead of the random parent selection exercised by default, … we only propagate the fittest
parents (closest to the target) by allowing them to cross-breed and mutate to produce two
children, replacing both parents in the next generation. Each pair of parents is allowed to
breed only once."

Our reading: everything but the parents' choice and the children's number stays as in
Algorithm 1, so that only the selection pressure differs —

* the selection is a *fitness ranking* (best first; the simulated observer ranks the whole
  population by cosine distance to the target); the best face is the elite and is kept in
  slot 1 (elitism, as in EmoGen);
* the bred slots 2..N − ``random_faces_count`` take children of the fittest pairs, formed in
  order of fitness — ranks (1,2), (1,3), (2,3), (1,4), (2,4), (3,4), … — each pair breeding
  once by uniform crossover into *two* complementary children (every gene of the one child
  from one parent, of the other from the other), each then mutated with m genes. The children
  replace their parents: no parent other than the elite survives into P_{g+1};
* if the ranking has too few faces to fill the bred slots with distinct pairs, the remaining
  slots are random faces R(x);
* the last ``random_faces_count`` slots are random faces R(x), as in EmoGen.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from emogen.errors import SelectionError, ShapeError
from emogen.ga.draws import Draws
from emogen.ga.genome import STATIC, Genome
from emogen.ga.operators import crossover, crossover_pair

ELITE = "elite"
MEAN_ALL = "mean_all"
MEAN_ELITE_OTHER = "mean_elite_other"
KEPT = "kept"
CROSSOVER_MUTATION = "crossover_mutation"
RANDOM = "random"


@dataclass(frozen=True)
class Offspring:
    """New populations of R runs, with where each face came from.

    genes : (R, N, K) float
    parents : (R, N, 2) int, indices into each run's *previous* population, -1 for none
      (``mean_all`` faces have (-1, -1): their parents are all of the generation's selections)
    operators : (N,) str, the operator that made each slot (the same in every run of a batch)
    """

    genes: np.ndarray
    parents: np.ndarray
    operators: np.ndarray


def _check(genes: np.ndarray, draws: Draws, genome: Genome) -> np.ndarray:
    genes = np.asarray(genes, dtype=np.float64)
    tail = () if genome.params is None else (len(genome.params),)
    if genes.ndim != 3 + len(tail) or genes.shape[3:] != tail:
        raise ShapeError(
            f"genes must have shape (n_runs, n_faces, n_genes{', ' if tail else ''}"
            f"{', '.join(map(str, tail))}); got {genes.shape}"
        )
    if draws.runs != genes.shape[0]:
        raise ShapeError(f"need draws for {genes.shape[0]} runs; got {draws.runs}")
    return genes


def _check_indices(name: str, index: np.ndarray, n: int) -> None:
    if index.size and (index.min() < 0 or index.max() >= n):
        raise SelectionError(f"{name} indices must be in [0, {n}); got {index.tolist()}")


def _check_distinct(name: str, index: np.ndarray) -> None:
    repeats = (np.diff(np.sort(index, axis=1), axis=1) == 0).any(axis=1)
    if repeats.any():
        run = int(np.flatnonzero(repeats)[0])
        raise SelectionError(f"{name} must not repeat a face; run {run} has {index[run].tolist()}")


def next_generation(
    genes: np.ndarray,
    elite: np.ndarray,
    others: np.ndarray,
    generation: int,
    *,
    draws: Draws,
    random_faces_count: int = 4,
    mutation_genes: int = 2,
    random_genes: int = 6,
    genome: Genome = STATIC,
) -> Offspring:
    """P_{g+1} of R runs from P_g and their selections [α_elite, p_g] = S(P_g) (Algorithm 1).

    genes : (R, N, K) float (R, N, K, 6 with a dynamic ``genome``, :mod:`emogen.ga.genome`),
    the populations P_g (``generation`` = g). elite : (R,) int, index of α_{g,elite} in each P_g;
    others : (R, |p_g|) int, indices of p_g (the same count in every run). ``random_faces_count``
    is the diversity boost (4 of 10), ``mutation_genes`` m (2), ``random_genes`` x (6). Slots
    are numbered fc = 1..N as in the paper.

    Our reading of Algorithm 1, line by line (S = |p_g| + 1, the number of selections):

    * ``while g <= G`` / ``S(P_g)``: the caller (the engine) shows P_g for g = 0..G and asks
      for a selection every time; this function is the loop body for one g < G. (At g = G the
      loop ends and α_{G,elite} is the result; no P_{G+1} is made.)
    * ``for fc_nr = 1..10``: the slots of P_{g+1}, fc = 1..N. The if/else-if chain is tried
      top to bottom for each slot; a slot whose condition fails falls through to the next
      branch. Slots fc > N − ``random_faces_count`` (7..10 by default) are always random: the
      text says four of ten faces are new random ones, and the garbled last branch
      (``α_new = R({i}_6)``) is the ``else`` of ``fc_nr < 7``.
    * ``if fc_nr = 1``: α_{g+1,1} = α_{g,elite} — elitism, the elite is copied unchanged.
    * ``else if fc_nr = 2 and S > 2``: α_{g+1,2} = A(all S selections). With S <= 2 slot 2
      falls through to the crossover branch.
    * ``else if fc_nr = 3 and g ∉ {1, 2}``: if S >= 2, α_{g+1,3} = A(α_elite, α_s) with α_s
      drawn uniformly from p_g; otherwise (only the elite selected) α_{g+1,3} = α_{g,3}, the
      current population's slot-3 face copied (operator ``kept``). In generations g = 1 and 2
      slot 3 falls through to crossover.
    * ``else if fc_nr < 7``: the pseudo-code writes α' = B(α_s, α_s'), α'' = M(α', {i}_2)
      and then stores α'; the text and the issue say crossover *and* mutation, so we store
      α''. α_s and α_s' are two *distinct* members of {α_elite} ∪ p_g, drawn uniformly
      without replacement within a pair and with replacement between pairs ("non-identical"
      is read as distinct population members). If only the elite is selected there is no
      pair: the child is a copy of the elite, then mutated.
    * ``α_new = R({i}_6)`` (the missing ``else``): the remaining slots are fresh random faces.

    Draw order (per run, fixed, so a run replays from its seed): slot by slot from fc = 1
    upwards — slot 3's partner (``integers(|p_g|, ())``), then for each crossover slot the pair
    (``pairs(S)``), the crossover mask and the mutation — and finally all random faces at once.
    """
    genes = _check(genes, draws, genome)
    r, n, k = genes.shape[:3]
    elite = np.asarray(elite, dtype=np.int64).reshape(r)
    others = np.asarray(others, dtype=np.int64).reshape(r, -1)
    selected = np.concatenate([elite[:, None], others], axis=1)
    _check_indices("selection", selected, n)
    _check_distinct("selections", selected)
    s, n_bred = selected.shape[1], n - random_faces_count
    runs = np.arange(r)
    out = np.zeros_like(genes)
    parents = np.full((r, n, 2), -1, dtype=np.int64)
    ops = [RANDOM] * n
    elite_genes = genes[runs, elite]
    for i in range(n_bred):
        slot = i + 1
        if slot == 1:
            out[:, i], parents[:, i, 0], ops[i] = elite_genes, elite, ELITE
        elif slot == 2 and s > 2:
            out[:, i], ops[i] = genome.average(genes[runs[:, None], selected]), MEAN_ALL
        elif slot == 3 and generation not in (1, 2):
            if s >= 2:
                other = others[runs, draws.integers(s - 1, ())]
                out[:, i] = genome.average(np.stack([elite_genes, genes[runs, other]], axis=1))
                parents[:, i, 0], parents[:, i, 1], ops[i] = elite, other, MEAN_ELITE_OTHER
            else:
                out[:, i], parents[:, i, 0], ops[i] = genes[:, i], i, KEPT
        else:
            out[:, i], parents[:, i] = _bred(genes, selected, mutation_genes, draws, genome)
            ops[i] = CROSSOVER_MUTATION
    out[:, n_bred:] = genome.random(n - n_bred, k, random_genes, draws)
    return Offspring(out, parents, np.array(ops))


def _bred(
    genes: np.ndarray, selected: np.ndarray, m: int, draws: Draws, genome: Genome
) -> tuple[np.ndarray, np.ndarray]:
    """A crossover slot for every run: (child (R, K), parents (R, 2)).

    Two distinct selected faces, crossed over and mutated; with only the elite selected there is
    no pair, and the child is the elite's copy, mutated.
    """
    runs = np.arange(len(genes))
    parents = np.full((len(genes), 2), -1, dtype=np.int64)
    if selected.shape[1] >= 2:
        pair = draws.pairs(selected.shape[1])
        a, b = selected[runs, pair[:, 0]], selected[runs, pair[:, 1]]
        child = crossover(genes[runs, a], genes[runs, b], draws)
        parents[:, 0], parents[:, 1] = a, b
    else:
        child = genes[runs, selected[:, 0]]
        parents[:, 0] = selected[:, 0]
    return genome.mutate(child[:, None], m, draws)[:, 0], parents


def ranked_pairs(n_ranked: int) -> Iterator[tuple[int, int]]:
    """Rank positions of the pairs in order of fitness: (0,1), (0,2), (1,2), (0,3), …"""
    for j in range(1, n_ranked):
        for i in range(j):
            yield i, j


def classical_next_generation(
    genes: np.ndarray,
    ranking: np.ndarray,
    *,
    draws: Draws,
    random_faces_count: int = 4,
    mutation_genes: int = 2,
    random_genes: int = 6,
    genome: Genome = STATIC,
) -> Offspring:
    """P_{g+1} of R runs from P_g and a fitness ranking of (some of) its faces, best first.

    genes : (R, N, K) float; ranking : (R, L) int, distinct indices into each P_g, best first
    (L >= 1, the same for every run). Draw order: for each pair its crossover mask and the two
    children's mutations, then the random faces.
    """
    genes = _check(genes, draws, genome)
    r, n, k = genes.shape[:3]
    ranking = np.asarray(ranking, dtype=np.int64).reshape(r, -1)
    if ranking.shape[1] == 0:
        raise SelectionError(f"ranking must hold indices in [0, {n}); got none")
    _check_indices("ranking", ranking, n)
    _check_distinct("ranking", ranking)
    n_bred = n - random_faces_count
    runs = np.arange(r)
    out = np.zeros_like(genes)
    parents = np.full((r, n, 2), -1, dtype=np.int64)
    ops = [RANDOM] * n
    out[:, 0], parents[:, 0, 0], ops[0] = genes[runs, ranking[:, 0]], ranking[:, 0], ELITE
    slot = 1
    pairs = ranked_pairs(ranking.shape[1])
    while slot < n_bred:
        pair = next(pairs, None)
        if pair is None:
            break
        a, b = ranking[:, pair[0]], ranking[:, pair[1]]
        children = genome.mutate(
            crossover_pair(genes[runs, a], genes[runs, b], draws), mutation_genes, draws
        )
        for c in range(min(2, n_bred - slot)):
            out[:, slot], parents[:, slot, 0], parents[:, slot, 1] = children[:, c], a, b
            ops[slot] = CROSSOVER_MUTATION
            slot += 1
    out[:, slot:] = genome.random(n - slot, k, random_genes, draws)
    return Offspring(out, parents, np.array(ops))
