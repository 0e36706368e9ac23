"""One generation of EmoGen's GA: Algorithm 1 of the paper, as a pure function."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from emogen.errors import SelectionError
from emogen.ga.operators import average, check_genes, crossover, mutate, random_faces

ELITE = "elite"
MEAN_ALL = "mean_all"
MEAN_ELITE_OTHER = "mean_elite_other"
KEPT = "kept"
CROSSOVER_MUTATION = "crossover_mutation"
RANDOM = "random"


@dataclass(frozen=True)
class Offspring:
    """A new population, with where each face came from.

    genes : (n_faces, n_genes) float
    parents : (n_faces, 2) int, indices into the *previous* population, -1 for none
      (``mean_all`` faces have (-1, -1): their parents are all of the generation's selections)
    operators : (n_faces,) str, the operator that made each face
    """

    genes: np.ndarray
    parents: np.ndarray
    operators: np.ndarray


def next_generation(
    genes: np.ndarray,
    elite: int,
    others: np.ndarray,
    generation: int,
    *,
    random_faces_count: int = 4,
    mutation_genes: int = 2,
    random_genes: int = 6,
    rng: np.random.Generator,
) -> Offspring:
    """P_{g+1} from P_g and its selection [α_elite, p_g] = S(P_g), following Algorithm 1.

    genes : (N, K) float, the current population P_g (generation ``generation`` = g).
    elite : index of α_{g,elite} in P_g; others : (|p_g|,) int, indices of p_g.
    ``random_faces_count`` is the diversity boost (4 of 10), ``mutation_genes`` m (2),
    ``random_genes`` x (6). Slots are numbered fc = 1..N as in the paper.

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

    Draw order (fixed, so a run replays from its seed): slot by slot from fc = 1 upwards —
    slot 3's partner index, then for each crossover slot the pair, the crossover mask and the
    mutation — and finally all random faces at once.
    """
    genes = check_genes(genes)
    n, k = genes.shape
    others = np.asarray(others, dtype=np.int64).reshape(-1)
    selected = np.concatenate([[int(elite)], others])
    if selected.min() < 0 or selected.max() >= n:
        raise SelectionError(f"selection indices must be in [0, {n}); got {selected.tolist()}")
    s = len(selected)
    n_bred = n - random_faces_count
    out = np.zeros_like(genes)
    parents = np.full((n, 2), -1, dtype=np.int64)
    ops = np.empty(n, dtype=object)

    for slot in range(1, n_bred + 1):
        i = slot - 1
        if slot == 1:
            out[i], parents[i, 0], ops[i] = genes[elite], elite, ELITE
        elif slot == 2 and s > 2:
            out[i], ops[i] = average(genes[selected]), MEAN_ALL
        elif slot == 3 and generation not in (1, 2):
            if s >= 2:
                other = int(others[rng.integers(len(others))])
                out[i] = average(genes[[elite, other]])
                parents[i], ops[i] = (elite, other), MEAN_ELITE_OTHER
            else:
                out[i], parents[i, 0], ops[i] = genes[i], i, KEPT
        else:
            if s >= 2:
                a, b = selected[rng.choice(s, size=2, replace=False)]
                child = crossover(genes[[a]], genes[[b]], rng=rng)
                parents[i] = (a, b)
            else:
                child = genes[[elite]].copy()
                parents[i, 0] = elite
            out[i] = mutate(child, mutation_genes, rng=rng)[0]
            ops[i] = CROSSOVER_MUTATION
    out[n_bred:] = random_faces(n - n_bred, k, random_genes, rng=rng)
    ops[n_bred:] = RANDOM
    return Offspring(out, parents, ops.astype(str))
