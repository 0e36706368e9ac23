"""The classical GA variant, for the paper's selection-pressure comparison (Section IV-C).

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

import numpy as np

from emogen.errors import SelectionError
from emogen.ga.operators import check_genes, crossover_pair, mutate, random_faces
from emogen.ga.step import CROSSOVER_MUTATION, ELITE, RANDOM, Offspring


def ranked_pairs(n_ranked: int) -> Iterator[tuple[int, int]]:
    """Rank positions of the pairs in order of fitness: (0,1), (0,2), (1,2), (0,3), …"""
    for j in range(1, n_ranked):
        for i in range(j):
            yield i, j


def classical_next_generation(
    genes: np.ndarray,
    ranking: np.ndarray,
    *,
    random_faces_count: int = 4,
    mutation_genes: int = 2,
    random_genes: int = 6,
    rng: np.random.Generator,
) -> Offspring:
    """P_{g+1} from P_g and a fitness ranking of (some of) its faces, best first.

    genes : (N, K) float; ranking : (R,) int, distinct indices into P_g, best first (R >= 1).
    Draw order: for each pair its crossover mask and the two children's mutations, then the
    random faces.
    """
    genes = check_genes(genes)
    n, k = genes.shape
    ranking = np.asarray(ranking, dtype=np.int64).reshape(-1)
    if len(ranking) == 0 or ranking.min() < 0 or ranking.max() >= n:
        raise SelectionError(f"ranking must hold indices in [0, {n}); got {ranking.tolist()}")
    if len(set(ranking.tolist())) != len(ranking):
        raise SelectionError(f"ranking must not repeat a face; got {ranking.tolist()}")
    n_bred = n - random_faces_count
    out = np.zeros_like(genes)
    parents = np.full((n, 2), -1, dtype=np.int64)
    ops = np.empty(n, dtype=object)
    out[0], parents[0, 0], ops[0] = genes[ranking[0]], ranking[0], ELITE

    slot = 1
    pairs = ranked_pairs(len(ranking))
    while slot < n_bred:
        pair = next(pairs, None)
        if pair is None:
            break
        a, b = ranking[pair[0]], ranking[pair[1]]
        children = np.concatenate(crossover_pair(genes[[a]], genes[[b]], rng=rng))
        children = mutate(children, mutation_genes, rng=rng)
        for child in children[: n_bred - slot]:
            out[slot], parents[slot], ops[slot] = child, (a, b), CROSSOVER_MUTATION
            slot += 1
    out[slot:] = random_faces(n - slot, k, random_genes, rng=rng)
    ops[slot:] = RANDOM
    return Offspring(out, parents, ops.astype(str))
